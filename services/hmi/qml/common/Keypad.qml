import QtQuick
import QtQuick.Controls
import QtQuick.Layouts
import OpenVcu.Hmi

// A numeric keypad in a popup: open(title, initial) then `accepted(text)`.
Popup {
    id: keypad
    property string title: ""
    property alias value: field.text
    signal accepted(string text)
    modal: true
    anchors.centerIn: Overlay.overlay
    width: 320
    padding: 12
    background: Rectangle { color: Theme.panel; radius: 8; border.color: Theme.accent }

    function show(titleText, initial) {
        title = titleText
        field.text = initial
        open()
    }

    ColumnLayout {
        anchors.fill: parent
        spacing: 8
        Text { text: keypad.title; color: Theme.text; font.pixelSize: Theme.font; Layout.fillWidth: true; elide: Text.ElideMiddle }
        TextField {
            id: field
            objectName: "keypadField"
            Layout.fillWidth: true
            font.pixelSize: Theme.fontLarge
            inputMethodHints: Qt.ImhFormattedNumbersOnly
        }
        GridLayout {
            columns: 3
            Layout.fillWidth: true
            Repeater {
                model: ["7", "8", "9", "4", "5", "6", "1", "2", "3", "-", "0", "."]
                TouchButton {
                    text: modelData
                    Layout.fillWidth: true
                    onClicked: field.text += modelData
                }
            }
        }
        RowLayout {
            Layout.fillWidth: true
            TouchButton { text: "⌫"; Layout.fillWidth: true; onClicked: field.text = field.text.slice(0, -1) }
            TouchButton { text: "Cancel"; Layout.fillWidth: true; onClicked: keypad.close() }
            TouchButton {
                text: "OK"; tint: Theme.accent; Layout.fillWidth: true
                onClicked: { keypad.accepted(field.text); keypad.close() }
            }
        }
    }
}
