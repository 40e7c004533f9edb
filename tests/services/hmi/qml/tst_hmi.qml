import QtQuick
import QtTest
import OpenVcu.Models
import OpenVcu.Hmi

// The main interactions of the HMI screens without a running stack (issue 10).
Item {
    id: root
    width: 720
    height: 600

    Component { id: vehicleTab; VehicleTab { anchors.fill: parent } }
    Component { id: dashboardTab; DashboardTab { anchors.fill: parent } }
    Component { id: canTab; CanDataTab { anchors.fill: parent } }
    Component { id: setupTab; EcuSetupTab { anchors.fill: parent } }
    Component { id: debugTab; DebugTab { anchors.fill: parent } }
    Component { id: traceTab; TraceViewer { anchors.fill: parent } }
    Component { id: keypadComponent; Keypad {} }
    Component { id: scheduleComponent; ScheduleModel {} }

    /// Depth-first search for an item whose `text` property equals (or contains) `text`.
    function findText(item, text, exact) {
        if (item.text !== undefined && (exact ? item.text === text : String(item.text).indexOf(text) >= 0))
            return item
        const children = item.children !== undefined ? item.children : []
        for (let i = 0; i < children.length; ++i) {
            const found = findText(children[i], text, exact)
            if (found) return found
        }
        if (item.contentItem && item.contentItem !== item) return findText(item.contentItem, text, exact)
        return null
    }

    TestCase {
        name: "HmiScreens"
        when: windowShown

        function test_every_screen_loads() {
            for (const component of [vehicleTab, dashboardTab, canTab, setupTab, debugTab, traceTab]) {
                const screen = createTemporaryObject(component, root)
                verify(screen !== null, "a screen failed to load")
            }
        }

        function test_operator_switches_are_disabled_without_a_stack() {
            const screen = createTemporaryObject(vehicleTab, root)
            waitForRendering(screen)
            const start = findText(screen, "Start / Stop", false)
            verify(start !== null, "no Start / Stop switch")
            verify(!start.enabled, "Start must be disabled while the stack is not connected")
            verify(findText(screen, "Not connected", false) !== null, "the operator status says Not connected")
        }

        function test_dashboard_marks_values_never_received() {
            const screen = createTemporaryObject(dashboardTab, root)
            waitForRendering(screen)
            verify(findText(screen, "Pack voltage (Not connected)", true) !== null, "the voltage dial is not marked")
        }

        function test_keypad_typing_gives_the_number() {
            const keypad = createTemporaryObject(keypadComponent, root)
            let accepted = ""
            keypad.accepted.connect(function(text) { accepted = text })
            keypad.show("cycle (ms)", "")
            tryCompare(keypad, "opened", true)
            for (const key of ["5", "0", "OK"]) {
                const button = findText(keypad.contentItem, key, true)
                verify(button !== null, "no key " + key)
                mouseClick(button)
            }
            compare(accepted, "50")
        }

        function test_schedule_edits_are_checked_before_sending() {
            const schedule = createTemporaryObject(scheduleComponent, root)
            verify(schedule.rowCount() > 0)
            compare(schedule.setCycle(0, "fast"), "cycle must be a whole number of ms in 1..3600000")
            compare(schedule.setCycle(0, "20"), "")  // sent: the answer follows in lastResult
            compare(schedule.lastResult.indexOf("waiting for the answer") > 0, true)
        }

        function test_adding_a_message_picks_it_from_the_dbc_then_its_cycle() {
            const screen = createTemporaryObject(setupTab, root)
            waitForRendering(screen)
            mouseClick(findChild(screen, "addMessageButton"))
            const popup = findChild(screen, "addMessagePopup")
            tryCompare(popup, "opened", true)
            const list = findChild(popup.contentItem, "addMessageCandidates")
            verify(list.count > 10, "the DBC's other messages are offered")
            findChild(popup.contentItem, "addMessageFilter").text = "hvessd2"
            tryCompare(list, "count", 1)
            waitForRendering(list)
            const entry = findText(list.contentItem, "HVESSD2_PGN61585", true)
            verify(entry !== null, "HVESSD2_PGN61585 is not offered")
            mouseClick(entry)
            tryCompare(popup, "opened", false)
            const keypad = findChild(screen, "setupKeypad")
            tryCompare(keypad, "opened", true)
            keypad.value = ""
            for (const key of ["4", "0", "OK"]) mouseClick(findText(keypad.contentItem, key, true))
            tryVerify(() => findText(screen, "add HVESSD2_PGN61585 every 40 ms", false) !== null,
                      1000, "the ScheduleAdd was not sent")
        }

        function test_browse_lists_the_data_folder_and_a_tapped_log_opens() {
            const screen = createTemporaryObject(traceTab, root)
            waitForRendering(screen)
            mouseClick(findChild(screen, "browseButton"))
            const popup = findChild(screen, "browsePopup")
            tryCompare(popup, "opened", true)
            const list = findChild(popup.contentItem, "browseList")
            tryVerify(() => list.count >= 5, 1000, "the data folder's logs are not listed")
            waitForRendering(list)
            const entry = findText(list.contentItem, "candump_l.log", true)
            verify(entry !== null, "candump_l.log is not listed")
            mouseClick(entry)
            tryCompare(popup, "opened", false)
            tryVerify(() => findChild(screen, "traceList").count > 0, 5000, "the tapped log was not opened")
        }

        function test_the_statistics_page_computes_all_logs_of_a_folder() {
            const screen = createTemporaryObject(traceTab, root)
            waitForRendering(screen)
            mouseClick(findChild(screen, "browseButton"))
            const popup = findChild(screen, "browsePopup")
            tryCompare(popup, "opened", true)
            const all = findText(popup.contentItem, "All *.log", true)
            verify(all !== null && all.enabled, "no 'All *.log' for the data folder")
            mouseClick(all)
            tryCompare(popup, "opened", false)
            verify(screen.paths.length >= 4, "the folder's logs were not all opened: " + screen.paths.length)
            mouseClick(findText(screen, "Statistics", true))
            const messages = findChild(screen, "messageTable")
            tryVerify(() => messages.count > 0, 10000, "no message statistics")
            verify(findChild(screen, "nodeTable").count > 0, "no node statistics")
            verify(findChild(screen, "loadPlot").visible, "no bus load plot")
            verify(findChild(screen, "statsSummary").text.indexOf("frames in") >= 0, findChild(screen, "statsSummary").text)
            // candump_malformed.log: the skipped lines are said, with file:line
            verify(findChild(screen, "statsError").text.indexOf("malformed") >= 0, findChild(screen, "statsError").text)
        }

        function test_the_debug_tab_lists_the_configured_j1939_bus_before_can_tx_reports_it() {
            const screen = createTemporaryObject(debugTab, root)
            waitForRendering(screen)
            mouseClick(findText(screen, "J1939", true))
            const list = findChild(screen, "j1939List")
            verify(list !== null && list.visible, "no J1939 page")
            tryCompare(list, "count", 1)  // HHEA: the vehicle bus has a "j1939" object
            waitForRendering(list)
            verify(findText(list.contentItem, "bus vehicle", true) !== null, "the vehicle bus is not listed")
            verify(findText(list.contentItem, "not heard from vcu-can-tx yet", false) !== null, "not marked as not heard")
        }

        function test_the_debug_tab_offers_record_and_names_the_data_folder() {
            const screen = createTemporaryObject(debugTab, root)
            waitForRendering(screen)
            mouseClick(findText(screen, "Record", true))
            const button = findChild(screen, "recordButton")
            verify(button !== null && button.visible, "no Record button")
            compare(button.text, "● Record")
            compare(findChild(screen, "recordState").text, "not recording")
            verify(findText(screen, "/recordings/<date-time>", false) !== null, "the target folder is not shown")
            verify(!findChild(screen, "analyseButton").visible, "Analyse before any recording")
        }

        function test_the_on_screen_keyboard_types_a_search() {
            const screen = createTemporaryObject(canTab, root)
            waitForRendering(screen)
            const search = findChild(screen, "signalSearch")
            verify(search !== null)
            mouseClick(findChild(search, "keyboardButton"))
            const keyboard = findChild(search, "textKeyboard")
            verify(keyboard !== null, "no keyboard")
            tryCompare(keyboard, "opened", true)
            for (const key of ["h", "s", "_", "u", "l", "v"]) {
                const button = findText(keyboard.contentItem, key, true)
                verify(button !== null, "no key " + key)
                mouseClick(button)
            }
            mouseClick(findText(keyboard.contentItem, "⌫", true))
            mouseClick(findText(keyboard.contentItem, "OK", true))
            tryCompare(keyboard, "opened", false)
            compare(search.text, "hs_ul")
        }

        function test_tapping_a_signal_in_the_tree_plots_it() {
            const screen = createTemporaryObject(canTab, root)
            waitForRendering(screen)
            const plot = findChild(screen, "plot")
            verify(plot !== null)
            compare(plot.keys.length, 0)
            compare(plot.toggleKey("VIC.HVESSD1_PGN61584.HS_ULvl"), "")
            compare(plot.keys.length, 1)
            compare(plot.legend.length, 1)
        }
    }
}
