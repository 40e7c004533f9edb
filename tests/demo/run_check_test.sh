#!/bin/bash
# Issue 19: `./run.sh --check` runs `vcu check` and nothing else: no install, no build, no
# Python. The shipped vehicle passes (exit 0); a copy with a broken simulation.json, a
# dashboard.json that is not an object and a schedule with a syntax error fails (exit 1)
# with each file named with its line (or JSON path) on stderr and no Python traceback; so
# does one whose simulation and dashboard are valid JSON their loaders refuse.
# RUN_SH=FILE tests another script (the run.sh before issue 19 fails it).
set -uo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "run_check_test: FAIL: $*"; echo "---- stdout"; cat "$work/out"; echo "---- stderr"; cat "$work/err"; exit 1; }

"${RUN_SH:-$root/run.sh}" --check >"$work/out" 2>"$work/err"
status=$?
[ $status -eq 0 ] || fail "the shipped vehicle: exit $status, not 0"
grep -q "vehicle 'hhea': 12 files, 0 errors" "$work/out" || fail "no summary for the shipped vehicle"
grep -qE '== building|install' "$work/out" "$work/err" && fail "--check installed or built"

cp "$root"/config/hhea/* "$work/"
printf '{"vehicle": {"mass": 1,}}\n' > "$work/simulation.json"
printf '[]\n' > "$work/dashboard.json"
printf '{\n  "messages": {\n    "a": 1\n    "b": 2\n  }\n}\n' > "$work/schedule.json"
"${RUN_SH:-$root/run.sh}" --check --config "$work/vehicle.json" >"$work/out" 2>"$work/err"
status=$?
[ $status -eq 1 ] || fail "the broken vehicle: exit $status, not 1"
grep -q "^$work/simulation.json:1:" "$work/err" || fail "simulation.json's syntax error not reported with its line"
grep -q "^$work/dashboard.json: error: the top level must be a JSON object" "$work/err" || fail "dashboard.json not refused"
grep -q "^$work/schedule.json:4:" "$work/err" || fail "schedule.json's syntax error not reported with its line"
grep -q "Traceback" "$work/out" "$work/err" && fail "a Python traceback"
grep -q "12 files, 3 errors" "$work/out" || fail "the summary does not count 3 errors"

# Valid JSON the loaders refuse (#20): a state of charge over 100 % and a dashboard signal
# the catalog lacks, each named with its JSON path.
cp "$root"/config/hhea/* "$work/"
printf '{"model": "hhea", "battery": {"initialSoc": 150}}\n' > "$work/simulation.json"
printf '{"items": [{"key": "internal.relay.Cl16"}]}\n' > "$work/dashboard.json"
"${RUN_SH:-$root/run.sh}" --check --config "$work/vehicle.json" >"$work/out" 2>"$work/err"
status=$?
[ $status -eq 1 ] || fail "the vehicle with refused content: exit $status, not 1"
grep -q "^$work/simulation.json: /battery/initialSoc: error: " "$work/err" || fail "simulation.json's content not refused"
grep -q "^$work/dashboard.json: /items/0/key: error: unknown signal" "$work/err" || fail "dashboard.json's content not refused"
grep -q "12 files, 2 errors" "$work/out" || fail "the summary does not count 2 errors"
echo "run_check_test: PASS"
