import QtQuick
import QtQuick.Controls
import QtQuick.Layouts
import OpenVcu.Hmi

// A text field with a ⌨ button that opens the on-screen keyboard (TextKeyboard, created on
// first use); a physical keyboard types into the field as usual.
RowLayout {
    id: touchField
    property alias text: field.text
    property alias placeholderText: field.placeholderText
    property int pixelSize: Theme.font
    spacing: 2
    TextField { id: field; Layout.fillWidth: true; font.pixelSize: touchField.pixelSize }
    TouchButton {
        objectName: "keyboardButton"
        text: "⌨"
        implicitWidth: 44
        implicitHeight: Math.max(field.implicitHeight, 36)
        onClicked: {
            keyboardLoader.active = true
            keyboardLoader.item.show(field.placeholderText, field.text)
        }
    }
    Loader {
        id: keyboardLoader
        active: false
        sourceComponent: Component { TextKeyboard { objectName: "textKeyboard"; onAccepted: (typed) => field.text = typed } }
    }
}
