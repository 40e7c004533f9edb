#!/bin/bash
# `vcu top` names the sender of every STATUS value (inside run_isolated.sh): config/hhea's
# dashboard lists the InverterStatus of four HVLP inverters (HVLP_SA71..74); with vcu-fsm
# running on that configuration, `vcu top --once` labels each as the HMI's Vehicle tab
# does (display::shortLabel: "HVLP_SA72 InverterStatus") unless the dashboard gives the key
# a label of its own ("Inverter 0x71"), so no bare "InverterStatus" is left.
set -uo pipefail
root=$(cd "$(dirname "$0")/../../.." && pwd)
bin=${OPENVCU_BIN:-$root/build/bin}
NAME="top_labels_test"
fail() { echo "$NAME: FAIL: $*"; exit 1; }
[ "${OPENVCU_ISOLATED:-}" = 1 ] || { echo "$NAME: SKIP: run inside run_isolated.sh"; exit 77; }

config=$root/config/hhea/vehicle.json
"$bin/vcu-fsm" --config "$config" > /tmp/fsm.log 2>&1 &
fsm=$!
trap 'kill $fsm 2>/dev/null' EXIT
# vcu top --once exits 0 once it heard a heartbeat (each look takes 1.5 s)
for _ in 1 2 3 4 5 6; do
  "$bin/vcu" top --once --config "$config" > /tmp/top.out 2>/tmp/top.err && break
done
grep -q '^STATUS' /tmp/top.out || fail "no STATUS line: $(cat /tmp/top.out /tmp/top.err /tmp/fsm.log)"
status=$(sed -n '/^STATUS/,/^[A-Z]/p' /tmp/top.out)
echo "$NAME: $status"
for sa in 72 73 74; do
  echo "$status" | grep -q "HVLP_SA$sa InverterStatus " || fail "HVLP_SA$sa's InverterStatus is not named"
done
echo "$status" | grep -q "Inverter 0x71 " || fail "the dashboard's label of HVLP_SA71 is not used"
bare=$(echo "$status" | grep -oE '(^|   |STATUS +)InverterStatus ' | wc -l)
[ "$bare" -eq 0 ] || fail "$bare InverterStatus value(s) without their sender"
echo "$NAME: passed"
