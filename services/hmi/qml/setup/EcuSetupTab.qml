import QtQuick
import QtQuick.Controls
import QtQuick.Layouts
import OpenVcu.Models
import OpenVcu.Hmi

// The transmit schedule: message, signal, cycle, on/off, J1939-76 pair and delta, value,
// override. Cycle and on/off are what vcu-can-tx runs (its heartbeat); until it has reported,
// the DBC's cycle shows in grey with "DBC". Tap the cycle, "on"/"off", the value (the
// schedule's value: ScheduleDefault) or "set" under Override to change it; "Add message"
// picks any DBC message and a cycle (ScheduleAdd) and its signals become rows. Each change is
// a checked, acknowledged command to the running stack (no restart). Overrides are marked
// and clearable; added messages are marked "+".
ColumnLayout {
    spacing: 4
    ScheduleModel { id: schedule }
    Keypad { id: keypad; objectName: "setupKeypad"; property var apply; onAccepted: (text) => { const refused = apply(text); if (refused !== "") message.text = refused } }

    Row {
        Layout.fillWidth: true
        Repeater {
            model: [["Message", 0.22], ["Signal", 0.22], ["Cycle", 0.11], ["Sent", 0.07], ["SHM / Δ", 0.12], ["Value", 0.13], ["Override", 0.13]]
            Text { text: modelData[0]; color: Theme.textDim; font.pixelSize: Theme.fontSmall; width: scheduleList.width * modelData[1] }
        }
    }
    ListView {
        id: scheduleList
        Layout.fillWidth: true
        Layout.fillHeight: true
        clip: true
        model: schedule
        delegate: Rectangle {
            width: scheduleList.width
            height: 40
            color: overridden ? Qt.darker(Theme.warn, 2.5) : (index % 2 ? Theme.panel : Theme.background)
            Row {
                anchors.fill: parent
                anchors.leftMargin: 4
                Text { width: scheduleList.width * 0.22; text: (added ? "+ " : "") + message; color: added ? Theme.accent : Theme.text; font.pixelSize: Theme.fontSmall; elide: Text.ElideRight; anchors.verticalCenter: parent.verticalCenter }
                Text { width: scheduleList.width * 0.22; text: signal; color: Theme.text; font.pixelSize: Theme.fontSmall; elide: Text.ElideRight; anchors.verticalCenter: parent.verticalCenter }
                Text {
                    width: scheduleList.width * 0.11; text: (cycleMs > 0 ? cycleMs + " ms" : "-") + (live ? "" : " DBC"); color: live ? Theme.accent : Theme.textDim; font.pixelSize: Theme.fontSmall
                    anchors.verticalCenter: parent.verticalCenter
                    MouseArea {
                        anchors.fill: parent
                        onClicked: { keypad.apply = (t) => schedule.setCycle(index, t); keypad.show("cycle of " + message + " (ms)", cycleMs) }
                    }
                }
                Text {
                    width: scheduleList.width * 0.07; text: enabled ? "on" : "off"; color: enabled ? Theme.good : Theme.bad; font.pixelSize: Theme.fontSmall; font.bold: !enabled
                    anchors.verticalCenter: parent.verticalCenter
                    MouseArea { anchors.fill: parent; onClicked: message.text = schedule.setEnabled(index, !enabled) }
                }
                Text { width: scheduleList.width * 0.12; text: shmPair ? "pair " + deltaUs + " µs" : "-"; color: Theme.textDim; font.pixelSize: Theme.fontSmall; anchors.verticalCenter: parent.verticalCenter }
                Text {
                    width: scheduleList.width * 0.13; text: valueText; color: Theme.accent; font.pixelSize: Theme.fontSmall; elide: Text.ElideRight
                    anchors.verticalCenter: parent.verticalCenter
                    MouseArea {
                        anchors.fill: parent
                        onClicked: { keypad.apply = (t) => schedule.setDefault(index, t); keypad.show("schedule value of " + signal + " (" + range + ")", "") }
                    }
                }
                Row {
                    width: scheduleList.width * 0.13
                    anchors.verticalCenter: parent.verticalCenter
                    spacing: 4
                    Text {
                        text: overridden ? "OVR " + overrideText : "set"
                        color: overridden ? Theme.warn : Theme.accent; font.pixelSize: Theme.fontSmall; font.bold: overridden
                        anchors.verticalCenter: parent.verticalCenter
                        MouseArea {
                            anchors.fill: parent
                            onClicked: { keypad.apply = (t) => schedule.setOverride(index, t); keypad.show("override " + signal + " (" + range + ")", "") }
                        }
                    }
                    TouchButton { visible: overridden; text: "✕"; implicitWidth: 40; implicitHeight: 34; onClicked: message.text = schedule.clearOverride(index) }
                }
            }
        }
    }
    Text { id: message; color: Theme.bad; font.pixelSize: Theme.fontSmall; visible: text !== ""; Layout.fillWidth: true; elide: Text.ElideRight }
    RowLayout {
        TouchButton {
            objectName: "addMessageButton"
            text: "Add message…"
            onClicked: { addPopup.filter = ""; addPopup.open() }
        }
        StatusDot { status: schedule.status }
        Text { text: schedule.lastResult !== "" ? schedule.lastResult : Theme.statusText(schedule.status) + " " + schedule.errorString
               color: schedule.lastResult.indexOf("refused") >= 0 ? Theme.bad : Theme.textDim; font.pixelSize: Theme.fontSmall; Layout.fillWidth: true; elide: Text.ElideRight }
    }

    // Any DBC message on a configured bus that has no rows yet: pick one, then its cycle.
    Popup {
        id: addPopup
        objectName: "addMessagePopup"
        property alias filter: filterField.text
        property int revision: 0  // bumped at each opening: the candidates are read again
        modal: true
        onAboutToShow: revision++
        anchors.centerIn: Overlay.overlay
        width: Math.min(parent.width - 40, 480)
        height: Math.min(parent.height - 40, 420)
        padding: 10
        background: Rectangle { color: Theme.panel; radius: 8; border.color: Theme.accent }
        ColumnLayout {
            anchors.fill: parent
            spacing: 6
            Text { text: "Add a DBC message to the transmit schedule"; color: Theme.text; font.pixelSize: Theme.font; Layout.fillWidth: true; elide: Text.ElideRight }
            TouchField { id: filterField; objectName: "addMessageFilter"; placeholderText: "filter"; Layout.fillWidth: true }
            ListView {
                id: candidateList
                objectName: "addMessageCandidates"
                Layout.fillWidth: true
                Layout.fillHeight: true
                clip: true
                model: addPopup.revision > 0 ? schedule.candidates(filterField.text) : []
                delegate: Rectangle {
                    width: candidateList.width
                    height: Theme.touch
                    color: index % 2 ? Theme.panelLight : Theme.panel
                    Text { text: modelData; color: Theme.text; font.pixelSize: Theme.font; anchors.verticalCenter: parent.verticalCenter; anchors.left: parent.left; anchors.leftMargin: 8 }
                    MouseArea {
                        anchors.fill: parent
                        onClicked: {
                            const name = modelData
                            keypad.apply = (t) => schedule.addMessage(name, t)
                            keypad.show("add " + name + ": cycle (ms)", "100")
                            addPopup.close()
                        }
                    }
                }
            }
            TouchButton { text: "Cancel"; Layout.alignment: Qt.AlignRight; onClicked: addPopup.close() }
        }
    }
}
