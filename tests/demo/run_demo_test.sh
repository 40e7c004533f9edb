#!/bin/bash
# The first command's demo, checked (inside run_isolated.sh: private /dev/shm, /tmp, network
# and PIDs): ./run.sh --headless --for 30 --scenario drive must bring the HHEA stack up under
# supervisord with vcu-web, drive it through Driving and Charging back to Standby, stop
# everything and leave no process of the stack and no shared-memory object behind.
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
# vcu-web comes up with the stack (when it is built) and is stopped with it
if [ -x "${OPENVCU_BIN:-$root/build/bin}/vcu-web" ]; then
  grep -q '^web: http://127.0.0.1:8080 ' "$out" || fail "no 'web: http://127.0.0.1:8080' line: vcu-web did not run"
fi
left=$(ls /dev/shm | grep -E '^(openvcu-|iceoryx_)' || true)
[ -z "$left" ] || fail "shared memory left behind: $left"
procs=$(pgrep -a -f 'vcu-(can-rx|can-tx|fsm|gpio|ecu-sim|web)|iox-roudi|supervisord' || true)
[ -z "$procs" ] || fail "processes left behind: $procs"
echo "run_demo_test: PASS"
