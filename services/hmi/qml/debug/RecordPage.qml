import QtQuick
import QtQuick.Controls
import QtQuick.Layouts
import OpenVcu.Models
import OpenVcu.Hmi

// Record (issue 21, the thesis' dashboard "data logging"): `vcu record` into the data
// folder (DATA/recordings/<yyyyMMdd-hhmmss>) until Stop, then Analyse opens the recorded
// *.log files in the Trace tab (signals and statistics).
ColumnLayout {
    id: page
    /// Asks the window to open `logs` in the Trace tab.
    signal analyse(var logs)
    spacing: 8
    RecordController { id: recorder }

    RowLayout {
        spacing: 12
        TouchButton {
            objectName: "recordButton"
            text: recorder.state === RecordController.Idle ? "● Record"
                  : recorder.state === RecordController.Stopping ? "Stopping…" : "■ Stop"
            tint: recorder.active ? Theme.bad : Theme.panelLight
            enabled: recorder.state !== RecordController.Stopping
            implicitWidth: 160
            onClicked: recorder.active ? recorder.stop() : recorder.start()
        }
        ColumnLayout {
            Layout.fillWidth: true
            Text {
                objectName: "recordState"
                text: recorder.state === RecordController.Idle ? "not recording"
                      : recorder.state === RecordController.Starting ? "starting vcu record…"
                      : recorder.state === RecordController.Recording ? "recording  " + recorder.elapsedText
                      : "stopping  " + recorder.elapsedText
                color: recorder.state === RecordController.Recording ? Theme.bad : Theme.text
                font.pixelSize: Theme.fontLarge
            }
            Text {
                text: recorder.folder !== "" ? recorder.folder : "into " + browser.dataFolder + "/recordings/<date-time>"
                color: Theme.textDim; font.pixelSize: Theme.fontSmall; elide: Text.ElideLeft; Layout.fillWidth: true
            }
        }
        TouchButton {
            objectName: "analyseButton"
            text: "Analyse"
            visible: recorder.recordedLogs.length > 0 && !recorder.active
            onClicked: page.analyse(recorder.recordedLogs)
        }
    }
    FileBrowserModel { id: browser }  // only its data folder
    Text {
        objectName: "recordResult"
        Layout.fillWidth: true
        Layout.fillHeight: true
        text: recorder.lastResult
        color: recorder.status === ModelStatus.Error ? Theme.bad : Theme.textDim
        font.pixelSize: Theme.fontSmall; font.family: "monospace"
        wrapMode: Text.Wrap; elide: Text.ElideRight
        verticalAlignment: Text.AlignTop
    }
}
