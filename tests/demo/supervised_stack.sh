#!/bin/bash
# Sourced by stack_lib.sh and tractor_lib.sh (inside run_isolated.sh): the paths and the
# supervisord configuration of one vehicle's test stack. Before sourcing, set VEHICLE (a
# folder of config/: hhea, tractor; COPY_VEHICLE=1: a copy of it, below). Sets root, bin, vcu, config and run (a fresh folder),
# exports what config/supervisor/openvcu.conf reads and writes it to $run/openvcu.conf.
#   ctl ARGS...         supervisorctl on this stack
#   start_supervisor    supervisord in the background ($supervisor), shut down at exit
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
bin=${OPENVCU_BIN:-$root/build/bin}
vcu=$bin/vcu
config=$root/config/${VEHICLE:?set VEHICLE before sourcing supervised_stack.sh}/vehicle.json
run=$(mktemp -d)
# COPY_VEHICLE=1: the stack runs on a copy of the vehicle's folder in $run, so what it writes
# beside its configuration (schedule.overlay.json after a schedule command) stays in the sandbox
if [ "${COPY_VEHICLE:-0}" = 1 ]; then
  cp -r "$(dirname "$config")" "$run/vehicle" && rm -f "$run/vehicle/"*.overlay.json
  config=$run/vehicle/vehicle.json
fi
export OPENVCU_BIN=$bin OPENVCU_CONFIG=$config OPENVCU_RUN=$run OPENVCU_ROUDI=$root/config/iceoryx/iox-roudi.sh
sed -e 's/^;user=root.*/user=root/' "$root/config/supervisor/openvcu.conf" > "$run/openvcu.conf"
ctl() { supervisorctl -c "$run/openvcu.conf" "$@"; }
start_supervisor() {
  supervisord -n -c "$run/openvcu.conf" > "$run/supervisord.out" 2>&1 &
  supervisor=$!
  trap 'ctl shutdown >/dev/null 2>&1; wait $supervisor 2>/dev/null' EXIT
}
