#!/bin/bash
# Issue 18 (inside run_isolated.sh): the signal table truncated by root while the HHEA stack
# drives under supervisord (`truncate -s 0 /dev/shm/openvcu-hhea`). Before, vcu-can-rx,
# vcu-can-tx, vcu-fsm and vcu-ecu-sim died by SIGBUS, supervisord restarted them and the
# FSM's state was lost. Now:
#   - no service dies: every one keeps its pid and supervisord logs no exit;
#   - the table is whole again (its size, and `vcu signal get` attaches);
#   - every service says so in one log line ("signal table 'openvcu-hhea' was damaged ...");
#   - the FSM is still in Driving: vcu-fsm wrote its state back into the table.
#   table_damage_test.sh      (ctest: label integration)
set -uo pipefail
NAME=table_damage
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
truncate -s 0 "$table"
echo "$NAME: truncated $table ($size bytes) to 0 bytes while Driving"

# Each service reports it at its next heartbeat tick (1 s): wait for every report, at most 10 s.
reported() { grep -c "signal table 'openvcu-$instance' was damaged" "$run/$1.log" 2>/dev/null || true; }
for _ in $(seq 1 20); do
  missing=0
  for program in "${programs[@]}"; do [ "$(reported "$program")" -ge 1 ] || missing=1; done
  [ $missing -eq 0 ] && break
  sleep 0.5
done

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
# the state, from the table (vcu top reads internal.fsm.state)
wait_state Driving || check "the FSM is no longer in Driving: '$(state)'"

if [ $failures -ne 0 ]; then fail "$failures check(s) failed (logs in $run)"; fi
echo "$NAME: PASS: no service died, every one reported the damage once, the FSM is still Driving"
