#!/usr/bin/python3
"""Checks of the HTML trace report as headless chromium showed it (report_browser_test.sh).

  check_screenshot.py layout DOM.html
      prints the page height from the report's <pre id="chart-layout"> (chromium --dump-dom)
  check_screenshot.py pixels DOM.html SHOT.png --expect ID[,ID...]
      every expected chart is in the layout once, lies inside the screenshot, and drew
      something: over 0.5 % of its area differs from the page background, and over 0.1 %
      is saturated colour (the data: axes, grid and text are grey)
  check_screenshot.py zoom DOM.html T0 T1
      the DOM of report.html#view=T0,T1: every time chart (svg.tsvg) shows the range
      T0..T1: its x ticks lie inside it and its zoom groups are stretched by the ratio
      of its full range to T1 - T0
  check_screenshot.py netlog NETLOG.json [--expect-page-requests]
      no request of the document to an http/https/ws/wss URL in chromium's net log; the
      browser's own background requests (component updater: initiator "not an origin",
      network isolation key "null null") are listed but not counted. With
      --expect-page-requests the check passes only when it finds some (the control page).

Exit 0: passed, 1: failed (with the reasons on stdout), 2: unreadable input.
Needs PIL (Debian python3-pil) for `pixels` only.
"""
import html
import json
import re
import sys

BACKGROUND_SHARE = 0.005  # of the chart area differing from the page background
COLOUR_SHARE = 0.001      # of the chart area in saturated colour
CHANNEL_TOLERANCE = 16
SATURATION = 60           # max - min channel of a "coloured" pixel
NETWORK_SCHEMES = ("http:", "https:", "ws:", "wss:")


def read_layout(dom_path):
    with open(dom_path, encoding="utf-8") as dom:
        text = dom.read()
    match = re.search(r'<pre id="chart-layout"[^>]*>(.*?)</pre>', text, re.S)
    if not match or not match.group(1).strip():
        print(f"{dom_path}: no chart layout: the report's script did not run")
        sys.exit(1)
    return json.loads(html.unescape(match.group(1)))


def check_pixels(dom_path, shot_path, expected):
    from PIL import Image  # only this check needs PIL

    layout = read_layout(dom_path)
    image = Image.open(shot_path).convert("RGB")
    width, height = image.size
    pixels = image.load()
    background = pixels[2, 2]  # the body's margin
    failures = []
    ids = [chart["id"] for chart in layout["charts"]]
    for wanted in expected:
        if ids.count(wanted) != 1:
            failures.append(f"chart {wanted!r} appears {ids.count(wanted)} times in the layout (want 1)")
    for chart in layout["charts"]:
        x0, y0, w, h = chart["x"], chart["y"], chart["w"], chart["h"]
        name = f"chart {chart['id']!r} at {x0},{y0} {w}x{h}"
        if w < 100 or h < 60:
            failures.append(f"{name}: too small")
            continue
        if x0 < 0 or y0 < 0 or x0 + w > width or y0 + h > height:
            failures.append(f"{name}: not inside the {width}x{height} screenshot")
            continue
        differing = coloured = 0
        for y in range(y0, y0 + h):
            for x in range(x0, x0 + w):
                r, g, b = pixels[x, y]
                if max(abs(r - background[0]), abs(g - background[1]), abs(b - background[2])) > CHANNEL_TOLERANCE:
                    differing += 1
                if max(r, g, b) - min(r, g, b) > SATURATION:
                    coloured += 1
        area = w * h
        print(f"{name}: {100 * differing / area:.2f} % drawn, {100 * coloured / area:.2f} % in colour")
        if differing <= BACKGROUND_SHARE * area:
            failures.append(f"{name}: only {differing} of {area} pixels differ from the background")
        if coloured <= COLOUR_SHARE * area:
            failures.append(f"{name}: only {coloured} of {area} pixels in colour: no data drawn")
    return failures


def check_zoom(dom_path, t0, t1):
    with open(dom_path, encoding="utf-8") as dom:
        text = dom.read()
    failures = []
    charts = re.findall(r'<svg class="tsvg"(.*?)</svg>', text, re.S)
    if not charts:
        return ["no time chart (svg.tsvg) in the DOM"]
    for chart in charts:
        name = re.search(r'id="([^"]*)"', chart).group(1)
        full0 = float(re.search(r'data-t0="([^"]*)"', chart).group(1))
        full1 = float(re.search(r'data-t1="([^"]*)"', chart).group(1))
        axis = re.search(r'<g class="xa"[^>]*>(.*?)</g>', chart, re.S).group(1)
        ticks = [float(value) for value in re.findall(r"<text[^>]*>([^<]*)</text>", axis)]
        if len(ticks) < 2 or min(ticks) < t0 - 1e-9 or max(ticks) > t1 + 1e-9:
            failures.append(f"chart {name!r}: x ticks {ticks} not inside {t0}..{t1}")
        stretch = (full1 - full0) / (t1 - t0)
        stretches = re.findall(r'<g class="zx" transform="matrix\(([^ ]+) ', chart)
        if not stretches:
            failures.append(f"chart {name!r}: no zoom transform")
        for matrix in stretches:
            if abs(float(matrix) - stretch) > stretch * 0.01:
                failures.append(f"chart {name!r}: zoom group stretched by {matrix}, want {stretch}")
        print(f"chart {name!r}: ticks {ticks[0]}..{ticks[-1]}")
    return failures


def check_netlog(netlog_path, expect_page_requests):
    try:
        with open(netlog_path, encoding="utf-8") as log:
            text = log.read()
        try:
            netlog = json.loads(text)
        except json.JSONDecodeError:
            # chromium killed before it closed the log: the events so far
            netlog = json.loads(text.rstrip().rstrip(",") + "]}")
    except (OSError, ValueError) as error:
        print(f"{netlog_path}: unreadable net log: {error}")
        sys.exit(2)
    types = {value: key for key, value in netlog["constants"]["logEventTypes"].items()}
    requests = {}
    for event in netlog.get("events", []):
        if types.get(event.get("type")) != "URL_REQUEST_START_JOB":
            continue
        params = event.get("params", {})
        url = params.get("url", "")
        if url.lower().startswith(NETWORK_SCHEMES):
            requests[event["source"]["id"]] = params
    page, background = [], []
    for params in requests.values():
        internal = params.get("initiator") == "not an origin" and params.get("network_isolation_key") == "null null"
        (background if internal else page).append(params["url"])
    for url in sorted(background):
        print(f"browser background request, not the document's: {url[:100]}")
    for url in sorted(page):
        print(f"request of the document: {url[:200]}")
    if expect_page_requests:
        return [] if page else ["the control page's requests were not found in the net log"]
    return [f"the document requested {url[:200]}" for url in page]


def main(argv):
    if len(argv) < 3 or argv[1] not in ("layout", "pixels", "zoom", "netlog"):
        print(__doc__)
        return 2
    mode = argv[1]
    if mode == "layout":
        print(read_layout(argv[2])["page"]["h"])
        return 0
    if mode == "pixels":
        if len(argv) != 6 or argv[4] != "--expect":
            print(__doc__)
            return 2
        failures = check_pixels(argv[2], argv[3], [name for name in argv[5].split(",") if name])
    elif mode == "zoom":
        if len(argv) != 5:
            print(__doc__)
            return 2
        failures = check_zoom(argv[2], float(argv[3]), float(argv[4]))
    else:
        failures = check_netlog(argv[2], "--expect-page-requests" in argv[3:])
    for failure in failures:
        print(f"FAIL: {failure}")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
