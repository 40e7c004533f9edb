#!/bin/bash
# The first command's demo, checked (inside run_isolated.sh: private /dev/shm, /tmp, network
# and PIDs): ./run.sh --headless --for 30 --scenario drive must bring the HHEA stack up under
# supervisord, drive it through Driving and Charging back to Standby, stop everything and
# leave no process of the stack and no shared-memory object behind.
set -uo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
out=$(mktemp)
"$root/run.sh" --headless --for 30 --scenario drive > "$out" 2>&1
status=$?
cat "$out"
fail() { echo "run_demo_test: FAIL: $*"; exit 1; }
[ $status -eq 0 ] || fail "run.sh exited with $status"
for expected in "FSM Driving" "FSM Charging" "FSM Standby" '== stopped'; do
  grep -q "$expected" "$out" || fail "no '$expected' in run.sh's output"
done
grep -q 'HV connection 1 "Connected (Normal)"' "$out" || fail "the battery never reported connected"
left=$(ls /dev/shm | grep -E '^(openvcu-|iceoryx_)' || true)
[ -z "$left" ] || fail "shared memory left behind: $left"
procs=$(pgrep -a -f 'vcu-(can-rx|can-tx|fsm|gpio|ecu-sim)|iox-roudi|supervisord' || true)
[ -z "$procs" ] || fail "processes left behind: $procs"
echo "run_demo_test: PASS"
