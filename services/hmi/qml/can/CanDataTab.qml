import QtQuick
import QtQuick.Controls
import QtQuick.Layouts
import OpenVcu.Models
import OpenVcu.Hmi

// The DBC tree (bus > node > message > signal) with search; tap a signal to add it to the
// live plot (up to 4), choose the window, pause, and drag on the plot for a cursor readout.
RowLayout {
    id: tab
    property var initialKeys: []
    property int initialWindow: 30      // s: 10, 30, 60, 300 or 600
    property bool initialFramesPage: false
    spacing: 6

    ColumnLayout {
        Layout.preferredWidth: tab.width * 0.45
        Layout.maximumWidth: tab.width * 0.45
        Layout.fillHeight: true
        TouchField {
            objectName: "signalSearch"
            Layout.fillWidth: true
            placeholderText: "search signals"
            onTextChanged: tree.search = text
        }
        ListView {
            id: treeView
            Layout.fillWidth: true
            Layout.fillHeight: true
            clip: true
            model: SignalTreeModel { id: tree }
            delegate: Rectangle {
                width: treeView.width
                height: depth === 3 ? 40 : 34
                color: depth === 3 && plot.keys.indexOf(key) >= 0 ? Qt.darker(Theme.accent, 1.8) : (index % 2 ? Theme.panel : Theme.background)
                Column {
                    x: 6 + depth * 12
                    width: parent.width - x - 4
                    anchors.verticalCenter: parent.verticalCenter
                    Row {
                        spacing: 6
                        Text { text: depth < 3 ? (expanded ? "▾" : "▸") : "•"; color: Theme.textDim; font.pixelSize: Theme.font }
                        Text { text: name; color: Theme.text; font.pixelSize: Theme.fontSmall; font.bold: depth < 3 }
                        Text {
                            text: depth === 3 ? valueText : ""
                            color: valueStatus === ModelStatus.Ready ? Theme.good : Theme.textDim
                            font.pixelSize: Theme.fontSmall
                            font.italic: valueStatus !== ModelStatus.Ready
                        }
                    }
                    Text {
                        text: detail + (depth === 3 && comment !== "" ? "  " + comment : "")
                        color: Theme.textDim; font.pixelSize: 11; width: parent.width; elide: Text.ElideRight
                        visible: text !== ""
                    }
                }
                MouseArea {
                    anchors.fill: parent
                    onClicked: depth === 3 ? plotMessage.text = plot.toggleKey(key) : tree.toggle(index)
                }
            }
        }
    }

    ColumnLayout {
        Layout.fillWidth: true
        Layout.fillHeight: true
        TabBar {
            id: rightPages
            Layout.fillWidth: true
            // after the buttons exist (a binding is overwritten when the first one is added)
            Component.onCompleted: if (tab.initialFramesPage) setCurrentIndex(1)
            TabButton { text: "Plot"; implicitHeight: 40; font.pixelSize: Theme.fontSmall }
            TabButton { text: "Frames"; implicitHeight: 40; font.pixelSize: Theme.fontSmall }
        }
        // pages as plain Items: a StackLayout nested in the window's StackLayout crashed in
        // Qt 6.4.2 (QQuickStackLayout::cachedItemSizeHints) when the tab was switched
        Item {
            Layout.fillWidth: true
            Layout.fillHeight: true
            ColumnLayout {
                anchors.fill: parent
                visible: rightPages.currentIndex === 0
                RowLayout {
                    ComboBox {
                        id: windowBox
                        model: ["10 s", "30 s", "1 min", "5 min", "10 min"]
                        readonly property var seconds: [10, 30, 60, 300, 600]
                        currentIndex: Math.max(0, seconds.indexOf(tab.initialWindow))
                        onCurrentIndexChanged: plot.windowSeconds = seconds[currentIndex]
                    }
                    TouchButton { text: plot.paused ? "Resume" : "Pause"; onClicked: plot.paused = !plot.paused }
                    TouchButton { text: "Clear"; onClicked: plot.keys = [] }
                }
                Rectangle {
                    Layout.fillWidth: true
                    Layout.fillHeight: true
                    color: Theme.panel
                    SignalPlot {
                        id: plot
                        objectName: "plot"
                        anchors.fill: parent
                        Component.onCompleted: {
                            windowSeconds = windowBox.seconds[windowBox.currentIndex]
                            if (tab.initialKeys.length > 0) keys = tab.initialKeys
                        }
                    }
                    Rectangle {
                        visible: plot.cursorX >= 0
                        x: plot.cursorX; width: 1; height: parent.height; color: Theme.text
                    }
                    MouseArea {
                        anchors.fill: parent
                        onPressed: (mouse) => plot.cursorX = mouse.x
                        onPositionChanged: (mouse) => plot.cursorX = Math.max(0, Math.min(width, mouse.x))
                        onDoubleClicked: plot.cursorX = -1
                    }
                    Text {
                        anchors.centerIn: parent
                        visible: plot.keys.length === 0
                        text: "tap signals in the tree to plot them (up to 4)"
                        color: Theme.textDim; font.pixelSize: Theme.font
                    }
                }
                Repeater {
                    model: plot.legend
                    Text { text: modelData; color: ["#42a5f5", "#ffa726", "#66bb6a", "#ec407a"][index]; font.pixelSize: Theme.fontSmall }
                }
                Text { text: plot.readout; color: Theme.text; font.pixelSize: Theme.fontSmall; Layout.fillWidth: true; elide: Text.ElideRight }
                Text { id: plotMessage; color: Theme.bad; font.pixelSize: Theme.fontSmall; visible: text !== "" }
                Row {
                    spacing: 6
                    StatusDot { status: plot.status }
                    Text { text: Theme.statusText(plot.status) + "  " + plot.errorString; color: Theme.textDim; font.pixelSize: Theme.fontSmall }
                }
            }
            ColumnLayout {
                anchors.fill: parent
                visible: rightPages.currentIndex === 1
                FrameTraceModel { id: frames; active: rightPages.currentIndex === 1 && tab.visible }
                RowLayout {
                    TouchField { placeholderText: "ID"; Layout.preferredWidth: 110; pixelSize: Theme.fontSmall; onTextChanged: frames.idFilter = text }
                    TouchField { placeholderText: "PGN"; Layout.preferredWidth: 110; pixelSize: Theme.fontSmall; onTextChanged: frames.pgnFilter = text }
                    TouchField { placeholderText: "node"; Layout.fillWidth: true; pixelSize: Theme.fontSmall; onTextChanged: frames.nodeFilter = text }
                }
                RowLayout {
                    TouchButton { text: frames.paused ? "Resume" : "Pause"; onClicked: frames.paused = !frames.paused }
                    CheckBox { id: decodedBox; text: "decoded"; checked: true }
                    Text { text: frames.framesPerSecond.toFixed(0) + " frames/s"; color: Theme.textDim; font.pixelSize: Theme.fontSmall }
                }
                ListView {
                    id: frameView
                    Layout.fillWidth: true
                    Layout.fillHeight: true
                    clip: true
                    model: frames
                    delegate: Column {
                        width: frameView.width
                        Text {
                            text: direction + " " + frameId + " [" + bytes + "] " + message
                            color: direction === "Tx" ? Theme.accent : Theme.text
                            font.pixelSize: 11; font.family: "monospace"; width: parent.width; elide: Text.ElideRight
                        }
                        Text { text: decoded; visible: decodedBox.checked && decoded !== ""; color: Theme.textDim; font.pixelSize: 10; width: parent.width; elide: Text.ElideRight }
                    }
                }
                Row {
                    spacing: 6
                    StatusDot { status: frames.status }
                    Text { text: Theme.statusText(frames.status) + "  " + frames.errorString; color: Theme.textDim; font.pixelSize: Theme.fontSmall; width: 300; elide: Text.ElideRight }
                }
            }
        }
    }
}
