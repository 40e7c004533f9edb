import QtQuick
import QtQuick.Controls
import QtQuick.Layouts
import OpenVcu.Models
import OpenVcu.Hmi

// The transmit schedule: message, signal, cycle, J1939-76 pair and delta, value, override.
// Tap the cycle, the value (the schedule's value: ScheduleDefault) or "set" under Override
// to type a new one on the keypad; each change is a checked, acknowledged command to the
// running stack (no restart). Overrides are marked and clearable.
ColumnLayout {
    spacing: 4
    ScheduleModel { id: schedule }
    Keypad { id: keypad; property var apply; onAccepted: (text) => { const refused = apply(text); if (refused !== "") message.text = refused } }

    Row {
        Layout.fillWidth: true
        Repeater {
            model: [["Message", 0.24], ["Signal", 0.26], ["Cycle", 0.1], ["SHM / Δ", 0.12], ["Value", 0.14], ["Override", 0.14]]
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
                Text { width: scheduleList.width * 0.24; text: message; color: Theme.text; font.pixelSize: Theme.fontSmall; elide: Text.ElideRight; anchors.verticalCenter: parent.verticalCenter }
                Text { width: scheduleList.width * 0.26; text: signal; color: Theme.text; font.pixelSize: Theme.fontSmall; elide: Text.ElideRight; anchors.verticalCenter: parent.verticalCenter }
                Text {
                    width: scheduleList.width * 0.1; text: cycleMs > 0 ? cycleMs + " ms" : "-"; color: Theme.accent; font.pixelSize: Theme.fontSmall
                    anchors.verticalCenter: parent.verticalCenter
                    MouseArea {
                        anchors.fill: parent
                        onClicked: { keypad.apply = (t) => schedule.setCycle(index, t); keypad.show("cycle of " + message + " (ms)", cycleMs) }
                    }
                }
                Text { width: scheduleList.width * 0.12; text: shmPair ? "pair " + deltaUs + " µs" : "-"; color: Theme.textDim; font.pixelSize: Theme.fontSmall; anchors.verticalCenter: parent.verticalCenter }
                Text {
                    width: scheduleList.width * 0.14; text: valueText; color: Theme.accent; font.pixelSize: Theme.fontSmall; elide: Text.ElideRight
                    anchors.verticalCenter: parent.verticalCenter
                    MouseArea {
                        anchors.fill: parent
                        onClicked: { keypad.apply = (t) => schedule.setDefault(index, t); keypad.show("schedule value of " + signal + " (" + range + ")", "") }
                    }
                }
                Row {
                    width: scheduleList.width * 0.14
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
        StatusDot { status: schedule.status }
        Text { text: schedule.lastResult !== "" ? schedule.lastResult : Theme.statusText(schedule.status) + " " + schedule.errorString
               color: schedule.lastResult.indexOf("refused") >= 0 ? Theme.bad : Theme.textDim; font.pixelSize: Theme.fontSmall; Layout.fillWidth: true; elide: Text.ElideRight }
    }
}
