import QtQuick
import OpenVcu.Hmi

// A coloured dot for a ModelStatus value, with its name as tooltip text.
Rectangle {
    property int status: 2
    width: 14; height: 14; radius: 7
    color: Theme.statusColor(status)
    border.color: Qt.darker(color, 1.6)
}
