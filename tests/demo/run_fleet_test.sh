#!/bin/bash
# Issue 25: ./run.sh --fleet 2 --headless --for 10, inside run_isolated.sh (private /dev/shm,
# /tmp, network and PIDs: the fleet's mosquitto on 127.0.0.1:1883 is the sandbox's own). Both
# simulated vehicles must appear online in `vcu fleet watch`'s lines, each with an FSM state
# (run.sh starts them), and the stop must leave no process and no shared memory behind.
#   run_fleet_test.sh        (ctest runs it through OPENVCU_ISOLATED_LAUNCHER)
set -uo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
[ -x /usr/sbin/mosquitto ] || { echo "run_fleet_test: skipped: needs mosquitto (scripts/install-deps.sh)"; exit 77; }
out=$(mktemp)
"$root/run.sh" --fleet 2 --headless --for 10 --isolated > "$out" 2>&1
status=$?
cat "$out"
fail() { echo "run_fleet_test: FAIL: $*"; exit 1; }
[ $status -eq 0 ] || fail "run.sh exited with $status"
# the watch's lines in a pipe: "HH:MM:SS VEHICLE LINK STATE FAULTS SOC LAST"
for vehicle in hhea-01 hhea-02; do
  grep -qE "^[0-9:]{8} $vehicle online " "$out" || fail "$vehicle never appeared online"
  grep -qE "^[0-9:]{8} $vehicle online [A-Z]" "$out" || fail "$vehicle online but no FSM state seen"
done
grep -q '== stopped' "$out" || fail "run.sh did not stop cleanly"
left=$(ls /dev/shm | grep -E '^(openvcu-|iceoryx_)' || true)
[ -z "$left" ] || fail "shared memory left behind: $left"
procs=$(pgrep -a -f 'vcu-(can-rx|can-tx|fsm|gpio|ecu-sim|telemetry)|vcu fleet|iox-roudi|supervisord|mosquitto' || true)
[ -z "$procs" ] || fail "processes left behind: $procs"
echo "run_fleet_test: PASS"
