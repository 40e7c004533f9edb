import QtQuick
import QtQuick.Layouts
import OpenVcu.Models
import OpenVcu.Hmi

// Clock, battery (SOC, SOH, charger), FSM state and one dot per service.
Rectangle {
    id: header
    property var health
    property var fsm
    color: Theme.panel
    implicitHeight: 56

    // the keys come from the dashboard file (--dashboard): nothing here names a vehicle's signal
    DashboardSettings { id: settings }
    SignalValue { id: soc; key: settings.socKey }
    SignalValue { id: soh; key: settings.sohKey }
    SignalValue { id: charger; key: settings.chargerKey }

    RowLayout {
        anchors.fill: parent
        anchors.margins: 6
        spacing: 12
        Text { objectName: "clock"; text: Stack.clockText; color: Theme.text; font.pixelSize: Theme.fontLarge; font.bold: true }
        Column {
            Text { text: "SOC " + soc.text; color: Theme.statusColor(soc.status) === Theme.good ? Theme.text : Theme.statusColor(soc.status); font.pixelSize: Theme.font }
            Text { text: "SOH " + soh.text + "   charger " + charger.text; color: Theme.textDim; font.pixelSize: Theme.fontSmall }
        }
        Item { Layout.fillWidth: true }
        Column {
            // while vcu-fsm is silent the state is its last one: struck through, amber, with the note
            readonly property bool stale: header.fsm ? header.fsm.stateNote !== "" : false
            Text { objectName: "fsmState"; text: header.fsm ? header.fsm.stateName : "--"; color: parent.stale ? Theme.warn : Theme.text; font.strikeout: parent.stale; font.pixelSize: Theme.fontLarge; anchors.right: parent.right }
            Text { objectName: "fsmNote"; text: header.fsm ? (parent.stale ? header.fsm.stateNote : "for " + header.fsm.stateAge) : ""; color: parent.stale ? Theme.warn : Theme.textDim; font.pixelSize: Theme.fontSmall; anchors.right: parent.right }
        }
        Grid {
            columns: 3
            spacing: 3
            Repeater {
                model: header.health
                Row {
                    spacing: 2
                    StatusDot { status: connection; width: 10; height: 10; anchors.verticalCenter: parent.verticalCenter }
                    Text { text: name.replace("vcu-", ""); color: Theme.textDim; font.pixelSize: 11 }
                }
            }
        }
    }
}
