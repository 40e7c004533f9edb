#!/usr/bin/python3
"""Known-answer CAN log for `vcu trace report` (issue 21, report_browser_test.sh).

  make_trace_log.py write DIR
      writes DIR/drive.log (candump -L, bus can0), DIR/drive.dbc (J1939) and DIR/facts.json
      (what the log holds, computed here from the generated frames)
  make_trace_log.py check REPORT.html DIR/facts.json
      the report of `vcu trace report` agrees with facts.json: the message table's count,
      expected cycle (GenMsgCycleTime), mean and max period, missing frames and gaps; the DTC
      table's SA, SPN, FMI, OC, raise and clear times; a "DTC raised" and a "DTC cleared"
      finding per DTC and one complete-BAM finding per BAM; the DTC timeline's lanes; the node
      table's frames per SA; the node chart's labels "0x27 Vehicle_Control_Unit" (SA first,
      uncut); a signal chart of VehicleSpeed in km/h

The log, 20 s from 1700000000.000000:
  VCU_Status  0x18FF0127 (SA 0x27) every 100 ms exactly; VehicleSpeed (km/h) ramps 0 -> 60 -> 0
  VCU_Limits  0x18FF0327 (SA 0x27) every 500 ms exactly
  VCU_Command 0x0CFF0228 (SA 0x28) every 20 ms with up to +-2 ms jitter and frames 150, 151,
              400 and 733 dropped (4 missing, 3 gaps)
  DM1 of 0x27 by BAM (TP.CM 0x1CECFF27, TP.DT 0x1CEBFF27, 2 packets 50 ms apart) every 1 s
  from 5 s to 11 s: amber lamp, 3 DTCs; from 12 s a single-frame DM1 without DTC (cleared).
Both SAs are transmitted by the DBC node Vehicle_Control_Unit: only the SA tells them apart.

Example:
  make_trace_log.py write /tmp/known && vcu trace report --dbc /tmp/known/drive.dbc \\
      /tmp/known/drive.log -o /tmp/known/report.html --signals VCU_Status.VehicleSpeed &&
  make_trace_log.py check /tmp/known/report.html /tmp/known/facts.json

Exit 0: written / passed, 1: a check failed (reasons on stdout), 2: usage or unreadable input.
Standard library only.
"""
import html.parser
import json
import os
import random
import re
import sys

START_US = 1_700_000_000_000_000
DURATION_US = 20_000_000
BUS = "can0"
NODE = "Vehicle_Control_Unit"
SPEED_FACTOR = 1 / 256  # km/h per bit
SPEED_PEAK_KMH = 60.0
DROPPED = (150, 151, 400, 733)
JITTER_US = 2000
# SPN, FMI, occurrence count: one of each size class of SPN (8, 12 and 19 bits)
DTCS = ((190, 2, 1), (3226, 4, 5), (524000, 31, 127))
DM1_PGN = 0xFECA
BAM_FIRST_US, BAM_LAST_US, CLEAR_FIRST_US = 5_000_000, 11_000_000, 12_000_000
BAM_PACKET_GAP_US = 50_000

CYCLIC = (
    # name, CAN id (extended), cycle [us]
    ("VCU_Status", 0x18FF0127, 100_000),
    ("VCU_Limits", 0x18FF0327, 500_000),
    ("VCU_Command", 0x0CFF0228, 20_000),
)


def dbc_text():
    ids = {name: can_id | 0x80000000 for name, can_id, _ in CYCLIC}
    lines = [
        'VERSION "known-answer log of tests/tools/report/make_trace_log.py"', "", "NS_ :", "", "BS_:", "",
        f"BU_: {NODE} Dashboard", "",
        f"BO_ {ids['VCU_Status']} VCU_Status: 8 {NODE}",
        ' SG_ VehicleSpeed : 0|16@1+ (0.00390625,0) [0|250.996] "km/h" Dashboard',
        ' SG_ StatusCounter : 16|8@1+ (1,0) [0|255] "" Dashboard', "",
        f"BO_ {ids['VCU_Limits']} VCU_Limits: 8 {NODE}",
        ' SG_ SpeedLimit : 0|8@1+ (1,0) [0|250] "km/h" Dashboard', "",
        f"BO_ {ids['VCU_Command']} VCU_Command: 8 {NODE}",
        ' SG_ TorqueRequest : 0|16@1+ (0.1,-1000) [-1000|1000] "Nm" Dashboard', "",
        'BA_DEF_ BO_  "GenMsgCycleTime" INT 0 65535;',
        'BA_DEF_DEF_  "GenMsgCycleTime" 0;',
    ]
    for name, _, cycle_us in CYCLIC:
        lines.append(f'BA_ "GenMsgCycleTime" BO_ {ids[name]} {cycle_us // 1000};')
    return "\n".join(lines) + "\n"


def speed_kmh(t_us):
    half = DURATION_US / 2
    return SPEED_PEAK_KMH * (t_us / half if t_us <= half else (DURATION_US - t_us) / half)


def dm1_bytes(dtcs, lamps):
    data = bytearray([lamps, 0xFF])
    for spn, fmi, oc in dtcs:
        data += bytes([spn & 0xFF, (spn >> 8) & 0xFF, ((spn >> 16) & 0x07) << 5 | fmi, oc & 0x7F])
    return bytes(data)


def generate():
    """(time [us from START], id, data) of every frame, and the facts."""
    frames = []
    rng = random.Random(21)
    facts = {"start_s": START_US / 1e6, "bus": BUS, "node": NODE, "messages": [], "dtcs": [], "nodes": {}}
    for name, can_id, cycle_us in CYCLIC:
        times = []
        for index in range(DURATION_US // cycle_us):
            t = index * cycle_us
            if name == "VCU_Command":
                if index in DROPPED:
                    continue
                t += 5_000 + rng.randint(-JITTER_US, JITTER_US)
            times.append(t)
            if name == "VCU_Status":
                raw = round(speed_kmh(t) / SPEED_FACTOR)
                data = bytes([raw & 0xFF, raw >> 8, index & 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF])
            elif name == "VCU_Limits":
                data = bytes([90, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF])
            else:
                data = bytes([0x10, 0x27, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF])
            frames.append((t, can_id, data))
        periods = [b - a for a, b in zip(times, times[1:])]
        missing = sum(round(p / cycle_us) - 1 for p in periods)
        facts["messages"].append({
            "name": name, "id": f"0x{can_id:08X}", "sa": f"0x{can_id & 0xFF:02X}", "count": len(times),
            "expected_ms": cycle_us / 1000, "mean_ms": sum(periods) / len(periods) / 1000,
            "max_ms": max(periods) / 1000, "min_ms": min(periods) / 1000, "missing": missing,
            "gaps": sum(1 for p in periods if p > 1.5 * cycle_us)})

    sa = 0x27
    payload = dm1_bytes(DTCS, 0x04)  # amber warning lamp on
    packets = (len(payload) + 6) // 7
    raised_us = None
    facts["bam"] = {"sa": f"0x{sa:02X}", "count": 0, "bytes": len(payload), "packets": packets}
    for t in range(BAM_FIRST_US, BAM_LAST_US + 1, 1_000_000):
        cm = bytes([0x20, len(payload) & 0xFF, len(payload) >> 8, packets, 0xFF,
                    DM1_PGN & 0xFF, (DM1_PGN >> 8) & 0xFF, DM1_PGN >> 16])
        frames.append((t, 0x1CECFF00 | sa, cm))
        facts["bam"]["count"] += 1
        for number in range(1, packets + 1):
            chunk = payload[(number - 1) * 7:number * 7]
            frames.append((t + number * BAM_PACKET_GAP_US, 0x1CEBFF00 | sa,
                           bytes([number]) + chunk + b"\xFF" * (7 - len(chunk))))
        if raised_us is None:
            raised_us = t + packets * BAM_PACKET_GAP_US  # the DM1 is complete with its last packet
    for t in range(CLEAR_FIRST_US, DURATION_US, 1_000_000):
        frames.append((t, 0x18FECA00 | sa, bytes([0x00, 0xFF, 0, 0, 0, 0, 0xFF, 0xFF])))
    for spn, fmi, oc in DTCS:
        facts["dtcs"].append({"sa": f"0x{sa:02X}", "spn": spn, "fmi": fmi, "oc": oc,
                              "raised_s": raised_us / 1e6, "cleared_s": CLEAR_FIRST_US / 1e6})

    frames.sort(key=lambda frame: frame[0])
    assert frames[0][0] == 0, "the first frame starts the timeline"
    for _, can_id, _ in frames:
        key = f"0x{can_id & 0xFF:02X}"
        facts["nodes"][key] = facts["nodes"].get(key, 0) + 1
    facts["signal"] = {"key": "VCU_Status.VehicleSpeed", "min": 0.0,
                       "max": max(speed_kmh(t) for t, can_id, _ in frames if can_id == CYCLIC[0][1])}
    return frames, facts


def write(folder):
    os.makedirs(folder, exist_ok=True)
    frames, facts = generate()
    with open(os.path.join(folder, "drive.log"), "w", encoding="ascii") as log:
        for t, can_id, data in frames:
            stamp = START_US + t
            log.write(f"({stamp // 1_000_000}.{stamp % 1_000_000:06d}) {BUS} {can_id:08X}#{data.hex().upper()}\n")
    with open(os.path.join(folder, "drive.dbc"), "w", encoding="ascii") as dbc:
        dbc.write(dbc_text())
    with open(os.path.join(folder, "facts.json"), "w", encoding="utf-8") as out:
        json.dump(facts, out, indent=1)
    print(f"{folder}/drive.log: {len(frames)} frames")
    return 0


class Tables(html.parser.HTMLParser):
    """Every <table> as (header cells, rows of cells); the <text> of every svg by its id (the
    drawn text: a <title> tooltip inside a <text> is left out)."""

    def __init__(self):
        super().__init__()
        self.tables = []
        self.svg_texts = {}
        self._cell = None
        self._row = None
        self._svg = None
        self._text = None
        self._title = False

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        if tag == "table":
            self.tables.append(([], []))
        elif tag == "tr":
            self._row = []
        elif tag in ("td", "th"):
            self._cell = ""
        elif tag == "svg":
            self._svg = attrs.get("id", "")
            self.svg_texts.setdefault(self._svg, [])
        elif tag == "text" and self._svg is not None:
            self._text = ""
        elif tag == "title":
            self._title = True

    def handle_endtag(self, tag):
        if tag in ("td", "th") and self._cell is not None:
            self._row.append(self._cell.strip())
            self._cell = None
        elif tag == "tr" and self._row is not None and self.tables:
            header, rows = self.tables[-1]
            if not header:
                header.extend(self._row)
            else:
                rows.append(self._row)
            self._row = None
        elif tag == "text" and self._text is not None:
            self.svg_texts[self._svg].append(self._text)
            self._text = None
        elif tag == "svg":
            self._svg = None
        elif tag == "title":
            self._title = False

    def handle_data(self, data):
        if self._cell is not None:
            self._cell += data
        if self._text is not None and not self._title:
            self._text += data


def table_with(tables, column):
    for header, rows in tables:
        if column in header:
            return [dict(zip(header, row)) for row in rows]
    return None


def near(text, want, tolerance):
    try:
        return abs(float(text) - want) <= tolerance
    except ValueError:
        return False


def check(report_path, facts_path):
    try:
        with open(report_path, encoding="utf-8") as report:
            parser = Tables()
            parser.feed(report.read())
        with open(facts_path, encoding="utf-8") as source:
            facts = json.load(source)
    except (OSError, ValueError) as error:
        print(f"unreadable input: {error}")
        return 2
    failures = []

    messages = table_with(parser.tables, "expected [ms]")
    if messages is None:
        failures.append("no message table (column 'expected [ms]')")
        messages = []
    for want in facts["messages"]:
        rows = [row for row in messages if row.get("id") == want["id"]]
        if len(rows) != 1:
            failures.append(f"message {want['name']} {want['id']}: {len(rows)} rows in the message table (want 1)")
            continue
        row = rows[0]
        for column, expected, tolerance in (("count", want["count"], 0), ("expected [ms]", want["expected_ms"], 0.05),
                                            ("mean [ms]", want["mean_ms"], 0.006), ("max [ms]", want["max_ms"], 0.051),
                                            ("missing", want["missing"], 0), ("gaps", want["gaps"], 0)):
            if not near(row.get(column, ""), expected, tolerance):
                failures.append(f"message {want['name']}: {column} {row.get(column)!r}, want {expected}")
        if row.get("name") != want["name"] or row.get("SA") != want["sa"] or row.get("from") != "DBC":
            failures.append(f"message {want['name']}: name/SA/from {row.get('name')}/{row.get('SA')}/{row.get('from')}")
        print(f"message {want['name']}: count {row.get('count')} mean {row.get('mean [ms]')} ms "
              f"missing {row.get('missing')} gaps {row.get('gaps')}")

    dtcs = table_with(parser.tables, "SPN")
    if dtcs is None:
        failures.append("no DTC table (column 'SPN')")
        dtcs = []
    if len(dtcs) != len(facts["dtcs"]):
        failures.append(f"{len(dtcs)} rows in the DTC table, want {len(facts['dtcs'])}")
    for want in facts["dtcs"]:
        rows = [row for row in dtcs if row.get("SPN") == str(want["spn"]) and row.get("FMI") == str(want["fmi"])]
        if len(rows) != 1:
            failures.append(f"DTC SPN {want['spn']} FMI {want['fmi']}: {len(rows)} rows (want 1)")
            continue
        row = rows[0]
        if (row.get("SA") != want["sa"] or row.get("OC") != str(want["oc"]) or row.get("list") != "DM1"
                or not near(row.get("raised [s]", ""), want["raised_s"], 0.0011)
                or not near(row.get("cleared [s]", ""), want["cleared_s"], 0.0011)):
            failures.append(f"DTC SPN {want['spn']} FMI {want['fmi']}: row {row}, want {want}")
        print(f"DTC SPN {row.get('SPN')} FMI {row.get('FMI')} OC {row.get('OC')}: "
              f"{row.get('raised [s]')} .. {row.get('cleared [s]')} s")

    # the checker's findings and the timeline's lanes name the same DTCs
    findings = [row.get("finding", "") for row in table_with(parser.tables, "finding") or []]
    for want in facts["dtcs"]:
        code = f"SPN {want['spn']} FMI {want['fmi']}"
        for event in ("raised", "cleared"):
            found = sum(1 for text in findings if text.startswith(f"{want['sa']} DM1: DTC {event} {code} "))
            if found != 1:
                failures.append(f"{found} findings 'DTC {event} {code}' (want 1)")
        if f"{code} ({want['sa']})" not in parser.svg_texts.get("dtc-timeline", []):
            failures.append(f"no DTC timeline lane '{code} ({want['sa']})'")
    bam = facts["bam"]
    complete = sum(1 for text in findings
                   if text.startswith(f"BAM {bam['sa']} -> all PGN 65226 (0xFECA) DM1 ")
                   and f" {bam['bytes']} bytes in {bam['packets']} packets" in text)
    if complete != bam["count"]:
        failures.append(f"{complete} complete DM1 BAM findings, want {bam['count']}")

    nodes = table_with(parser.tables, "data rate [bit/s]")
    if nodes is None:
        failures.append("no node table (column 'data rate [bit/s]')")
        nodes = []
    for sa, frames in facts["nodes"].items():
        rows = [row for row in nodes if row.get("SA") == sa]
        if len(rows) != 1 or rows[0].get("frames") != str(frames) or rows[0].get("node") != facts["node"]:
            failures.append(f"node {sa}: rows {rows}, want {frames} frames of {facts['node']}")
    # the node chart: the SA comes first and is never cut, so both nodes of one name are told apart
    labels = parser.svg_texts.get("node-rate", [])
    for sa in facts["nodes"]:
        want = f"{sa} {facts['node']}"
        if want not in labels:
            failures.append(f"node chart: no label {want!r} (labels: {labels})")

    signal_labels = " ".join(text for key, texts in parser.svg_texts.items() if key.startswith("signals-") for text in texts)
    if facts["signal"]["key"].split(".")[1] not in signal_labels:
        failures.append(f"no signal chart names {facts['signal']['key']}")
    if not re.search(r"\bkm/h\b", signal_labels):
        failures.append("the signal chart has no km/h axis")

    for failure in failures:
        print(f"FAIL: {failure}")
    return 1 if failures else 0


def main(argv):
    if len(argv) == 3 and argv[1] == "write":
        return write(argv[2])
    if len(argv) == 4 and argv[1] == "check":
        return check(argv[2], argv[3])
    print(__doc__)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv))
