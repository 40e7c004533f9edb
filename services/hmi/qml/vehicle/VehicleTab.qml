import QtQuick
import QtQuick.Controls
import QtQuick.Layouts
import OpenVcu.Models
import OpenVcu.Hmi

// Operator switches (enabled as the state machine allows, each with its answer) and the
// vehicle status table coloured from value-table texts; tap a row for its details.
RowLayout {
    id: vehicleTab
    spacing: 8
    OperatorModel { id: operators }
    DashboardSettings { id: statusSettings }

    ColumnLayout {
        Layout.preferredWidth: vehicleTab.width * 0.45
        Layout.maximumWidth: vehicleTab.width * (vehicleTab.height < 450 ? 0.6 : 0.45)
        Layout.fillHeight: true
        Text { text: "Operator"; color: Theme.textDim; font.pixelSize: Theme.font }
        GridLayout {
            // two columns on short screens (800x480), one on the 720x600 touchscreen
            columns: vehicleTab.height < 450 ? 2 : 1
            Layout.fillWidth: true
            columnSpacing: 6
            Repeater {
                model: operators
                ColumnLayout {
                    Layout.fillWidth: true
                    spacing: 2
                    TouchButton {
                        objectName: "switch_" + key
                        Layout.fillWidth: true
                        text: label + (on ? "  ON" : "")
                        checkable: false
                        checked: on
                        tint: on ? Theme.good : Theme.panelLight
                        enabled: allowed && !pending
                        onClicked: operators.toggle(index)
                    }
                    Text {
                        Layout.fillWidth: true
                        text: result !== "" ? result : stateText
                        color: result.indexOf("refused") >= 0 || result.indexOf("no answer") >= 0 ? Theme.bad : Theme.textDim
                        font.pixelSize: Theme.fontSmall
                        elide: Text.ElideRight
                    }
                }
            }
        }
        Item { Layout.fillHeight: true }
        Row {
            spacing: 6
            StatusDot { status: operators.status }
            Text { text: Theme.statusText(operators.status) + " " + operators.errorString; color: Theme.textDim; font.pixelSize: Theme.fontSmall }
        }
    }

    ColumnLayout {
        Layout.fillWidth: true
        Layout.fillHeight: true
        Text { text: "Vehicle status"; color: Theme.textDim; font.pixelSize: Theme.font }
        ListView {
            id: statusList
            Layout.fillWidth: true
            Layout.fillHeight: true
            clip: true
            model: SignalListModel {
                id: statusModel
                keys: statusSettings.statusKeys  // the dashboard file's "status" list
            }
            delegate: Rectangle {
                width: statusList.width
                height: 36
                color: index % 2 ? Theme.panel : Theme.panelLight
                RowLayout {
                    anchors.fill: parent
                    anchors.margins: 6
                    StatusDot { status: valueStatus }
                    Text { text: label; color: Theme.text; font.pixelSize: Theme.fontSmall; Layout.fillWidth: true; elide: Text.ElideRight }
                    Text {
                        text: valueText
                        Layout.maximumWidth: statusList.width * 0.5
                        elide: Text.ElideRight
                        color: valueStatus === ModelStatus.Ready ? Theme.toneColor(tone) : Theme.textDim
                        font.pixelSize: Theme.font
                        font.italic: valueStatus !== ModelStatus.Ready
                    }
                }
                MouseArea { anchors.fill: parent; onClicked: { detailPopup.text = detail; detailPopup.open() } }
            }
        }
    }

    Popup {
        id: detailPopup
        property alias text: detailText.text
        anchors.centerIn: Overlay.overlay
        width: 420
        modal: true
        background: Rectangle { color: Theme.panel; border.color: Theme.accent; radius: 8 }
        Text { id: detailText; width: parent.width; wrapMode: Text.Wrap; color: Theme.text; font.pixelSize: Theme.fontSmall }
    }
}
