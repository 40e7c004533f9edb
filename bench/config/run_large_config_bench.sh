#!/bin/bash
# How long loading a vehicle takes as it grows (issue 19): a vehicle.json with N internal
# signals (`vcu signal list`, which loads the configuration and builds the catalog as every
# service does), and an FSM file of N states in a ring (`vcu fsm check`).
#   bench/config/run_large_config_bench.sh [BIN_DIR] [N]      default: build/bin 100000
# Ends with: RESULT signals=N signals_load_s=... states=N fsm_check_s=...
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
bin=${1:-$root/build/bin}
n=${2:-100000}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
/usr/bin/python3 - "$root" "$work" "$n" <<'PY'
import json, sys
root, work, n = sys.argv[1], sys.argv[2], int(sys.argv[3])
base = root + "/config/hhea/"
v = json.load(open(base + "vehicle.json"))
for key in ("dbc", "fsm", "schedule", "gpio", "simulation", "receive", "dashboard", "diagnostics", "web", "telemetry", "safety"):
    if key in v:
        fix = lambda p: p if p.startswith("/") else base + p
        v[key] = [fix(p) for p in v[key]] if isinstance(v[key], list) else fix(v[key])
v["internalSignals"] = v.get("internalSignals", []) + [{"name": f"bulk.s{i}", "min": 0, "max": 1} for i in range(n)]
json.dump(v, open(work + "/vehicle.json", "w"))
states = [{"name": f"S{i}", "transitions": [{"condition": {"key": "internal.operator.StartStop", "eq": "Start"},
                                             "nextState": f"S{(i + 1) % n}"}]} for i in range(n)]
json.dump({"initialState": "S0", "states": states}, open(work + "/fsm.json", "w"))
PY
seconds() {
  local t0 t1
  t0=$(date +%s%N)
  "$@" >/dev/null 2>&1 || true
  t1=$(date +%s%N)
  awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.3f", (b - a) / 1e9 }'
}
echo "== $n internal signals: vcu signal list"
signals_s=$(seconds "$bin/vcu" signal list --config "$work/vehicle.json" internal.bulk.s1)
echo "   $signals_s s"
echo "== $n states: vcu fsm check"
fsm_s=$(seconds "$bin/vcu" fsm check "$work/fsm.json" --config "$root/config/hhea/vehicle.json")
echo "   $fsm_s s"
echo "RESULT signals=$n signals_load_s=$signals_s states=$n fsm_check_s=$fsm_s"
