import QtQuick
import OpenVcu.Hmi

// The bus load over time of one bus (TraceStatsModel.buses[i].series: points (s, %), one
// per bucket of bucketS) as a line on a 0..max % scale (the highest bucket rounded up to
// 10 %) with the mean as a dashed line; the axis texts in the corners.
Rectangle {
    id: plot
    property var series: []
    property real meanPct: 0
    property real peakPct: 0
    property real bucketS: 0
    color: Theme.panel
    // the scale: the peak rounded up to 10 %, at least 10 %
    readonly property real topPct: Math.max(10, Math.ceil(peakPct / 10) * 10)
    readonly property real endS: series.length > 0 ? series[series.length - 1].x : 1
    onSeriesChanged: canvas.requestPaint()
    onWidthChanged: canvas.requestPaint()
    onHeightChanged: canvas.requestPaint()
    Canvas {
        id: canvas
        objectName: "loadCanvas"
        anchors.fill: parent
        anchors.margins: 4
        onPaint: {
            const ctx = getContext("2d")
            ctx.reset()
            if (plot.series.length === 0) return
            const xOf = (s) => plot.endS > 0 ? s / plot.endS * width : 0
            const yOf = (pct) => height - Math.min(pct, plot.topPct) / plot.topPct * height
            ctx.strokeStyle = Theme.textDim
            ctx.setLineDash([4, 4])
            ctx.beginPath()
            ctx.moveTo(0, yOf(plot.meanPct))
            ctx.lineTo(width, yOf(plot.meanPct))
            ctx.stroke()
            ctx.setLineDash([])
            ctx.strokeStyle = "#42a5f5"
            ctx.lineWidth = 2
            ctx.beginPath()
            for (let i = 0; i < plot.series.length; ++i) {
                const p = plot.series[i]
                if (i === 0) ctx.moveTo(xOf(p.x), yOf(p.y))
                else ctx.lineTo(xOf(p.x), yOf(p.y))
            }
            ctx.stroke()
        }
    }
    Text { anchors.left: parent.left; anchors.top: parent.top; anchors.margins: 2; text: plot.topPct + " %"; color: Theme.textDim; font.pixelSize: 11 }
    Text { anchors.left: parent.left; anchors.bottom: parent.bottom; anchors.margins: 2; text: "0"; color: Theme.textDim; font.pixelSize: 11 }
    Text { anchors.right: parent.right; anchors.bottom: parent.bottom; anchors.margins: 2; text: plot.endS.toFixed(1) + " s"; color: Theme.textDim; font.pixelSize: 11 }
    Text { anchors.right: parent.right; anchors.top: parent.top; anchors.margins: 2; text: "per " + (plot.bucketS * 1000).toFixed(0) + " ms, mean dashed"; color: Theme.textDim; font.pixelSize: 11; visible: plot.bucketS > 0 }
}
