import QtQuick
import QtQuick.Controls
import QtQuick.Layouts
import OpenVcu.Models
import OpenVcu.Hmi

// Open a CAN log (candump -L, candump default, ASC) with a progress bar, frames decoded
// with the DBC, chosen signals on a zoomable timeline, export of the decoded signals as CSV.
ColumnLayout {
    spacing: 4
    TraceModel { id: trace }
    RowLayout {
        Layout.fillWidth: true
        TextField { id: pathField; Layout.fillWidth: true; placeholderText: "log file path (candump -L, candump, .asc)"; font.pixelSize: Theme.fontSmall }
        TouchButton { text: "Open"; enabled: !trace.loading && pathField.text !== ""; onClicked: trace.open(pathField.text) }
        TouchButton {
            text: "Export CSV"; enabled: !trace.loading && traceView.count > 0
            onClicked: { const e = trace.exportCsv(trace.fileName + ".csv"); exportText.text = e === "" ? "saved " + trace.fileName + ".csv" : e }
        }
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
