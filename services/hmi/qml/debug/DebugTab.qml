import QtQuick
import QtQuick.Controls
import QtQuick.Layouts
import OpenVcu.Models
import OpenVcu.Hmi

// Log (filter by service and level, export), FSM transitions, active faults with reset,
// the J1939 networks (J1939Page), service health with restart, system figures,
// reboot/shutdown after confirmation, and Record (vcu record into the data folder; Analyse
// hands the logs to the Trace tab).
ColumnLayout {
    id: debugTab
    property var health
    property var fsm
    /// Record's Analyse: the window opens `logs` in the Trace tab.
    signal analyse(var logs)
    spacing: 4
    LogModel { id: logModel }
    FileBrowserModel { id: exportFolder }  // only its data folder: exports go there
    FaultModel { id: faults }
    SystemActions { id: actions }

    TabBar {
        id: pages
        Layout.fillWidth: true
        Repeater {
            // a fixed list: a model rebuilt on each new fault count recreated the buttons and
            // sent the operator back to the first page
            model: ["Log", "Transitions", "Faults", "Services", "Record", "J1939"]
            TabButton {
                text: modelData === "Faults" ? "Faults (" + faults.activeCount + ")" : modelData
                font.pixelSize: Theme.fontSmall; implicitHeight: 40
            }
        }
    }
    // pages as plain Items (see CanDataTab.qml: nested StackLayouts crashed in Qt 6.4.2)
    Item {
        Layout.fillWidth: true
        Layout.fillHeight: true

        ColumnLayout {
            anchors.fill: parent
            visible: pages.currentIndex === 0
            RowLayout {
                ComboBox {
                    id: serviceBox
                    model: [""].concat(logModel.services)
                    displayText: currentText === "" ? "all services" : currentText
                    onCurrentTextChanged: logModel.serviceFilter = currentText
                }
                ComboBox {
                    model: ["trace", "debug", "info", "warning", "error", "critical"]
                    currentIndex: logModel.minimumLevel
                    onCurrentIndexChanged: logModel.minimumLevel = currentIndex
                }
                TouchButton {
                    text: "Export"
                    onClicked: {
                        const path = exportFolder.newFilePath("vcu-hmi-log", "txt")
                        const error = logModel.exportTo(path)
                        exportResult.text = error === "" ? "saved " + path : error
                    }
                }
                Text { id: exportResult; color: Theme.textDim; font.pixelSize: Theme.fontSmall; Layout.fillWidth: true; elide: Text.ElideLeft }
            }
            ListView {
                id: logView
                Layout.fillWidth: true
                Layout.fillHeight: true
                clip: true
                model: logModel
                onCountChanged: if (atYEnd || count < 30) positionViewAtEnd()
                delegate: Text {
                    width: logView.width
                    text: time + " " + levelName + " " + service + ": " + model.text
                    color: level >= 4 ? Theme.bad : level === 3 ? Theme.warn : Theme.text
                    font.pixelSize: 12
                    elide: Text.ElideRight
                }
                Text { anchors.centerIn: parent; visible: logView.count === 0; text: "no log records yet (" + Theme.statusText(logModel.status) + ")"; color: Theme.textDim }
            }
        }

        ListView {
            id: transitionView
            anchors.fill: parent
            visible: pages.currentIndex === 1
            clip: true
            model: debugTab.fsm
            delegate: Text {
                width: transitionView.width
                text: time + "  " + fromState + " → " + toState + "   " + cause
                color: Theme.text; font.pixelSize: Theme.fontSmall; elide: Text.ElideRight
            }
            Text { anchors.centerIn: parent; visible: transitionView.count === 0; text: "no transition since the HMI started; state " + (debugTab.fsm ? debugTab.fsm.stateName : "--"); color: Theme.textDim }
        }

        ColumnLayout {
            anchors.fill: parent
            visible: pages.currentIndex === 2
            RowLayout {
                TouchButton { text: "Reset faults"; tint: Theme.warn; onClicked: faults.resetFaults() }
                Text { text: faults.lastResult; color: Theme.textDim; font.pixelSize: Theme.fontSmall; Layout.fillWidth: true; elide: Text.ElideRight }
            }
            ListView {
                id: faultView
                Layout.fillWidth: true
                Layout.fillHeight: true
                clip: true
                model: faults
                delegate: Text {
                    width: faultView.width
                    text: time + "  " + name + " (" + source + "): " + model.text
                    color: severity >= 2 ? Theme.bad : Theme.warn; font.pixelSize: Theme.fontSmall; elide: Text.ElideRight
                }
                Text { anchors.centerIn: parent; visible: faultView.count === 0; text: "no active fault"; color: Theme.good }
            }
        }

        ColumnLayout {
            anchors.fill: parent
            visible: pages.currentIndex === 3
            Text { text: debugTab.health ? debugTab.health.systemText : ""; color: Theme.textDim; font.pixelSize: Theme.fontSmall }
            ListView {
                id: services
                Layout.fillWidth: true
                Layout.fillHeight: true
                clip: true
                model: debugTab.health
                delegate: Rectangle {
                    width: services.width
                    height: 44
                    color: index % 2 ? Theme.panel : Theme.background
                    RowLayout {
                        anchors.fill: parent
                        anchors.margins: 4
                        StatusDot { status: connection }
                        Text { text: name; color: Theme.text; font.pixelSize: Theme.fontSmall; Layout.preferredWidth: 110 }
                        Text {
                            text: "pid " + pid + "  up " + uptime + "  restarts " + restarts + "  beat " + beatAge + "  CPU " + cpu + " %  RSS " + rss + " MB  " + statusText
                            color: Theme.textDim; font.pixelSize: 12; Layout.fillWidth: true; elide: Text.ElideRight
                        }
                        TouchButton { text: "Restart"; implicitHeight: 36; onClicked: { confirm.action = () => actions.restartService(name); confirm.question = "Restart " + name + "?"; confirm.open() } }
                    }
                }
            }
            RowLayout {
                TouchButton { text: "Reboot"; tint: Theme.bad; onClicked: { confirm.action = () => actions.power("reboot"); confirm.question = "Reboot the VCU?"; confirm.open() } }
                TouchButton { text: "Shut down"; tint: Theme.bad; onClicked: { confirm.action = () => actions.power("poweroff"); confirm.question = "Shut the VCU down?"; confirm.open() } }
                Text { text: actions.lastResult; color: Theme.textDim; font.pixelSize: Theme.fontSmall; Layout.fillWidth: true; elide: Text.ElideRight }
            }
        }

        RecordPage {
            anchors.fill: parent
            visible: pages.currentIndex === 4
            onAnalyse: (logs) => debugTab.analyse(logs)
        }

        J1939Page {
            anchors.fill: parent
            visible: pages.currentIndex === 5
        }
    }

    Dialog {
        id: confirm
        property var action
        property alias question: questionText.text
        anchors.centerIn: Overlay.overlay
        modal: true
        title: "Confirm"
        standardButtons: Dialog.Yes | Dialog.No
        Text { id: questionText; color: Theme.text; font.pixelSize: Theme.font }
        onAccepted: if (action) action()
    }
}
