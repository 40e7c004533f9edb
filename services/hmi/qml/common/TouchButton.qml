import QtQuick
import QtQuick.Controls
import OpenVcu.Hmi

// A button sized for a gloved finger.
Button {
    id: control
    property color tint: Theme.panelLight
    implicitHeight: Theme.touch
    implicitWidth: Math.max(Theme.touch * 2, contentItem.implicitWidth + 24)
    font.pixelSize: Theme.font
    contentItem: Text {
        text: control.text
        font: control.font
        color: control.enabled ? Theme.text : Theme.textDim
        horizontalAlignment: Text.AlignHCenter
        verticalAlignment: Text.AlignVCenter
        elide: Text.ElideRight
    }
    background: Rectangle {
        radius: 6
        color: control.down ? Qt.lighter(control.tint, 1.4) : control.tint
        opacity: control.enabled ? 1 : 0.45
        border.color: control.checked ? Theme.accent : "transparent"
        border.width: 2
    }
}
