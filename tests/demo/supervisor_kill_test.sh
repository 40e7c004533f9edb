#!/bin/bash
# Issue 19: a supervisor that dies must not leave its services running. Inside
# run_isolated.sh: ./run.sh --headless brings the supervised stack up; supervisord is then
# SIGKILLed (it stops nothing itself). Every service (vcu-can-rx, -can-tx, -fsm, -gpio,
# -ecu-sim, and vcu-web when it is built) must end within GONE_SECONDS: the kernel sends
# each SIGTERM when its parent dies (PR_SET_PDEATHSIG, set by the service runtime). Their
# last log lines are lost: supervisord wrote the log files from their output pipes. run.sh
# sees supervisord gone, stops iox-roudi (not a service: no parent-death signal) and
# removes the shared memory; nothing may be left.
set -uo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
GONE_SECONDS=5
UP_SECONDS=90
work=$(mktemp -d)
log=$work/run.log
SERVICES='vcu-(can-rx|can-tx|fsm|gpio|ecu-sim|web)'
EXPECTED=5; [ -x "${OPENVCU_BIN:-$root/build/bin}/vcu-web" ] && EXPECTED=6

fail() {
  echo "supervisor_kill_test: FAIL: $*"
  echo "---- run.sh's output"; cat "$log" 2>/dev/null
  exit 1
}

"$root/run.sh" --headless > "$log" 2>&1 &
runner=$!
up=0
for _ in $(seq 1 $((UP_SECONDS * 10))); do
  if grep -qE '^[0-9]{2}:[0-9]{2}:[0-9]{2} FSM ' "$log"; then up=1; break; fi
  kill -0 "$runner" 2>/dev/null || fail "run.sh ended before the stack was up"
  sleep 0.1
done
[ $up -eq 1 ] || fail "no status line within ${UP_SECONDS} s"
services=$(pgrep -f "$SERVICES" | tr '\n' ' ')
[ "$(echo $services | wc -w)" -eq $EXPECTED ] || fail "expected $EXPECTED services before the kill, found: $(pgrep -a -f "$SERVICES")"
supervisor=$(pgrep -x supervisord || pgrep -f 'supervisord -n')
[ -n "$supervisor" ] || fail "no supervisord"

killed=$(date +%s%N)
kill -KILL "$supervisor"
gone=0
for _ in $(seq 1 $((GONE_SECONDS * 20))); do
  if [ -z "$(pgrep -f "$SERVICES" || true)" ]; then gone=1; break; fi
  sleep 0.05
done
[ $gone -eq 1 ] || fail "${GONE_SECONDS} s after supervisord's SIGKILL still running: $(pgrep -a -f "$SERVICES")"
echo "supervisor_kill_test: every service ended $(( ($(date +%s%N) - killed) / 1000000 )) ms after supervisord's SIGKILL"

# run.sh notices (its loop polls supervisord every 3 s), stops iox-roudi, removes the table
for _ in $(seq 1 100); do kill -0 "$runner" 2>/dev/null || break; sleep 0.1; done
kill -0 "$runner" 2>/dev/null && fail "run.sh still runs 10 s after supervisord died"
wait "$runner"
left=$(pgrep -a -f "$SERVICES|iox-roudi|supervisord" || true)
[ -z "$left" ] || fail "processes left behind: $left"
shm=$(ls /dev/shm | grep -E '^(openvcu-|iceoryx_)' || true)
[ -z "$shm" ] || fail "shared memory left behind: $shm"
echo "supervisor_kill_test: PASS"
