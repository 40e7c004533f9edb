#!/bin/bash
# Sourced by the supervised-stack tests (soak_test.sh, replace_vic_test.sh), inside
# run_isolated.sh: starts the HHEA stack with the simulated vehicle under supervisord and
# gives the helpers they share. Before sourcing, set NAME (the prefix of every output line).
#   ctl ARGS...       supervisorctl on this stack
#   fail TEXT         prints "NAME: FAIL: TEXT", stops the stack, exits 1
#   beats             `vcu status` (every service's last heartbeat)
#   state             the FSM state by name (`vcu top --once`)
#   wait_state NAME   until the FSM is in NAME: each look takes vcu top's 1.5 s, at most 20
#   drive             Start -> Ready -> Connect Driving -> Driving, or fail
#   hmi               1 when vcu-hmi is built and runs (offscreen) under supervisord
VEHICLE=hhea
source "$(dirname "${BASH_SOURCE[0]}")/supervised_stack.sh"
# the HMI joins when it is built, offscreen (no display in the sandbox)
hmi=0
if [ -x "$bin/vcu-hmi" ]; then
  hmi=1
  sed -i -e '/^\[program:hmi\]/,/^$/s/^autostart=false/autostart=true\nenvironment=QT_QPA_PLATFORM="offscreen",XDG_RUNTIME_DIR="'"${run//\//\\/}"'"/' "$run/openvcu.conf"
fi
fail() { echo "$NAME: FAIL: $*"; ctl shutdown >/dev/null 2>&1; exit 1; }
start_supervisor

beats() { "$vcu" status --config "$config" --wait 1.2 2>/dev/null; }
state() { "$vcu" top --once --config "$config" 2>/dev/null | sed -n 's/^FSM *\([^(]*\).*/\1/p' | sed 's/ *$//'; }
wait_state() { for _ in $(seq 1 20); do [ "$(state)" = "$1" ] && return 0; done; return 1; }
signal_set() { "$vcu" signal set "$1" "$2" --config "$config" >/dev/null; }
drive() {
  for _ in $(seq 1 30); do [ "$(beats | grep -c '^vcu-')" -ge 5 ] && break; done
  [ "$(beats | grep -c '^vcu-')" -ge 5 ] || fail "the stack did not come up"
  signal_set internal.operator.StartStop Start
  wait_state Ready || fail "not Ready after Start: $(state)"
  signal_set internal.operator.ConnectDriving 1
  wait_state Driving || fail "not Driving: $(state)"
}
