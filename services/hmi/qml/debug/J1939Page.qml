import QtQuick
import QtQuick.Controls
import QtQuick.Layouts
import OpenVcu.Models
import OpenVcu.Hmi

// The J1939 networks as vcu-can-tx sees them (what `vcu j1939` prints), per bus: a header
// row with the bus's freshness (grey: not heard yet, orange: not heard for 3 s, its last view
// kept), the VCU's claim state, address and NAME; the other nodes (address, NAME, the DBC
// node with that NmStationAddress); the VCU's DTCs (active first) and the DM1 lamps.
ColumnLayout {
    spacing: 4
    J1939Model { id: j1939 }

    ListView {
        id: j1939List
        objectName: "j1939List"
        Layout.fillWidth: true
        Layout.fillHeight: true
        clip: true
        model: j1939
        delegate: Rectangle {
            width: j1939List.width
            height: kind === J1939Model.Claim ? 40 : 28
            color: kind === J1939Model.Claim ? Theme.panelLight : (index % 2 ? Theme.panel : Theme.background)
            opacity: busStatus === ModelStatus.Ready || kind === J1939Model.Claim ? 1 : 0.6
            RowLayout {
                anchors.fill: parent
                anchors.leftMargin: kind === J1939Model.Claim ? 6 : 28
                anchors.rightMargin: 6
                spacing: 10
                StatusDot { visible: kind === J1939Model.Claim; status: busStatus }
                Text {
                    visible: kind === J1939Model.Claim
                    text: "bus " + bus
                    color: Theme.text; font.pixelSize: Theme.font; font.bold: true
                }
                Text {  // claim state, DBC node, DTC state, lamps or a heading
                    visible: kind !== J1939Model.Node && kind !== J1939Model.Dtc
                    text: label + (kind === J1939Model.Claim && busStatus === ModelStatus.Stale ? "  (not heard for 3 s)" : "")
                    color: alert ? Theme.bad : kind === J1939Model.Note ? Theme.textDim
                         : kind === J1939Model.Claim && label === "claimed" ? Theme.good : Theme.text
                    font.pixelSize: kind === J1939Model.Claim ? Theme.font : Theme.fontSmall
                    font.bold: alert
                    Layout.fillWidth: kind !== J1939Model.Claim
                    elide: Text.ElideRight
                }
                Text {
                    visible: address !== ""
                    text: (kind === J1939Model.Claim ? "address " : "") + address
                    color: Theme.text; font.pixelSize: kind === J1939Model.Claim ? Theme.font : Theme.fontSmall
                    Layout.preferredWidth: kind === J1939Model.Claim ? implicitWidth : 90
                }
                Text {
                    visible: nodeName !== ""
                    text: kind === J1939Model.Claim ? "NAME " + nodeName : nodeName
                    color: kind === J1939Model.Dtc && active ? Theme.bad : Theme.text
                    font.pixelSize: kind === J1939Model.Claim ? Theme.font : Theme.fontSmall
                    Layout.fillWidth: true
                    elide: Text.ElideRight
                }
                Text {
                    visible: kind === J1939Model.Node
                    text: label !== "" ? label : "-"
                    color: Theme.textDim; font.pixelSize: Theme.fontSmall
                    Layout.preferredWidth: 140
                    elide: Text.ElideRight
                }
                Text {
                    visible: kind === J1939Model.Dtc
                    text: "SPN " + spn + "  FMI " + fmi + "  × " + occurrences
                    color: Theme.text; font.pixelSize: Theme.fontSmall
                    Layout.preferredWidth: 190
                }
                Text {
                    visible: kind === J1939Model.Dtc
                    text: label
                    color: active ? Theme.bad : Theme.textDim; font.pixelSize: Theme.fontSmall; font.bold: active
                    Layout.preferredWidth: 110
                }
            }
        }
        Text {
            anchors.centerIn: parent
            visible: j1939List.count === 0
            text: "no J1939 bus in the configuration and none reported by vcu-can-tx"
            color: Theme.textDim
        }
    }
    RowLayout {
        StatusDot { status: j1939.status }
        Text {
            text: "vcu-can-tx's view, once a second and on change: " + Theme.statusText(j1939.status) + " " + j1939.errorString
            color: Theme.textDim; font.pixelSize: Theme.fontSmall; Layout.fillWidth: true; elide: Text.ElideRight
        }
    }
}
