#!/bin/bash
# Issue 21: the HTML trace report opens offline in a real browser. Inside
# tests/harness/run_isolated.sh (private network namespace: nothing can leave), Debian's
# headless chromium
#   1. --dump-dom's the sample report (make_sample_report, with a signal named
#      "<script>alert(1)</script>"): the report's script ran and wrote the chart layout,
#      the name stayed text (one <script> element in the document);
#      with #view=300,320 every time chart shows 300..320 s (the zoom code ran);
#   2. takes a --screenshot at the same window size with --log-net-log: every chart drew
#      (check_screenshot.py pixels) and the document requested no http/https/ws URL
#      (check_screenshot.py netlog); the pixel check must fail on a blank image;
#   3. loads a control page that does fetch http:// and ws:// URLs: the net log check must
#      see them (so step 2 can fail).
# SKIPPED (exit 77) without chromium or PIL. The screenshot stays in $OPENVCU_REPORT_WORK.
#
#   OPENVCU_MAKE_SAMPLE_REPORT=build/tests/tools/report/make_sample_report \
#   OPENVCU_REPORT_WORK=build/tests/tools/report/browser \
#   tests/harness/run_isolated.sh -- tests/tools/report/report_browser_test.sh
set -uo pipefail
here=$(cd "$(dirname "$0")" && pwd)
python=/usr/bin/python3
chromium=${CHROMIUM:-/usr/bin/chromium}
checker="$here/check_screenshot.py"
width=1400
height=5000
max_height=16000
expected_charts="bus-load,node-rate,cycle-compare,cycle-difference,signals-1,signals-2,signals-3,signals-4,dtc-timeline,event-lanes"

skip() { echo "report_browser_test: SKIPPED: $*"; exit 77; }
fail() { echo "report_browser_test: FAIL: $*"; exit 1; }

[ -x "$chromium" ] || skip "no chromium at $chromium (Debian: apt install chromium)"
[ -x "$python" ] && "$python" -c 'import PIL' 2>/dev/null || skip "no PIL for $python (Debian: apt install python3-pil)"
[ -n "${OPENVCU_MAKE_SAMPLE_REPORT:-}" ] && [ -n "${OPENVCU_REPORT_WORK:-}" ] ||
  fail "set OPENVCU_MAKE_SAMPLE_REPORT and OPENVCU_REPORT_WORK (see the top of this file)"
[ "${OPENVCU_ISOLATED:-}" = 1 ] || fail "run me inside tests/harness/run_isolated.sh: chromium must not reach the network"

work=$OPENVCU_REPORT_WORK
rm -rf "$work"
mkdir -p "$work/home"
work=$(cd "$work" && pwd)
export HOME="$work/home" XDG_CONFIG_HOME="$work/home/.config" XDG_CACHE_HOME="$work/home/.cache"

"$OPENVCU_MAKE_SAMPLE_REPORT" "$work/report.html" --signal-name '<script>alert(1)</script>' ||
  fail "make_sample_report failed"

# The browser quiet: no first-run, sync, translate, network time or spell-check requests
# (the component updater still asks; the net log check tells its requests apart).
browser() {
  local size=$1
  shift
  timeout 30 "$chromium" --headless --no-sandbox --disable-gpu --hide-scrollbars --force-device-scale-factor=1 \
    --window-size="$size" --user-data-dir="$work/profile" --no-first-run --no-default-browser-check \
    --disable-background-networking --disable-component-update --disable-sync --disable-default-apps \
    --disable-extensions --disable-domain-reliability --disable-breakpad --disable-spell-checking \
    --disable-client-side-phishing-detection --metrics-recording-only --no-pings \
    --disable-features=Translate,OptimizationHints,MediaRouter,NetworkTimeServiceQuerying,AutofillServerCommunication \
    "$@" 2>>"$work/chromium.err"
}

# 1. the DOM after the script ran; a page taller than the window gets a taller window
# (the layout depends on the width only)
browser "$width,$height" --dump-dom "file://$work/report.html" >"$work/dom.html" || fail "chromium --dump-dom failed (see $work/chromium.err)"
page_height=$("$python" "$checker" layout "$work/dom.html") || fail "no chart layout in the DOM ($work/dom.html)"
if [ "$page_height" -gt "$height" ]; then
  height=$((page_height + 50 > max_height ? max_height : page_height + 50))
  echo "the page is $page_height px high: window $width x $height"
  browser "$width,$height" --dump-dom "file://$work/report.html" >"$work/dom.html" || fail "chromium --dump-dom failed"
fi
scripts=$(grep -o '<script' "$work/dom.html" | wc -l)
[ "$scripts" -eq 1 ] || fail "$scripts <script> elements in the DOM (want the report's one): a signal name was not escaped"
grep -q '&lt;script&gt;alert(1)&lt;/script&gt;' "$work/dom.html" || fail "the signal named <script>alert(1)</script> is not shown as text"

# 1b. the script's zoom: report.html#view=300,320 opens on that range in every time chart
browser "$width,$height" --dump-dom "file://$work/report.html#view=300,320" >"$work/dom-zoomed.html" ||
  fail "chromium --dump-dom of the zoomed report failed"
"$python" "$checker" zoom "$work/dom-zoomed.html" 300 320 || fail "the time charts did not zoom to 300..320 s"

# 2. the screenshot and the net log
browser "$width,$height" --log-net-log="$work/netlog.json" --screenshot="$work/shot.png" "file://$work/report.html" >/dev/null ||
  fail "chromium --screenshot failed (see $work/chromium.err)"
[ -s "$work/shot.png" ] || fail "no screenshot"
echo "screenshot: $work/shot.png"
"$python" "$checker" pixels "$work/dom.html" "$work/shot.png" --expect "$expected_charts" || fail "a chart drew nothing (see $work/shot.png)"
"$python" "$checker" netlog "$work/netlog.json" || fail "the report fetched something (see $work/netlog.json)"
# the pixel check fails on a blank page of the same size (so it can fail)
"$python" -c "from PIL import Image; Image.new('RGB', ($width, $height), 'white').save('$work/blank.png')" ||
  fail "cannot write the blank control image"
"$python" "$checker" pixels "$work/dom.html" "$work/blank.png" --expect "$expected_charts" >/dev/null &&
  fail "the pixel check passed a blank screenshot: it cannot catch a chart that draws nothing"

# 3. the control: a page that fetches is caught by the same net log check
cat >"$work/control.html" <<'EOF'
<!DOCTYPE html><html><head><meta charset="utf-8"><title>control</title></head><body>
<img src="http://127.0.0.1:9/pixel.png" alt=""><script>try { new WebSocket('ws://127.0.0.1:9/x'); } catch (e) {}</script>
</body></html>
EOF
browser "$width,800" --log-net-log="$work/control-netlog.json" --dump-dom "file://$work/control.html" >/dev/null ||
  fail "chromium failed on the control page"
"$python" "$checker" netlog "$work/control-netlog.json" --expect-page-requests >/dev/null ||
  fail "the net log check did not see the control page's requests: it cannot catch a report that fetches"
echo "report_browser_test: PASS"
