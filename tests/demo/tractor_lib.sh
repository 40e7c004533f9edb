#!/bin/bash
# Sourced by the tractor scenario tests (tractor_*_test.sh), inside run_isolated.sh: starts
# the config/tractor stack (iox-roudi, can-rx, can-tx, fsm, gpio and the simulated vehicle)
# under supervisord, without the HMI. Before sourcing, set NAME (the prefix of every line).
#   fail TEXT                  prints "NAME: FAIL: TEXT" and the services' log tails, stops, exits 1
#   pass                       prints "NAME: PASS"
#   get KEY                    `vcu signal get KEY` (bus, command, override, effective planes)
#   bus KEY                    the number on KEY's bus plane (received: as decoded; sent: as can-tx sent it)
#   eff KEY                    the number of KEY's effective command (internal signals: operator switches)
#   state                      the FSM state's name
#   wait_state NAME [S]        until the FSM is in NAME, at most S seconds (default 10)
#   wait_bus KEY OP NUMBER [S] until `bus KEY` OP NUMBER (awk: > >= < <= ==), at most S s (default 10)
#   wait_eff KEY OP NUMBER [S] the same for `eff KEY`
#   vset KEY VALUE             `vcu signal set` (answered by the owning service), or fail
#   sim_fault NAME on|off      `vcu sim fault`, or fail
#   up                         until every service beats, or fail
#   key_on                     key switch on (simulated GPIO line), then Ready, or fail
set -uo pipefail
VEHICLE=tractor
source "$(dirname "${BASH_SOURCE[0]}")/supervised_stack.sh"
fail() {
  echo "$NAME: FAIL: $*"
  echo "-- FSM state: $(state)"
  for log in fsm ecu-sim can-tx can-rx gpio; do
    [ -f "$run/$log.log" ] && { echo "-- $log.log (last lines)"; tail -n 8 "$run/$log.log"; }
  done
  ctl shutdown >/dev/null 2>&1
  exit 1
}
pass() { echo "$NAME: PASS"; }
start_supervisor

get() { "$vcu" signal get "$1" --config "$config" 2>/dev/null; }
bus() { get "$1" | awk '$1 == "bus" && $2 != "never" { print $2; exit }'; }
eff() { get "$1" | awk '$1 == "effective" && $2 != "none" { print $2; exit }'; }
# internal.fsm.state is the index of the state in fsm.json's "states" (docs/fsm.md)
mapfile -t states < <(python3 -c 'import json, sys; [print(s["name"]) for s in json.load(open(sys.argv[1]))["states"]]' \
  "$root/config/tractor/fsm.json")
state() { local index; index=$(bus internal.fsm.state); [ -n "$index" ] && echo "${states[$index]}"; }
wait_state() {
  local deadline=$(( $(date +%s%N) + ${2:-10} * 1000000000 ))
  while [ "$(date +%s%N)" -lt $deadline ]; do
    [ "$(state)" = "$1" ] && return 0
    sleep 0.2
  done
  return 1
}
wait_plane() {
  local plane=$1 deadline=$(( $(date +%s%N) + ${5:-10} * 1000000000 )) value
  shift
  while [ "$(date +%s%N)" -lt $deadline ]; do
    value=$($plane "$1")
    [ -n "$value" ] && awk -v v="$value" -v n="$3" "BEGIN { exit !(v $2 n) }" && return 0
    sleep 0.2
  done
  return 1
}
wait_bus() { wait_plane bus "$@"; }
wait_eff() { wait_plane eff "$@"; }
vset() { "$vcu" signal set "$1" "$2" --config "$config" >/dev/null || fail "vcu signal set $1 $2 was not accepted"; }
sim_fault() { "$vcu" sim fault "$1" "$2" --config "$config" >/dev/null || fail "vcu sim fault $1 $2 was not accepted"; }
up() {
  local beating=0
  for _ in $(seq 1 30); do
    beating=$("$vcu" status --config "$config" --wait 1.2 2>/dev/null | grep -c '^vcu-')
    [ "$beating" -ge 5 ] && return 0
  done
  fail "the stack did not come up: $beating of 5 services beat"
}
key_on() {
  up
  wait_state Standby 5 || fail "not in Standby at start: '$(state)'"
  vset internal.gpio.sim.KeySwitch 1
  wait_state Ready 10 || fail "not Ready 10 s after key on: '$(state)'"
}
