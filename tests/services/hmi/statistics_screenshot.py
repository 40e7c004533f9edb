#!/usr/bin/python3
"""The screenshot of the Trace tab's Statistics page in docs/images (issue 21).

  tests/services/hmi/statistics_screenshot.py BUILD_DIR [OUT.png]

Writes a 20 s candump -L log of the HHEA messages that have a GenMsgCycleTime in
config/hhea/hhea.dbc on bus "vehicle" (each at its cycle with +-0.3 ms of jitter; one
message loses 3 frames in a row, one runs 20 % slow), then runs vcu-hmi offscreen on
memq:// (no network, no stack) with --trace LOG --trace-page statistics --screenshot and
copies the Trace tab's picture to OUT.png (default docs/images/hmi-trace-statistics.png).
Deterministic (fixed seed).
"""
import os
import random
import re
import shutil
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
DBC = os.path.join(ROOT, "config/hhea/hhea.dbc")
CONFIG = os.path.join(ROOT, "config/hhea/vehicle.json")
SECONDS = 20.0
START = 1700000000.0


def cycled_messages():
    text = open(DBC, encoding="utf-8", errors="replace").read()
    lengths = {int(m.group(1)): int(m.group(2)) for m in re.finditer(r"^BO_ (\d+) \w+ *: *(\d+)", text, re.M)}
    cycles = {}
    for m in re.finditer(r'^BA_ "GenMsgCycleTime" BO_ (\d+) (\d+);', text, re.M):
        dbc_id, cycle = int(m.group(1)), int(m.group(2))
        if cycle > 0 and dbc_id in lengths and dbc_id & 0x80000000:
            cycles[dbc_id & 0x1FFFFFFF] = (cycle / 1000.0, min(lengths[dbc_id], 8))
    return sorted(cycles.items())


def write_log(path):
    rng = random.Random(21)
    messages = cycled_messages()[:14]
    lines = []
    for n, (can_id, (cycle, length)) in enumerate(messages):
        period = cycle * (1.2 if n == 3 else 1.0)  # one sender 20 % slow
        t = rng.uniform(0, cycle)
        k = 0
        while t < SECONDS:
            dropped = n == 1 and 50 <= k < 53  # three frames lost in a row
            if not dropped:
                stamp = START + t + rng.uniform(-0.0003, 0.0003)
                data = bytes(rng.randrange(256) for _ in range(length)).hex().upper()
                lines.append((stamp, "(%.6f) vehicle %08X#%s" % (stamp, can_id, data)))
            t += period
            k += 1
    lines.sort()
    with open(path, "w") as out:
        out.writelines(line + "\n" for _, line in lines)


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    hmi = os.path.join(sys.argv[1], "bin", "vcu-hmi")
    target = sys.argv[2] if len(sys.argv) > 2 else os.path.join(ROOT, "docs/images/hmi-trace-statistics.png")
    with tempfile.TemporaryDirectory() as folder:
        log = os.path.join(folder, "vehicle.log")
        write_log(log)
        shots = os.path.join(folder, "shots")
        env = dict(os.environ, QT_QPA_PLATFORM="offscreen", XDG_RUNTIME_DIR=folder)
        subprocess.run([hmi, "--config", CONFIG, "--lcm-url", "memq://", "--instance", "shot-%d" % os.getpid(),
                        "--no-frames", "--tab", "5", "--trace", log, "--trace-page", "statistics",
                        "--screenshot", shots, "--exit-after-screenshots"], env=env, check=True, timeout=120)
        shutil.copyfile(os.path.join(shots, "tab-5-trace.png"), target)
    print("saved", target)


if __name__ == "__main__":
    main()
