import QtQuick
import QtQuick.Controls
import QtQuick.Layouts
import OpenVcu.Models
import OpenVcu.Hmi

// Open a CAN log (candump -L, candump default, ASC) or a folder of `vcu record` (its *.log
// files, one per bus) with a progress bar. Signals page: the frames decoded with the DBC,
// chosen signals on a zoomable timeline, export of the decoded signals as CSV (one log at a
// time: the first, or the one chosen). Statistics page: bus load, nodes and message cycles
// of all opened logs as one timeline (TraceStatistics).
ColumnLayout {
    id: viewer
    /// The opened logs: one file, or the *.log files of a folder.
    property var paths: []
    /// Opened at start (vcu-hmi --trace PATH), on the Statistics page with initialStatistics.
    property string initialPath: ""
    property bool initialStatistics: false
    spacing: 4
    Component.onCompleted: {
        if (initialStatistics) pages.currentIndex = 1
        if (initialPath !== "") openPath(initialPath)
    }
    TraceModel { id: trace }
    TraceStatsModel { id: stats }
    FileBrowserModel { id: browser }

    /// Opens `list` (log files): the first on the Signals page, all of them for the statistics.
    function openPaths(list, shown) {
        if (list.length === 0) return
        paths = list
        pathField.text = shown !== undefined ? shown : list[0]
        trace.open(list[0])
        refreshStatistics()
    }
    /// A log file, or a folder whose *.log files are opened together.
    function openPath(path) {
        const logs = stats.logsInFolder(path)
        if (logs.length > 0) openPaths(logs, path)
        else openPaths([path])
    }
    /// The statistics are computed when their page is shown and the logs have changed.
    function refreshStatistics() {
        if (pages.currentIndex !== 1 || paths.length === 0) return
        if (JSON.stringify(stats.paths) !== JSON.stringify(paths) && !stats.computing) stats.compute(paths)
        else if (stats.computing) stats.compute(paths)
    }
    RowLayout {
        Layout.fillWidth: true
        TouchButton { objectName: "browseButton"; text: "Browse…"; enabled: !trace.loading; onClicked: { browser.reload(); browsePopup.open() } }
        TouchField { id: pathField; Layout.fillWidth: true; placeholderText: "log file or recording folder (candump -L, candump, .asc)"; pixelSize: Theme.fontSmall }
        TouchButton { text: "Open"; enabled: !trace.loading && pathField.text !== ""; onClicked: viewer.openPath(pathField.text) }
        TouchButton {
            text: "Export CSV"; enabled: !trace.loading && traceView.count > 0
            onClicked: {
                const base = trace.fileName.substring(trace.fileName.lastIndexOf("/") + 1)
                const path = browser.newFilePath(base, "csv")
                const e = trace.exportCsv(path)
                exportText.text = e === "" ? "saved " + path : e
            }
        }
    }
    // A folder listing sized for a finger: tap a folder to enter it, a file to open it.
    Popup {
        id: browsePopup
        objectName: "browsePopup"
        modal: true
        anchors.centerIn: Overlay.overlay
        width: Math.min(parent.width - 20, 640)
        height: Math.min(parent.height - 20, 460)
        padding: 8
        background: Rectangle { color: Theme.panel; radius: 8; border.color: Theme.accent }
        ColumnLayout {
            anchors.fill: parent
            spacing: 4
            RowLayout {
                Layout.fillWidth: true
                TouchButton { text: "Data"; onClicked: browser.folder = browser.dataFolder }
                Text { text: browser.folder; color: Theme.text; font.pixelSize: Theme.fontSmall; elide: Text.ElideLeft; Layout.fillWidth: true }
                TouchButton {
                    text: "All *.log"
                    enabled: stats.logsInFolder(browser.folder).length > 0
                    onClicked: { viewer.openPath(browser.folder); browsePopup.close() }
                }
                TouchButton { text: "Close"; onClicked: browsePopup.close() }
            }
            Text { text: browser.errorString; color: Theme.bad; font.pixelSize: Theme.fontSmall; visible: text !== ""; Layout.fillWidth: true; elide: Text.ElideLeft }
            ListView {
                id: fileList
                objectName: "browseList"
                Layout.fillWidth: true
                Layout.fillHeight: true
                clip: true
                model: browser
                delegate: Rectangle {
                    width: fileList.width
                    height: Theme.touch
                    color: index % 2 ? Theme.panelLight : Theme.panel
                    RowLayout {
                        anchors.fill: parent
                        anchors.leftMargin: 8
                        anchors.rightMargin: 8
                        Text { text: (isFolder ? "▸ " : "") + name; color: isFolder ? Theme.accent : Theme.text; font.pixelSize: Theme.font; elide: Text.ElideMiddle; Layout.fillWidth: true }
                        Text { text: sizeText + "  " + modified; color: Theme.textDim; font.pixelSize: Theme.fontSmall }
                    }
                    MouseArea {
                        anchors.fill: parent
                        onClicked: {
                            const file = browser.enter(index)
                            if (file === "") return
                            browsePopup.close()
                            viewer.openPaths([file])
                        }
                    }
                }
            }
        }
    }
    TabBar {
        id: pages
        objectName: "tracePages"
        Layout.fillWidth: true
        onCurrentIndexChanged: viewer.refreshStatistics()
        TabButton { text: "Signals"; font.pixelSize: Theme.fontSmall; implicitHeight: 40 }
        TabButton { text: "Statistics"; font.pixelSize: Theme.fontSmall; implicitHeight: 40 }
    }
    // pages as plain Items (see CanDataTab.qml: nested StackLayouts crashed in Qt 6.4.2)
    Item {
        Layout.fillWidth: true
        Layout.fillHeight: true
        ColumnLayout {
            anchors.fill: parent
            visible: pages.currentIndex === 0
            spacing: 4
            ComboBox {
                Layout.fillWidth: true
                visible: viewer.paths.length > 1
                model: viewer.paths
                font.pixelSize: Theme.fontSmall
                onActivated: (i) => trace.open(viewer.paths[i])
            }
            ProgressBar { Layout.fillWidth: true; value: trace.progress; visible: trace.loading }
            Text { text: trace.summary + (trace.errorString !== "" ? "  " + trace.errorString : ""); color: trace.status === ModelStatus.Error ? Theme.bad : Theme.textDim; font.pixelSize: Theme.fontSmall; Layout.fillWidth: true; elide: Text.ElideRight }
            Text { id: exportText; color: Theme.textDim; font.pixelSize: Theme.fontSmall; visible: text !== "" }
            RowLayout {
                Layout.fillWidth: true
                visible: traceView.count > 0
                ComboBox { id: signalBox; Layout.fillWidth: true; model: trace.loading ? [] : trace.signalNames(); font.pixelSize: Theme.fontSmall }
                TouchButton { text: "±"; onClicked: timelineMessage.text = timeline.toggleKey(signalBox.currentText) }
                TouchButton { text: "+"; onClicked: timeline.zoom(0.5, 0.5) }
                TouchButton { text: "−"; onClicked: timeline.zoom(2, 0.5) }
                TouchButton { text: "◀"; onClicked: timeline.pan(-0.25) }
                TouchButton { text: "▶"; onClicked: timeline.pan(0.25) }
                TouchButton { text: "All"; onClicked: timeline.reset() }
            }
            Rectangle {
                Layout.fillWidth: true
                Layout.preferredHeight: 140
                visible: traceView.count > 0
                color: Theme.panel
                TraceTimeline {
                    id: timeline
                    objectName: "timeline"
                    anchors.fill: parent
                    trace: trace
                }
                WheelHandler { onWheel: (event) => timeline.zoom(event.angleDelta.y > 0 ? 0.8 : 1.25, point.position.x / parent.width) }
                Text {
                    anchors.left: parent.left; anchors.bottom: parent.bottom; anchors.margins: 2
                    text: timeline.viewStart.toFixed(2) + " s .. " + timeline.viewEnd.toFixed(2) + " s"
                    color: Theme.textDim; font.pixelSize: 11
                }
            }
            Repeater {
                model: timeline.legend
                Text { text: modelData; color: ["#42a5f5", "#ffa726", "#66bb6a", "#ec407a"][index]; font.pixelSize: Theme.fontSmall }
            }
            Text { id: timelineMessage; color: Theme.bad; font.pixelSize: Theme.fontSmall; visible: text !== "" }
            ListView {
                id: traceView
                objectName: "traceList"
                Layout.fillWidth: true
                Layout.fillHeight: true
                clip: true
                model: trace
                delegate: Column {
                    width: traceView.width
                    Text { text: time + "  " + frameId + "  [" + bytes + "]  " + message; color: Theme.text; font.pixelSize: 12; font.family: "monospace"; width: parent.width; elide: Text.ElideRight }
                    Text { text: decoded; color: Theme.textDim; font.pixelSize: 11; width: parent.width; elide: Text.ElideRight; visible: decoded !== "" }
                }
                Text { anchors.centerIn: parent; visible: traceView.count === 0 && !trace.loading; text: "no log opened"; color: Theme.textDim; font.pixelSize: Theme.font }
            }
        }
        TraceStatistics {
            objectName: "statisticsPage"
            anchors.fill: parent
            visible: pages.currentIndex === 1
            stats: stats
        }
    }
}
