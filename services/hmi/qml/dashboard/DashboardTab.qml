import QtQuick
import QtQuick.Layouts
import OpenVcu.Models
import OpenVcu.Hmi

// Dials for pack voltage, current and power, and the grid of the dashboard file's values;
// stale and never-received values are greyed, italic and labelled.
ColumnLayout {
    spacing: 8
    DashboardSettings { id: settings }
    SignalValue { id: voltage; key: settings.voltageKey }
    SignalValue { id: current; key: settings.currentKey }
    SignalValue { id: power; key: settings.powerKey }

    RowLayout {
        Layout.fillWidth: true
        Layout.preferredHeight: parent.height * 0.45
        Layout.maximumHeight: parent.height * 0.45
        Dial {
            Layout.fillWidth: true; Layout.fillHeight: true
            title: "Pack voltage"; value: voltage.value; valueText: voltage.text; status: voltage.status
            minimum: settings.voltageRange[0]; maximum: settings.voltageRange[1]
        }
        Dial {
            Layout.fillWidth: true; Layout.fillHeight: true
            title: "Pack current"; value: current.value; valueText: current.text; status: current.status
            minimum: settings.currentRange[0]; maximum: settings.currentRange[1]
        }
        Dial {
            // power from the file's key, else U x I (then as fresh as the worse of the two)
            readonly property bool computed: settings.powerKey === ""
            readonly property double kilowatts: computed ? voltage.value * current.value / 1000 : power.value
            Layout.fillWidth: true; Layout.fillHeight: true
            title: computed ? "Power (U x I)" : "Power"
            value: kilowatts
            valueText: (computed ? (voltage.status === 0 && current.status === 0 ? kilowatts.toFixed(1) + " kW" : "--") : power.text)
            status: computed ? Math.max(voltage.status, current.status) : power.status
            minimum: settings.powerRange[0]; maximum: settings.powerRange[1]
        }
    }
    Text {
        visible: settings.status === ModelStatus.Error
        text: "dashboard file refused: " + settings.errorString
        color: Theme.bad; font.pixelSize: Theme.fontSmall; Layout.fillWidth: true; wrapMode: Text.Wrap
    }
    GridView {
        id: grid
        Layout.fillWidth: true
        Layout.fillHeight: true
        Layout.minimumHeight: cellHeight * 2
        clip: true
        cellWidth: Math.max(160, width / Math.max(1, Math.floor(width / 170)))
        cellHeight: 64
        model: SignalListModel { dashboard: true }
        delegate: Rectangle {
            width: grid.cellWidth - 6
            height: grid.cellHeight - 6
            radius: 6
            color: Theme.panel
            border.color: valueStatus === ModelStatus.Ready ? "transparent" : Theme.statusColor(valueStatus)
            Column {
                anchors.fill: parent
                anchors.margins: 6
                Text { text: label; color: Theme.textDim; font.pixelSize: Theme.fontSmall; width: parent.width; elide: Text.ElideRight }
                Text {
                    text: valueStatus === ModelStatus.NotConnected ? "never received" : valueText + (valueStatus === ModelStatus.Stale ? "  (stale)" : "")
                    color: valueStatus === ModelStatus.Ready ? Theme.toneColor(tone) : Theme.statusColor(valueStatus)
                    font.pixelSize: Theme.fontLarge
                    font.italic: valueStatus !== ModelStatus.Ready
                    width: parent.width
                    elide: Text.ElideRight
                }
            }
        }
    }
}
