#!/bin/bash
# Issue 18 (inside run_isolated.sh): the signal table truncated by root while the HHEA stack
# drives under supervisord (`truncate -s 0 /dev/shm/openvcu-hhea`). Before, vcu-can-rx,
# vcu-can-tx, vcu-fsm and vcu-ecu-sim died by SIGBUS, supervisord restarted them and the
# FSM's state was lost. Now:
#   - no service dies: every one keeps its pid and supervisord logs no exit;
#   - the table is whole again (its size, and `vcu signal get` attaches);
#   - every service says so in one log line ("signal table 'openvcu-hhea' was damaged ...");
#   - vcu-fsm wrote its state back ("the signal table lost its values: state 'Driving' ...")
#     and never left Driving: no transition to another state for OBSERVE_S seconds after the
#     truncation (longer than its 1.5 s input grace plus the 3 s HVESSS1 timeout, so a wipe
#     taken for a silent battery would show), and the table says Driving at the end.
#   table_damage_test.sh      (ctest: label integration)
set -uo pipefail
NAME=table_damage
OBSERVE_S=5
# shellcheck source=stack_lib.sh
. "$(dirname "$0")/stack_lib.sh"
drive

programs=(can-rx can-tx fsm gpio ecu-sim)
declare -A pids
for program in "${programs[@]}"; do pids[$program]=$(ctl pid "$program"); done
instance=$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["instance"])' "$config")
table=/dev/shm/openvcu-$instance
size=$(stat -c %s "$table")
log_lines=$(wc -l < "$run/supervisord.log")
fsm_lines=$(wc -l < "$run/fsm.log")
truncated_at=$(date +%s)
truncate -s 0 "$table"
echo "$NAME: truncated $table ($size bytes) to 0 bytes while Driving"

# vcu-fsm's transitions since the truncation other than Driving -> Driving (its
# self-transitions); a restart would log "-> <state>: initial state" or "resumed".
left_driving() { tail -n +"$((fsm_lines + 1))" "$run/fsm.log" | grep -E ": (- |Driving )?-> " | grep -v ": Driving -> Driving: "; }
# Each service reports the damage at its next heartbeat tick (1 s); the FSM must stay in
# Driving all the while: watch for OBSERVE_S seconds (fail early on the first transition).
reported() { grep -c "signal table 'openvcu-$instance' was damaged" "$run/$1.log" 2>/dev/null || true; }
while [ $(($(date +%s) - truncated_at)) -lt $OBSERVE_S ]; do
  left_driving >/dev/null && break
  sleep 0.5
done
# what the FSM's inputs look like now (shown when a check fails)
after=$("$vcu" signal get internal.gpio.Cl15 internal.relay.Cl15 internal.tx.keepAlive \
  VIC.HVESSS1_PGN61590.HS_HiUBusCnctnSts internal.operator.StartStop --config "$config" 2>&1)

failures=0
check() { echo "$NAME: FAIL: $*"; failures=$((failures + 1)); }
for program in "${programs[@]}"; do
  now=$(ctl pid "$program")
  [ "$now" = "${pids[$program]}" ] || check "$program was restarted (pid ${pids[$program]} -> $now)"
  lines=$(reported "$program")
  [ "$lines" = 1 ] || check "$program logged $lines damage lines, expected 1"
  grep "was damaged" "$run/$program.log" | head -1 | sed "s/^/$NAME: $program: /"
done
if tail -n +"$((log_lines + 1))" "$run/supervisord.log" | grep -E "exited: (can-rx|can-tx|fsm|gpio|ecu-sim) "; then
  check "supervisord saw a service exit after the truncation"
fi
[ "$(stat -c %s "$table")" = "$size" ] || check "$table is $(stat -c %s "$table") bytes, expected $size"
"$vcu" signal get internal.operator.StartStop --config "$config" >/dev/null 2>&1 || check "vcu signal get cannot attach to the table"
written_back=$(grep -c "the signal table lost its values: state 'Driving'" "$run/fsm.log")
[ "$written_back" -ge 1 ] || check "vcu-fsm did not write its state back (no 'the signal table lost its values: state 'Driving'' line)"
grep "the signal table lost its values" "$run/fsm.log" | head -1 | sed "s/^/$NAME: fsm: /"
if transitions=$(left_driving); then check "the FSM left Driving after the truncation: $transitions"; fi
# the state, from the table (vcu top reads internal.fsm.state): one look, no waiting for a return
now_state=$(state)
[ "$now_state" = Driving ] || check "the table says the FSM is in '$now_state', not Driving"

if [ $failures -ne 0 ]; then
  # the run folder lives in the test's private /tmp: show what the services said
  echo "$after" | sed "s/^/$NAME: after the truncation: /"
  for program in fsm can-tx gpio ecu-sim; do
    tail -n 30 "$run/$program.log" | sed "s/^/$NAME: $program.log: /"
  done
  fail "$failures check(s) failed (logs in $run)"
fi
echo "$NAME: PASS: no service died, every one reported the damage once, the FSM wrote its state back and stayed in Driving"
