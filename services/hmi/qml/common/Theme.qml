pragma Singleton
import QtQuick

// Colours and sizes of the touchscreen (dark, high contrast, 48 px touch targets).
QtObject {
    readonly property color background: "#101418"
    readonly property color panel: "#1c232b"
    readonly property color panelLight: "#27313b"
    readonly property color text: "#e8edf2"
    readonly property color textDim: "#8d9aa6"
    readonly property color good: "#43a047"
    readonly property color bad: "#e53935"
    readonly property color warn: "#fb8c00"
    readonly property color accent: "#1e88e5"
    readonly property int touch: 48
    readonly property int font: 16
    readonly property int fontSmall: 13
    readonly property int fontLarge: 22

    // ModelStatus: Ready 0, Stale 1, NotConnected 2, Error 3
    function statusColor(status) {
        return status === 0 ? good : status === 1 ? warn : status === 2 ? textDim : bad
    }
    function statusText(status) {
        return ["Ready", "Stale", "Not connected", "Error"][status] || "?"
    }
    // tone of a value text: 0 neutral, 1 good, 2 bad
    function toneColor(tone) {
        return tone === 1 ? good : tone === 2 ? bad : text
    }
}
