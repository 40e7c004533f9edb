import QtQuick
import QtQuick.Controls
import QtQuick.Layouts
import OpenVcu.Models
import OpenVcu.Hmi

// The touchscreen: header, five tabs and the trace viewer. Designed for 720x600
// (800x480 fits; the desktop window resizes). `currentTab` is set by the screenshot mode.
ApplicationWindow {
    id: window
    property alias currentTab: tabs.currentIndex
    width: 720
    height: 600
    minimumWidth: 640
    minimumHeight: 460
    visible: true
    title: "openvcu HMI - " + Stack.instance
    color: Theme.background

    HealthModel { id: health }
    FsmModel { id: fsm }

    header: ColumnLayout {
        spacing: 0
        Header { Layout.fillWidth: true; health: health; fsm: fsm }
        Rectangle {
            Layout.fillWidth: true
            Layout.preferredHeight: visible ? 24 : 0
            color: Theme.bad
            visible: Stack.tableStatus !== ModelStatus.Ready || Stack.eventStatus !== ModelStatus.Ready
            Text {
                id: banner
                anchors.fill: parent
                anchors.leftMargin: 8
                verticalAlignment: Text.AlignVCenter
                visible: parent.visible
                color: "white"
                font.pixelSize: Theme.fontSmall
                elide: Text.ElideRight
                text: (Stack.tableStatus !== ModelStatus.Ready ? "signal table: " + Theme.statusText(Stack.tableStatus) + "  " : "")
                      + (Stack.eventStatus !== ModelStatus.Ready ? "events: " + Theme.statusText(Stack.eventStatus) + "  " : "")
                      + Stack.errorString
            }
        }
        TabBar {
            id: tabs
            Layout.fillWidth: true
            Repeater {
                model: ["Vehicle", "Dashboard", "CAN Data", "ECU Setup", "Debug", "Trace"]
                TabButton {
                    text: modelData
                    implicitHeight: Theme.touch
                    font.pixelSize: Theme.font
                }
            }
        }
    }

    // the pages as plain Items: QQuickStackLayout of Qt 6.4.2 crashed now and then when the
    // tab was switched (cachedItemSizeHints, qmlAttachedPropertiesObject)
    Item {
        anchors.fill: parent
        anchors.margins: 6
        VehicleTab { anchors.fill: parent; visible: tabs.currentIndex === 0 }
        DashboardTab { anchors.fill: parent; visible: tabs.currentIndex === 1 }
        CanDataTab {
            anchors.fill: parent
            visible: tabs.currentIndex === 2
            initialKeys: typeof initialPlotKeys !== "undefined" ? initialPlotKeys : []
            initialWindow: typeof initialPlotWindow !== "undefined" ? initialPlotWindow : 30
            initialFramesPage: typeof initialCanPageFrames !== "undefined" ? initialCanPageFrames : false
        }
        EcuSetupTab { anchors.fill: parent; visible: tabs.currentIndex === 3 }
        DebugTab {
            anchors.fill: parent
            visible: tabs.currentIndex === 4
            health: health
            fsm: fsm
            onAnalyse: (logs) => {
                tabs.currentIndex = 5
                traceViewer.openPaths(logs, logs[0].substring(0, logs[0].lastIndexOf("/")))
            }
        }
        TraceViewer {
            id: traceViewer
            objectName: "traceViewer"
            anchors.fill: parent
            visible: tabs.currentIndex === 5
            initialPath: typeof initialTracePath !== "undefined" ? initialTracePath : ""
            initialStatistics: typeof initialTraceStatistics !== "undefined" ? initialTraceStatistics : false
        }
    }
}
