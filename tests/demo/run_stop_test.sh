#!/bin/bash
# Issue 19: `./run.sh | tee run.log` and Ctrl-C must stop everything. Inside run_isolated.sh
# (private /dev/shm, /tmp, network, PIDs). The pipeline runs in a process group of its own,
# as a terminal's foreground job does; once run.sh prints its first status line (the stack
# is up and beating) SIGINT goes to that whole group, as Ctrl-C sends it: run.sh, tee and
# whatever run.sh waits for at that moment. Then, within STOP_SECONDS, run.sh must have
# have ended its own stop (exit status 130) and left no process of the stack and no shared
# memory behind.
#   run_stop_test.sh [RUN_SH]     RUN_SH: the script to test (default: the repository's run.sh)
set -uo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
script=${1:-$root/run.sh}
STOP_SECONDS=20
UP_SECONDS=90
work=$(mktemp -d)
log=$work/run.log

fail() {
  echo "run_stop_test: FAIL: $*"
  echo "---- run.log (what tee wrote)"; cat "$log" 2>/dev/null
  exit 1
}
stack_processes() { pgrep -a -f 'vcu-(can-rx|can-tx|fsm|gpio|ecu-sim|hmi|web)|iox-roudi|supervisord' || true; }
shared_memory() { ls /dev/shm | grep -E '^(openvcu-|iceoryx_)' || true; }

# setsid: the pipeline's shell leads a new process group (its pid is the group id), as a
# terminal's job does. env --default-signal: a job started with '&' by a script has SIGINT
# ignored, and an ignored SIGINT is inherited and cannot be trapped, so without it no
# process of the pipeline would even see the Ctrl-C. The pipeline's shell survives the
# SIGINT (a handler, not an ignore: its children keep the default action) to write down how
# run.sh ended.
setsid env --default-signal=INT bash -c 'trap : INT; "$1" --headless 2>&1 | tee "$2" >/dev/null; echo "${PIPESTATUS[0]}" > "$3"' \
  run-pipeline "$script" "$log" "$work/status" &
group=$!

# up: run.sh prints a status line "HH:MM:SS FSM ..." every 3 s once every service beats
up=0
for _ in $(seq 1 $((UP_SECONDS * 10))); do
  if grep -qE '^[0-9]{2}:[0-9]{2}:[0-9]{2} FSM ' "$log" 2>/dev/null; then up=1; break; fi
  kill -0 "$group" 2>/dev/null || fail "the pipeline ended before the stack was up"
  sleep 0.1
done
[ $up -eq 1 ] || fail "no status line within ${UP_SECONDS} s"
[ -n "$(stack_processes)" ] || fail "the stack is up but no process of it is found (the check below would prove nothing)"
echo "run_stop_test: stack up: $(stack_processes | wc -l) processes; SIGINT to process group $group"

kill -INT -- "-$group"
gone=0
for _ in $(seq 1 $((STOP_SECONDS * 10))); do
  if [ -z "$(pgrep -f 'run\.sh' || true)" ] && [ -z "$(stack_processes)" ]; then gone=1; break; fi
  sleep 0.1
done
wait "$group" 2>/dev/null
if [ $gone -eq 0 ]; then
  fail "${STOP_SECONDS} s after SIGINT still running: $(pgrep -a -f 'run\.sh' || true) $(stack_processes)"
fi
# 130: run.sh went through its whole stop and exited as its INT trap says; 141 would be
# SIGPIPE killing it mid-stop on its first write to the dead tee (the run.sh before #19)
status=$(cat "$work/status" 2>/dev/null)
[ "$status" = 130 ] || fail "run.sh ended with status '${status}', not 130 (its orderly stop after SIGINT)"
left=$(shared_memory)
[ -z "$left" ] || fail "shared memory left behind: $left"
echo "run_stop_test: PASS (run.sh, supervisord, iox-roudi and every service ended; /dev/shm clean)"
