import QtQuick
import QtQuick.Controls
import QtQuick.Layouts
import OpenVcu.Hmi

// An on-screen keyboard in a popup for the touchscreen (no physical keyboard on the VCU):
// show(title, initial) then `accepted(text)`. Letters, digits and the characters of signal
// keys, message names and file paths; ⇧ switches the case.
Popup {
    id: keyboard
    property string title: ""
    property alias value: field.text
    property bool upper: false
    signal accepted(string text)
    modal: true
    anchors.centerIn: Overlay.overlay
    width: Math.min(Overlay.overlay ? Overlay.overlay.width - 10 : 700, 700)
    padding: 8
    background: Rectangle { color: Theme.panel; radius: 8; border.color: Theme.accent }

    function show(titleText, initial) {
        title = titleText
        field.text = initial
        open()
    }

    readonly property var rows: ["1234567890", "qwertyuiop", "asdfghjkl_", "zxcvbnm.-/"]

    ColumnLayout {
        anchors.fill: parent
        spacing: 4
        Text { text: keyboard.title; color: Theme.text; font.pixelSize: Theme.font; Layout.fillWidth: true; elide: Text.ElideMiddle }
        TextField { id: field; objectName: "keyboardField"; Layout.fillWidth: true; font.pixelSize: Theme.fontLarge }
        Repeater {
            model: keyboard.rows
            RowLayout {
                Layout.fillWidth: true
                spacing: 4
                readonly property string keys: modelData
                Repeater {
                    model: keys.length
                    TouchButton {
                        readonly property string key: keyboard.upper ? keys[index].toUpperCase() : keys[index]
                        text: key
                        Layout.fillWidth: true
                        implicitWidth: 40
                        onClicked: field.text += key
                    }
                }
            }
        }
        RowLayout {
            Layout.fillWidth: true
            spacing: 4
            TouchButton { text: "⇧"; tint: keyboard.upper ? Theme.accent : Theme.panelLight; onClicked: keyboard.upper = !keyboard.upper }
            TouchButton { text: "space"; Layout.fillWidth: true; onClicked: field.text += " " }
            TouchButton { text: "⌫"; onClicked: field.text = field.text.slice(0, -1) }
            TouchButton { text: "Clear"; onClicked: field.text = "" }
            TouchButton { text: "Cancel"; onClicked: keyboard.close() }
            TouchButton {
                text: "OK"; tint: Theme.accent
                onClicked: { keyboard.accepted(field.text); keyboard.close() }
            }
        }
    }
}
