import QtQuick
import QtQuick.Controls
import QtQuick.Layouts
import OpenVcu.Models
import OpenVcu.Hmi

// The Trace tab's Statistics page (issue 21): the figures of `vcu trace stats` over the
// opened log(s), computed on a worker thread by TraceStatsModel: bus load per bus (mean,
// peak, over time), then per message (periods in ms; the expected cycle in blue when it is
// the VCU's schedule, white from the DBC's GenMsgCycleTime; deviating rows in orange) or
// per node (frames, bit/s, share of the bus).
ColumnLayout {
    id: page
    property TraceStatsModel stats
    property int busIndex: 0
    spacing: 4

    component Cell: Text {
        property bool head: false
        color: head ? Theme.textDim : Theme.text
        font.pixelSize: 12
        font.bold: head
        horizontalAlignment: Text.AlignRight
        elide: Text.ElideRight
    }
    function ms(value) { return value > 0 ? value.toFixed(1) : "–" }
    function signedMs(value) { return Math.abs(value) < 0.05 ? "0.0" : (value > 0 ? "+" : "") + value.toFixed(1) }

    RowLayout {
        Layout.fillWidth: true
        BusyIndicator { running: page.stats.computing; visible: running; implicitWidth: 32; implicitHeight: 32 }
        Text {
            objectName: "statsSummary"
            Layout.fillWidth: true
            text: page.stats.computing ? "computing… " + page.stats.framesRead + " frames read"
                  : page.stats.paths.length === 0 ? "open a log (or a folder of vcu record) to see its statistics"
                  : page.stats.summary
            color: Theme.textDim; font.pixelSize: Theme.fontSmall; elide: Text.ElideRight
        }
        TouchButton {
            text: "Recompute"; implicitHeight: 40
            enabled: !page.stats.computing && page.stats.paths.length > 0
            onClicked: page.stats.compute(page.stats.paths)
        }
    }
    Text {
        objectName: "statsError"
        Layout.fillWidth: true
        visible: text !== ""
        text: page.stats.errorString
        color: page.stats.status === ModelStatus.Error ? Theme.bad : Theme.warn
        font.pixelSize: Theme.fontSmall; wrapMode: Text.Wrap; maximumLineCount: 3; elide: Text.ElideRight
    }
    // bus load: one line per bus (tap to plot it), the chosen bus's load over time
    Repeater {
        model: page.stats.buses
        Rectangle {
            Layout.fillWidth: true
            implicitHeight: 26
            color: index === page.busIndex ? Qt.darker(Theme.accent, 1.8) : Theme.panel
            Text {
                anchors.fill: parent; anchors.leftMargin: 6; verticalAlignment: Text.AlignVCenter
                text: modelData.bus + " (" + (modelData.bitrate / 1000) + " kbit/s): load mean " + modelData.loadMeanPct.toFixed(1)
                      + " %, peak " + modelData.loadMaxPct.toFixed(1) + " %, " + modelData.frames + " frames"
                      + (modelData.errorFrames > 0 ? ", " + modelData.errorFrames + " error frames" : "")
                color: Theme.text; font.pixelSize: Theme.fontSmall; elide: Text.ElideRight
            }
            MouseArea { anchors.fill: parent; onClicked: page.busIndex = index }
        }
    }
    LoadPlot {
        objectName: "loadPlot"
        Layout.fillWidth: true
        Layout.preferredHeight: 70
        visible: page.stats.buses.length > 0
        readonly property var bus: page.stats.buses.length > 0 ? page.stats.buses[Math.min(page.busIndex, page.stats.buses.length - 1)] : null
        series: bus ? bus.series : []
        meanPct: bus ? bus.loadMeanPct : 0
        peakPct: bus ? Math.max(bus.loadMaxPct, bus.seriesMaxPct) : 0
        bucketS: bus ? bus.bucketS : 0
    }
    TabBar {
        id: tables
        Layout.fillWidth: true
        visible: page.stats.buses.length > 0
        TabButton { text: "Messages (" + messageView.count + ")"; font.pixelSize: Theme.fontSmall; implicitHeight: 36 }
        TabButton { text: "Nodes (" + nodeView.count + ")"; font.pixelSize: Theme.fontSmall; implicitHeight: 36 }
    }
    Item {
        Layout.fillWidth: true
        Layout.fillHeight: true
        ListView {
            id: messageView
            objectName: "messageTable"
            anchors.fill: parent
            visible: tables.currentIndex === 0
            clip: true
            model: page.stats
            headerPositioning: ListView.OverlayHeader
            header: Rectangle {
                width: messageView.width; height: 22; color: Theme.background; z: 2
                Row {
                    spacing: 4
                    Cell { head: true; width: 56; text: "bus"; horizontalAlignment: Text.AlignLeft }
                    Cell { head: true; width: 84; text: "id"; horizontalAlignment: Text.AlignLeft }
                    Cell { head: true; width: messageView.width - 594; text: "name"; horizontalAlignment: Text.AlignLeft }
                    Cell { head: true; width: 50; text: "count" }
                    Cell { head: true; width: 44; text: "exp" }
                    Cell { head: true; width: 48; text: "mean" }
                    Cell { head: true; width: 44; text: "p50" }
                    Cell { head: true; width: 44; text: "p99" }
                    Cell { head: true; width: 48; text: "max" }
                    Cell { head: true; width: 48; text: "dev" }
                    Cell { head: true; width: 36; text: "gaps" }
                    Cell { head: true; width: 40; text: "miss" }
                }
            }
            delegate: Rectangle {
                width: messageView.width
                height: 22
                color: model.flagged ? Qt.darker(Theme.warn, 2.6) : (index % 2 ? Theme.panel : Theme.background)
                Row {
                    spacing: 4
                    anchors.verticalCenter: parent.verticalCenter
                    Cell { width: 56; text: model.bus; horizontalAlignment: Text.AlignLeft }
                    Cell { width: 84; text: model.frameId; horizontalAlignment: Text.AlignLeft; font.family: "monospace" }
                    Cell { width: messageView.width - 594; text: model.name !== "" ? model.name : "?"; horizontalAlignment: Text.AlignLeft; color: model.name !== "" ? Theme.text : Theme.textDim }
                    Cell { width: 50; text: model.count }
                    Cell { width: 44; text: page.ms(model.expectedMs); color: model.cycleSource === "schedule" ? Theme.accent : Theme.text }
                    Cell { width: 48; text: page.ms(model.meanMs) }
                    Cell { width: 44; text: page.ms(model.p50Ms) }
                    Cell { width: 44; text: page.ms(model.p99Ms) }
                    Cell { width: 48; text: page.ms(model.maxMs) }
                    Cell { width: 48; text: model.expectedMs > 0 && model.count > 1 ? page.signedMs(model.deviationMs) : "–"; color: model.flagged ? Theme.warn : Theme.text }
                    Cell { width: 36; text: model.gaps; color: model.gaps > 0 ? Theme.warn : Theme.text }
                    Cell { width: 40; text: model.missing; color: model.missing > 0 ? Theme.warn : Theme.text }
                }
            }
        }
        ListView {
            id: nodeView
            objectName: "nodeTable"
            anchors.fill: parent
            visible: tables.currentIndex === 1
            clip: true
            model: page.stats.nodes
            headerPositioning: ListView.OverlayHeader
            header: Rectangle {
                width: nodeView.width; height: 22; color: Theme.background; z: 2
                Row {
                    spacing: 4
                    Cell { head: true; width: 70; text: "bus"; horizontalAlignment: Text.AlignLeft }
                    Cell { head: true; width: 60; text: "SA"; horizontalAlignment: Text.AlignLeft }
                    Cell { head: true; width: nodeView.width - 440; text: "name"; horizontalAlignment: Text.AlignLeft }
                    Cell { head: true; width: 80; text: "frames" }
                    Cell { head: true; width: 90; text: "bit/s" }
                    Cell { head: true; width: 110; text: "share of bus" }
                }
            }
            delegate: Rectangle {
                width: nodeView.width
                height: 24
                color: index % 2 ? Theme.panel : Theme.background
                Row {
                    spacing: 4
                    anchors.verticalCenter: parent.verticalCenter
                    Cell { width: 70; text: model.bus; horizontalAlignment: Text.AlignLeft }
                    Cell { width: 60; text: model.saText; horizontalAlignment: Text.AlignLeft; font.family: "monospace" }
                    Cell { width: nodeView.width - 440; text: model.name !== "" ? model.name : "?"; horizontalAlignment: Text.AlignLeft; color: model.name !== "" ? Theme.text : Theme.textDim }
                    Cell { width: 80; text: model.frames }
                    Cell { width: 90; text: Math.round(model.bitsPerS) }
                    Item {
                        width: 110; height: 18
                        Rectangle { anchors.left: parent.left; anchors.verticalCenter: parent.verticalCenter; height: 10; width: Math.max(1, 60 * model.sharePct / 100); color: Theme.accent }
                        Cell { anchors.right: parent.right; width: 46; text: model.sharePct.toFixed(1) + " %" }
                    }
                }
            }
        }
        Text {
            anchors.centerIn: parent
            visible: !page.stats.computing && page.stats.paths.length > 0 && messageView.count === 0 && page.stats.status !== ModelStatus.Error
            text: "no frames"; color: Theme.textDim; font.pixelSize: Theme.font
        }
    }
}
