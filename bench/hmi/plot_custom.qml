import QtQuick
import OpenVcu.Models

// The HMI's SignalPlot on the same 4 signals, written at 60 Hz by bench_hmi_plots.
Item {
    width: 720
    height: 600
    SignalPlot {
        anchors.fill: parent
        windowSeconds: 30
        keys: benchKeys
    }
}
