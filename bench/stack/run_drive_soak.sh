#!/bin/bash
# Drive soak (docs/benchmarks.md "## stack"): the supervised HHEA stack with the simulated
# vehicle driven through the drive scenario again and again for MINUTES, while the HMI
# (offscreen) is stopped and started every HMI_PERIOD seconds (its start is the heaviest
# thing an operator does to the VCU's CPU). At the end the simulated VIC's J1939-76
# counters (vcu status: vic_pairs_ok, vic_pairs_refused) say whether a single pair of
# vcu-can-tx's was refused, and can-tx's own worst SHM -> SDM delta error and period error.
# Runs inside tests/harness/run_isolated.sh (LCM stays on a private loopback):
#   tests/harness/run_isolated.sh --keep $PWD -- env OPENVCU_BIN=$PWD/build/bin bench/stack/run_drive_soak.sh [MINUTES]
# MINUTES default 30; HMI_PERIOD default 150 (so the HMI starts and stops once every 5 minutes).
# One drive cycle: Start -> Ready -> Connect Driving -> Driving (5 s) -> disconnect -> AC
# charging (6 s) -> Stop -> Standby. Ends with one line
#   RESULT pair_refusals=N pairs_ok=N minutes=M drive_cycles=N drive_failures=N hmi_starts=N tx_delta_max_us=N tx_period_p99_us=N
set -uo pipefail
NAME=drive-soak
minutes=${1:-30}
hmiPeriod=${HMI_PERIOD:-150}
# shellcheck source=../../tests/demo/stack_lib.sh
source "$(cd "$(dirname "$0")/../.." && pwd)/tests/demo/stack_lib.sh"

for _ in $(seq 1 30); do [ "$(beats | grep -c '^vcu-')" -ge 5 ] && break; done
[ "$(beats | grep -c '^vcu-')" -ge 5 ] || fail "the stack did not come up"
echo "$NAME: stack up ($(nproc) cores, $(uname -r), load $(cut -d' ' -f1-3 /proc/loadavg)), HMI $( [ $hmi -eq 1 ] && echo "built: stopped and started every $hmiPeriod s" || echo "not built: not started")"

cycles=0; failures=0; hmiStarts=0; hmiOn=$hmi
end=$(( $(date +%s) + minutes * 60 ))
nextToggle=$(( $(date +%s) + hmiPeriod ))
toggle_hmi() {
  [ $hmi -eq 1 ] || return 0
  [ "$(date +%s)" -ge $nextToggle ] || return 0
  nextToggle=$(( nextToggle + hmiPeriod ))
  if [ $hmiOn -eq 1 ]; then ctl stop hmi >/dev/null; hmiOn=0; else ctl start hmi >/dev/null; hmiOn=1; hmiStarts=$((hmiStarts + 1)); fi
  echo "$NAME: $(date +%T) HMI $( [ $hmiOn -eq 1 ] && echo started || echo stopped)"
}
pause() { local until=$(( $(date +%s) + $1 )); while [ "$(date +%s)" -lt $until ]; do toggle_hmi; sleep 1; done; }
cycle() {
  signal_set internal.operator.StartStop Start
  wait_state Ready || return 1
  signal_set internal.operator.ConnectDriving 1
  wait_state Driving || return 1
  pause 5
  signal_set internal.operator.ConnectDriving 0
  signal_set internal.operator.ACCharging 1
  pause 6
  signal_set internal.operator.ACCharging 0
  pause 3
  signal_set internal.operator.StartStop Stop
  wait_state Standby || return 1
  return 0
}
while [ "$(date +%s)" -lt $end ]; do
  toggle_hmi
  if cycle; then cycles=$((cycles + 1)); else
    failures=$((failures + 1))
    echo "$NAME: $(date +%T) cycle failed in state '$(state)'; back to Standby"
    signal_set internal.operator.ConnectDriving 0; signal_set internal.operator.ACCharging 0
    signal_set internal.operator.StartStop Stop
    wait_state Standby || true
  fi
  [ $(( (cycles + failures) % 10 )) -eq 0 ] && echo "$NAME: $(date +%T) $cycles cycles, $failures failed, load $(cut -d' ' -f1-3 /proc/loadavg)"
  pause 2
done

stats=$("$vcu" status --config "$config" --wait 1.2 --stats 2>/dev/null)
value() { grep -oE "(^| )$1=[0-9-]+" <<<"$stats" | head -n1 | cut -d= -f2; }
ok=$(value vic_pairs_ok); refused=$(value vic_pairs_refused)
[ -n "$ok" ] && [ -n "$refused" ] || fail "no vic_pairs_ok / vic_pairs_refused in vcu status --stats"
worst() { grep -oE "tx\.[A-Za-z0-9_]+\.$1=[0-9]+" <<<"$stats" | sort -t= -k2 -n | tail -n1; }
deltaMax=$(worst delta_err_max_us); periodP99=$(worst period_err_p99_us)
echo "$NAME: simulated VIC: $ok pairs accepted, $refused refused; can-tx worst delta error max: $deltaMax; worst period error p99: $periodP99"
grep -h "VIC refuse\|VIC accepts" "$run"/*.log 2>/dev/null | tail -n 20
echo "RESULT pair_refusals=$refused pairs_ok=$ok minutes=$minutes drive_cycles=$cycles drive_failures=$failures" \
  "hmi_starts=$hmiStarts tx_delta_max_us=${deltaMax##*=} tx_period_p99_us=${periodP99##*=}"
