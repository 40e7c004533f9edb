#!/bin/bash
# Replacement (inside run_isolated.sh): the simulated VIC is swapped for a replay of its own
# recorded trace while the vehicle drives, and no VCU service is restarted.
#   1. the supervised HHEA stack with vcu-ecu-sim, driven to Driving;
#   2. `vcu record` of the vehicle bus for a few seconds; the VIC's frames (source address
#      0xF3) are cut out of it into a log of their own;
#   3. `vcu replay --loop` of that log starts, then `vcu sim fault silent.VIC on` silences
#      the simulated VIC: from now on the VIC on the bus is the recording;
#   4. for REPLACED seconds the FSM stays in Driving (the VCU's 3 s VIC timeout would end it
#      otherwise) and every VCU service keeps its pid;
#   5. control: the replay is stopped, and the FSM must leave Driving (the VIC is silent):
#      the replay, not a leftover of the simulation, kept the vehicle driving;
#   6. the simulated VIC speaks again and FaultReset brings the vehicle back to Ready.
#   replace_vic_test.sh [REPLACED]       (default 10 s)
set -uo pipefail
replaced=${1:-10}
NAME=replace_vic
# shellcheck source=stack_lib.sh
. "$(dirname "$0")/stack_lib.sh"
echo "replace_vic: logs $run"
drive

"$vcu" record "$run/rec" --for 4 --config "$config" > "$run/record.out" 2>&1 || fail "vcu record: $(cat "$run/record.out")"
mkdir -p "$run/vic"
# candump -L: "(t) vehicle 18F091F3#..." -> the frames whose source address is 0xF3
grep -E ' [0-9A-F]{6}F3#' "$run/rec/vehicle.log" > "$run/vic/vehicle.log"
frames=$(wc -l < "$run/vic/vehicle.log")
ids=$(awk '{split($3, f, "#"); print f[1]}' "$run/vic/vehicle.log" | sort -u | tr '\n' ' ')
[ "$frames" -gt 20 ] || fail "only $frames VIC frames recorded"
echo "replace_vic: recorded $frames VIC frames ($ids)"

declare -A pid
for p in roudi can-rx can-tx fsm gpio ecu-sim; do pid[$p]=$(ctl pid "$p"); done
"$vcu" replay "$run/vic" --loop --config "$config" > "$run/replay.out" 2>&1 &
replay=$!
# playing once it says so (it opened the bus first); ended early: its error is in the file
for _ in $(seq 1 100); do
  grep -q '^replaying ' "$run/replay.out" && break
  kill -0 "$replay" 2>/dev/null || fail "vcu replay ended: $(cat "$run/replay.out")"
  sleep 0.1
done
grep -q '^replaying ' "$run/replay.out" || fail "vcu replay did not start playing: $(cat "$run/replay.out")"
"$vcu" sim fault silent.VIC on --config "$config" > "$run/silent.out" 2>&1 || fail "vcu sim fault silent.VIC on: $(cat "$run/silent.out")"
echo "replace_vic: the simulated VIC is silent, the recording plays (vcu replay pid $replay)"

end=$(( $(date +%s) + replaced )); looks=0
while [ "$(date +%s)" -lt "$end" ]; do
  now=$(state); looks=$((looks + 1))
  [ "$now" = Driving ] || fail "the FSM left Driving while the replayed VIC was on the bus: '$now'"
done
for p in roudi can-rx can-tx fsm gpio ecu-sim; do
  [ "$(ctl pid "$p")" = "${pid[$p]}" ] || fail "$p was restarted during the replacement"
done
connection=$("$vcu" signal get VIC.HVESSS1_PGN61590.HS_HiUBusCnctnSts --config "$config" 2>&1 | awk '$1 == "bus" {print $2; exit}')
[ "$connection" = 1 ] || fail "the VIC's connection status in the table is '$connection', not 1 (Connected)"
echo "replace_vic: ${replaced} s on the replayed VIC: FSM Driving at all $looks looks, connection status $connection, no service restarted"

# control: without the replay the (silenced) VIC is gone and the FSM must notice
kill "$replay"; wait "$replay" 2>/dev/null
left=""
for _ in $(seq 1 8); do now=$(state); [ "$now" != Driving ] && { left=$now; break; }; done
[ -n "$left" ] || fail "the FSM stayed in Driving with no VIC on the bus: the replay was not what kept it driving"
echo "replace_vic: replay stopped -> FSM '$left' (the VIC is silent)"

"$vcu" sim fault silent.VIC off --config "$config" > /dev/null 2>&1 || fail "vcu sim fault silent.VIC off"
signal_set internal.operator.ConnectDriving 0
signal_set internal.operator.FaultReset 1
wait_state Ready || fail "not Ready again after the simulated VIC returned: $(state)"
for p in can-rx can-tx fsm gpio; do
  [ "$(ctl pid "$p")" = "${pid[$p]}" ] || fail "vcu-$p was restarted"
done
echo "replace_vic: the simulated VIC is back, FSM Ready; no VCU service was restarted at any point"
echo "replace_vic: PASS"
