import QtQuick
import OpenVcu.Hmi

// A round gauge: needle from `minimum` to `maximum` over 270 degrees; greyed and marked
// when the value is stale or was never received.
Item {
    id: dial
    property string title
    property string valueText: "--"
    property double value: 0
    property double minimum: 0
    property double maximum: 100
    property int status: 2
    readonly property bool fresh: status === 0
    implicitWidth: 200
    implicitHeight: 200

    Rectangle {
        id: face
        anchors.centerIn: parent
        width: Math.min(dial.width, dial.height) - 8
        height: width
        radius: width / 2
        color: Theme.panel
        border.width: 6
        border.color: dial.fresh ? Theme.accent : Theme.statusColor(dial.status)
        Rectangle {
            id: needle
            width: 4
            height: face.height * 0.4
            radius: 2
            color: dial.fresh ? Theme.text : Theme.textDim
            x: face.width / 2 - width / 2
            y: face.height / 2 - height
            transformOrigin: Item.Bottom
            rotation: {
                const span = dial.maximum - dial.minimum
                const f = span > 0 ? Math.max(0, Math.min(1, (dial.value - dial.minimum) / span)) : 0
                return -135 + 270 * f
            }
            Behavior on rotation { NumberAnimation { duration: 200 } }
        }
        Text {
            anchors.horizontalCenter: parent.horizontalCenter
            y: parent.height * 0.58
            text: dial.valueText
            color: dial.fresh ? Theme.text : Theme.textDim
            font.pixelSize: Theme.fontLarge
            font.italic: !dial.fresh
        }
        Text {
            anchors.horizontalCenter: parent.horizontalCenter
            y: parent.height * 0.75
            text: dial.title + (dial.fresh ? "" : " (" + Theme.statusText(dial.status) + ")")
            color: dial.fresh ? Theme.textDim : Theme.statusColor(dial.status)
            font.pixelSize: Theme.fontSmall
        }
    }
}
