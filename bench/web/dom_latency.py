#!/usr/bin/python3
"""Table change -> browser DOM latency of vcu-web's live page, in a real headless Chromium
(bench/web/run_web_bench.sh; docs/benchmarks.md "## vcu-web"). Needs Debian's
python3-selenium and chromium-driver (scripts/install-deps.sh installs both).

  dom_latency.py --url http://127.0.0.1:8080 --signals K1,K2,... [--samples 500]
                 [--max-seconds 240] [--mode auto|page|inject] [--screenshot FILE]

Before any script of the page runs, a hook (Page.addScriptToEvaluateOnNewDocument) wraps the
page's EventSource: every `update` event is parsed once more by a listener registered before
the page's own, which keeps the event's "t" (server wall clock at send) and each signal's
"ageMs", plus Date.now() at arrival. A MutationObserver on the DOM element that shows a
signal's value then takes, for every change of that element's text:
  writeMs = t - ageMs   (the wall-clock time the value was written to the signal table)
  domMs   = Date.now() in the observer's callback (right after the text changed in the DOM)
  frameMs = Date.now() in the next requestAnimationFrame (the frame that paints it)
and the latency is domMs - writeMs (also reported: arrival - writeMs and frameMs - writeMs).
Server and browser run on one machine, so both clocks are the same wall clock (1 ms steps).

--mode page (auto when services/web/www's page shows the picks table): the real page at /,
the picks put into its localStorage (`openvcu.picks.<instance>`), each signal's
`tr[data-key=KEY] td.value` observed: vcu-web's push path + the page's own parse and render.
--mode inject (auto otherwise): the bench's own EventSource on the page's origin sets a
<div>'s text per signal: vcu-web's push path + the browser's parse and one textContent.

Prints a few lines and ends with one line
  DOM samples=N p50_ms=.. p99_ms=.. max_ms=.. arrival_p50_ms=.. arrival_p99_ms=.. frame_p50_ms=.. frame_p99_ms=.. mode=page|inject
"""

import argparse
import json
import math
import sys
import time
import urllib.request

HOOK = r"""
(() => {
  const bench = window.__bench = {last: null, events: 0, samples: []};
  const Original = window.EventSource;
  if (!Original || Original.__benchHooked) return;
  class HookedEventSource extends Original {
    constructor(url, init) {
      super(url, init);
      // registered before anyone else's listener, so it runs first for every event
      this.addEventListener('update', (event) => {
        const arrival = Date.now();
        try {
          const data = JSON.parse(event.data);
          const signals = new Map();
          for (const s of data.signals || []) signals.set(s.key, s);
          bench.last = {t: data.t, arrival, signals};
          bench.events += 1;
        } catch (e) { /* the page counts bad events itself */ }
      });
    }
  }
  HookedEventSource.__benchHooked = true;
  window.EventSource = HookedEventSource;
})();
"""

# Observes value elements: arguments[0] = [[key, element], ...]
OBSERVE = r"""
const bench = window.__bench;
for (const [key, element] of arguments[0]) {
  const observer = new MutationObserver(() => {
    const dom = Date.now();
    const last = bench.last;
    const signal = last && last.signals.get(key);
    if (!signal || typeof signal.ageMs !== 'number' || typeof last.t !== 'number') return;
    const sample = {key, write: last.t - signal.ageMs, arrival: last.arrival, dom, frame: null,
                    text: element.textContent};
    bench.samples.push(sample);
    requestAnimationFrame(() => { sample.frame = Date.now(); });
  });
  observer.observe(element, {childList: true, characterData: true, subtree: true});
}
"""

# The bench's own view (mode inject): one EventSource, one <div> per key.
INJECT = r"""
const keys = arguments[0];
document.body.textContent = '';
const elements = [];
for (const key of keys) {
  const div = document.createElement('div');
  div.dataset.key = key;
  document.body.appendChild(div);
  elements.push([key, div]);
}
const source = new EventSource('/api/live?signals=' + encodeURIComponent(keys.join(',')));
source.addEventListener('update', (event) => {
  const data = JSON.parse(event.data);
  for (const s of data.signals || []) {
    const div = document.querySelector(`div[data-key="${CSS.escape(s.key)}"]`);
    const text = s.value === null ? '-' : (s.text || String(s.value));
    if (div && div.textContent !== text) div.textContent = text;
  }
});
return elements;
"""


def percentile(values, fraction):
    """Nearest rank: the smallest value with at least `fraction` of the samples at or below it."""
    ordered = sorted(values)
    if not ordered:
        return float("nan")
    rank = max(1, math.ceil(fraction * len(ordered)))
    return ordered[rank - 1]


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--url", required=True, help="http://127.0.0.1:PORT")
    parser.add_argument("--signals", required=True, help="K1,K2,... (catalog keys)")
    parser.add_argument("--samples", type=int, default=500, help="stop after this many DOM changes")
    parser.add_argument("--max-seconds", type=float, default=240.0, help="stop after this long in any case")
    parser.add_argument("--mode", choices=("auto", "page", "inject"), default="auto")
    parser.add_argument("--screenshot", help="save the page as PNG at the end")
    args = parser.parse_args()
    keys = [key for key in args.signals.split(",") if key]
    base = args.url.rstrip("/")

    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service
    from selenium.webdriver.common.by import By

    with urllib.request.urlopen(base + "/api/info", timeout=10) as answer:
        info = json.load(answer)
    options = webdriver.ChromeOptions()
    for flag in ("--headless=new", "--no-sandbox", "--disable-gpu", "--window-size=1280,900"):
        options.add_argument(flag)
    driver = webdriver.Chrome(service=Service(executable_path="/usr/bin/chromedriver"), options=options)
    try:
        driver.execute_cdp_cmd("Page.addScriptToEvaluateOnNewDocument", {"source": HOOK})
        mode = args.mode
        elements = None
        if mode in ("auto", "page"):
            driver.get(base + "/")
            picks = json.dumps({"keys": keys, "plotted": keys[: int(info.get("maxPlotted", 4))]})
            driver.execute_script("localStorage.setItem(arguments[0], arguments[1]);",
                                  f"openvcu.picks.{info.get('instance') or ''}", picks)
            driver.get(base + "/")
            deadline = time.monotonic() + 15
            while time.monotonic() < deadline:
                found = [driver.find_elements(By.CSS_SELECTOR, f'tr[data-key="{key}"] td.value') for key in keys]
                if all(found):
                    elements = [[key, cells[0]] for key, cells in zip(keys, found)]
                    break
                time.sleep(0.25)
            if elements is None:
                if mode == "page":
                    raise SystemExit("dom_latency.py: the page shows no picks table row for every key "
                                     "(tr[data-key=KEY] td.value) within 15 s")
                print("the page at / shows no picks table: measuring the bench's own view (mode inject)")
            else:
                mode = "page"
                # the rows start empty; the first event fills them (not a change of a value)
                time.sleep(2)
        if elements is None:
            mode = "inject"
            driver.get(base + "/api/info")
            elements = driver.execute_script(INJECT, keys)
            time.sleep(2)
        driver.execute_script(OBSERVE, elements)
        started = time.monotonic()
        count = 0
        while time.monotonic() - started < args.max_seconds:
            time.sleep(2)
            count = driver.execute_script("return window.__bench.samples.length;")
            if count >= args.samples:
                break
        time.sleep(0.1)  # the last sample's animation frame
        samples = driver.execute_script(
            "return window.__bench.samples.map(s => [s.key, s.write, s.arrival, s.dom, s.frame]);")
        events = driver.execute_script("return window.__bench.events;")
        elapsed = time.monotonic() - started
        if args.screenshot:
            driver.save_screenshot(args.screenshot)
    finally:
        driver.quit()

    dom = [s[3] - s[1] for s in samples]
    arrival = [s[2] - s[1] for s in samples]
    frame = [s[4] - s[1] for s in samples if s[4] is not None]
    per_key = {key: sum(1 for s in samples if s[0] == key) for key in keys}
    print(f"mode {mode}: {len(samples)} DOM changes in {elapsed:.0f} s ({events} update events"
          f" reached the page); per signal: " + ", ".join(f"{k} {n}" for k, n in per_key.items()))
    if not samples:
        print("DOM samples=0 mode=" + mode)
        return 1
    fmt = lambda v: f"{v:.0f}" if not math.isnan(v) else "nan"
    print(f"table write -> DOM text:   p50 {fmt(percentile(dom, .5))} ms, p99 {fmt(percentile(dom, .99))} ms,"
          f" max {max(dom)} ms, min {min(dom)} ms")
    print(f"table write -> event at the page: p50 {fmt(percentile(arrival, .5))} ms,"
          f" p99 {fmt(percentile(arrival, .99))} ms, max {max(arrival)} ms")
    if frame:
        print(f"table write -> next animation frame: p50 {fmt(percentile(frame, .5))} ms,"
              f" p99 {fmt(percentile(frame, .99))} ms, max {max(frame)} ms")
    print(f"DOM samples={len(samples)} p50_ms={fmt(percentile(dom, .5))} p99_ms={fmt(percentile(dom, .99))}"
          f" max_ms={max(dom)} arrival_p50_ms={fmt(percentile(arrival, .5))} arrival_p99_ms={fmt(percentile(arrival, .99))}"
          f" frame_p50_ms={fmt(percentile(frame, .5))} frame_p99_ms={fmt(percentile(frame, .99))} mode={mode}")
    return 0 if len(samples) >= args.samples else 2


if __name__ == "__main__":
    sys.exit(main())
