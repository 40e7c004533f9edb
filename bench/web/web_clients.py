#!/usr/bin/python3
"""Live-page clients for the vcu-web benchmark (bench/web/run_web_bench.sh; docs/benchmarks.md
"## vcu-web"). Python 3 standard library only.

  web_clients.py catalog --url http://127.0.0.1:8080 --signals K1,K2,...
      exits 0 when every key is in GET /api/catalog, else names the missing ones (exit 1)
  web_clients.py streams --url http://127.0.0.1:8080 --signals K1,K2,... --clients 10
                         [--ready-file F] [--max-seconds 300]
      opens N GET /api/live?signals=... streams, each read by its own thread as a browser's
      EventSource reads it (text/event-stream, events split on blank lines, every `update`
      parsed as JSON). Touches --ready-file once every stream has delivered its first
      `update`; counts from then until SIGTERM/SIGINT (or --max-seconds), then prints one
      JSON object: per client the events, events/s, per signal how many events a second
      carried a new value, how often a picked signal was not "Ready"; the streams that
      failed and why.

Example (inside the bench): start `streams ... --ready-file r &`, wait for r, measure the
server over a window, `kill -TERM` the client, read its JSON from stdout.
"""

import argparse
import http.client
import json
import signal
import sys
import threading
import time
import urllib.parse


def parse_url(url):
    parts = urllib.parse.urlsplit(url)
    if parts.scheme != "http" or not parts.hostname:
        raise SystemExit(f"web_clients.py: --url {url}: expected http://HOST:PORT")
    return parts.hostname, parts.port or 80


def get_json(host, port, path, timeout=10.0):
    connection = http.client.HTTPConnection(host, port, timeout=timeout)
    try:
        connection.request("GET", path)
        response = connection.getresponse()
        body = response.read()
        if response.status != 200:
            raise RuntimeError(f"GET {path}: HTTP {response.status}: {body[:200]!r}")
        return json.loads(body)
    finally:
        connection.close()


def command_catalog(args):
    host, port = parse_url(args.url)
    catalog = get_json(host, port, "/api/catalog")
    known = {entry.get("key") for entry in catalog.get("signals", [])}
    wanted = [key for key in args.signals.split(",") if key]
    missing = [key for key in wanted if key not in known]
    if missing:
        print(f"not in /api/catalog ({len(known)} signals): {', '.join(missing)}", file=sys.stderr)
        return 1
    print(f"catalog: {len(known)} signals, all {len(wanted)} picked keys present")
    return 0


class LiveClient(threading.Thread):
    """One live page: a GET /api/live stream read line by line until the process ends."""

    def __init__(self, index, host, port, path, keys, counting, on_first):
        super().__init__(daemon=True)
        self.index = index
        self.host, self.port, self.path = host, port, path
        self.keys = keys
        self.counting = counting      # threading.Event: set once every client is ready
        self.on_first = on_first      # called once, after this stream's first update
        self.lock = threading.Lock()
        self.events = 0               # update events since counting started
        self.changes = {key: 0 for key in keys}  # events carrying a value other than the last one
        self.last_value = {}
        self.bad = 0                  # events that were not JSON or lacked "signals"
        self.not_ready = 0            # picked signals seen with a status other than "Ready"
        self.error = None             # why the stream ended, if it did

    def run(self):
        try:
            connection = http.client.HTTPConnection(self.host, self.port, timeout=30)
            connection.request("GET", self.path, headers={"Accept": "text/event-stream", "Cache-Control": "no-cache"})
            response = connection.getresponse()
            kind = response.getheader("Content-Type", "")
            if response.status != 200 or not kind.startswith("text/event-stream"):
                self.error = f"HTTP {response.status} {kind}: {response.read(300)!r}"
                self.on_first(self)
                return
            event, data = "message", []
            first = True
            while True:
                line = response.fp.readline()
                if not line:
                    self.error = "the server closed the stream"
                    break
                line = line.rstrip(b"\r\n").decode("utf-8", "replace")
                if line == "":
                    if data and event == "update":
                        self.update("\n".join(data))
                        if first:
                            first = False
                            self.on_first(self)
                    event, data = "message", []
                elif line.startswith(":"):
                    continue  # comment (keep-alive)
                else:
                    name, _, value = line.partition(":")
                    value = value[1:] if value.startswith(" ") else value
                    if name == "event":
                        event = value
                    elif name == "data":
                        data.append(value)
        except Exception as error:  # a stream that fails is reported, not fatal to the others
            self.error = f"{type(error).__name__}: {error}"
        if first:
            self.on_first(self)

    def update(self, text):
        try:
            signals = json.loads(text)["signals"]
        except (ValueError, KeyError, TypeError):
            with self.lock:
                self.bad += 1
            return
        counting = self.counting.is_set()
        with self.lock:
            if counting:
                self.events += 1
            for entry in signals:
                key = entry.get("key")
                if key not in self.changes:
                    continue
                value = entry.get("value")
                if counting and entry.get("status") != "Ready":
                    self.not_ready += 1
                if key in self.last_value and self.last_value[key] != value and counting:
                    self.changes[key] += 1
                self.last_value[key] = value

    def summary(self, seconds):
        with self.lock:
            return {
                "client": self.index,
                "events": self.events,
                "eventsPerS": round(self.events / seconds, 2) if seconds > 0 else 0.0,
                "changesPerS": {key: round(n / seconds, 2) for key, n in self.changes.items()},
                "badEvents": self.bad,
                "notReady": self.not_ready,
                "error": self.error,
            }


def command_streams(args):
    host, port = parse_url(args.url)
    keys = [key for key in args.signals.split(",") if key]
    path = "/api/live?signals=" + urllib.parse.quote(",".join(keys), safe=",")
    counting = threading.Event()
    stop = threading.Event()
    pending = [args.clients]
    pending_lock = threading.Lock()
    started = {}

    def on_first(client):
        with pending_lock:
            pending[0] -= 1
            if pending[0] == 0:
                started["at"] = time.monotonic()
                counting.set()
                if args.ready_file:
                    with open(args.ready_file, "w") as ready:
                        ready.write(f"{args.clients}\n")

    clients = [LiveClient(i, host, port, path, keys, counting, on_first) for i in range(args.clients)]
    for client in clients:
        client.start()
    for name in (signal.SIGTERM, signal.SIGINT):
        signal.signal(name, lambda *_: stop.set())
    stop.wait(args.max_seconds)
    ended = time.monotonic()
    seconds = ended - started["at"] if "at" in started else 0.0
    result = {
        "clients": args.clients,
        "signals": keys,
        "seconds": round(seconds, 2),
        "ready": counting.is_set(),
        "perClient": [client.summary(seconds) for client in clients],
    }
    rates = [entry["eventsPerS"] for entry in result["perClient"]]
    result["eventsPerSMin"] = min(rates) if rates else 0.0
    result["eventsPerSMean"] = round(sum(rates) / len(rates), 2) if rates else 0.0
    result["failed"] = [entry for entry in result["perClient"] if entry["error"]]
    print(json.dumps(result), flush=True)
    return 0 if counting.is_set() and not result["failed"] else 1


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    catalog = sub.add_parser("catalog", help="check that the keys are in /api/catalog")
    streams = sub.add_parser("streams", help="hold N live streams and count their events")
    for each in (catalog, streams):
        each.add_argument("--url", required=True, help="http://127.0.0.1:PORT")
        each.add_argument("--signals", required=True, help="K1,K2,... (catalog keys)")
    streams.add_argument("--clients", type=int, default=1)
    streams.add_argument("--ready-file", help="written once every stream delivered its first update")
    streams.add_argument("--max-seconds", type=float, default=300.0, help="end by itself after this long")
    args = parser.parse_args()
    return command_catalog(args) if args.command == "catalog" else command_streams(args)


if __name__ == "__main__":
    sys.exit(main())
