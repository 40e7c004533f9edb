import QtQuick
import QtCharts

// Qt Charts variant of the live plot: 4 line series, one point each per 60 Hz tick
// (synthetic data), a 30 s window scrolling. Compared with SignalPlot in bench_hmi_plots.
Item {
    width: 720
    height: 600
    property int windowPoints: 30 * 60
    property real t: 0
    ChartView {
        id: chart
        anchors.fill: parent
        antialiasing: false
        legend.visible: false
        ValueAxis { id: axisX; min: 0; max: 30 }
        ValueAxis { id: axisY; min: -1.5; max: 1.5 }
        LineSeries { id: s0; axisX: axisX; axisY: axisY; useOpenGL: false }
        LineSeries { id: s1; axisX: axisX; axisY: axisY }
        LineSeries { id: s2; axisX: axisX; axisY: axisY }
        LineSeries { id: s3; axisX: axisX; axisY: axisY }
    }
    Timer {
        interval: 16
        repeat: true
        running: true
        onTriggered: {
            t += 1 / 60
            const series = [s0, s1, s2, s3]
            for (let i = 0; i < 4; ++i) {
                series[i].append(t, Math.sin(t * (i + 1)) + 0.1 * Math.random())
                if (series[i].count > windowPoints) series[i].remove(0)
            }
            axisX.min = Math.max(0, t - 30)
            axisX.max = Math.max(30, t)
        }
    }
}
