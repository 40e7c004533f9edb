#!/bin/bash
# Whole-stack CPU and memory per service at full HHEA traffic (docs/benchmarks.md "## stack").
# Runs inside tests/harness/run_isolated.sh (private /dev/shm, /tmp, network):
#   tests/harness/run_isolated.sh --keep $PWD -- env OPENVCU_BIN=$PWD/build/bin bench/stack/run_stack_bench.sh [SECONDS] [WINDOWS]
# The HHEA stack under supervisord with the simulated vehicle, driven to Driving (every
# periodic message of both sides on the bus, the inverters enabled); then WINDOWS (default 3)
# windows of SECONDS (default 60) one after the other, each measuring the CPU time of every
# process: the sum of /proc/PID/task/*/schedstat (ns on a CPU, all threads; utime + stime
# from /proc/PID/stat as a cross-check with 10 ms ticks). After the last window the memory
# (/proc/PID/status: VmRSS = RssAnon + RssFile + RssShmem; the shared segments of iceoryx
# and the signal table count in RssShmem) and `vcu top --once` as the operator sees it.
# SDM_SPIN_US=N runs it with a copy of the configuration whose schedule says "sdmSpinUs": N.
# Ends with one line
#   RESULT services_cpu_pct=<median window> services_cpu_min=.. services_cpu_max=.. services_switches_per_s=<median>
#          windows=N seconds=S <service>_pct=<median> <service>_switches=<median per s>..
# where "services" is every process but iox-roudi (and the HMI, which this bench does not start).
set -uo pipefail
seconds=${1:-60}
windows=${2:-3}
root=$(cd "$(dirname "$0")/../.." && pwd)
bin=${OPENVCU_BIN:-$root/build/bin}
config=$root/config/hhea/vehicle.json
run=$(mktemp -d)
if [ -n "${SDM_SPIN_US:-}" ]; then
  # SDM_SPIN_US=N: a copy of the configuration whose schedule has "sdmSpinUs": N (vcu-can-tx's
  # on-CPU wait for short SHM -> SDM deltas; 0 turns it off), relative paths made absolute
  dir=$(dirname "$config")
  jq --argjson spin "$SDM_SPIN_US" '.sdmSpinUs = $spin' "$dir/$(jq -r .schedule "$config")" > "$run/schedule.json"
  jq --arg dir "$dir" --arg schedule "$run/schedule.json" '
    def absolute: if startswith("/") then . else $dir + "/" + . end;
    .dbc |= map(absolute) | .schedule = $schedule |
    with_entries(if (.key | IN("fsm", "gpio", "simulation", "receive", "dashboard", "diagnostics", "web", "telemetry", "safety")) then .value |= absolute else . end)' \
    "$config" > "$run/vehicle.json"
  config=$run/vehicle.json
  echo "SDM_SPIN_US=$SDM_SPIN_US: configuration copied to $config"
fi
export OPENVCU_BIN=$bin OPENVCU_CONFIG=$config OPENVCU_RUN=$run OPENVCU_ROUDI=$root/config/iceoryx/iox-roudi.sh
sed -e 's/^;user=root.*/user=root/' "$root/config/supervisor/openvcu.conf" > "$run/openvcu.conf"
supervisord -n -c "$run/openvcu.conf" > "$run/supervisord.out" 2>&1 &
trap 'supervisorctl -c "$run/openvcu.conf" shutdown >/dev/null 2>&1; wait' EXIT
# up when the five services beat (vcu status lists one line per service heard)
up=0
for _ in $(seq 1 30); do
  beating=$("$bin/vcu" status --config "$config" --wait 1 2>/dev/null | grep -c '^vcu-' || true)
  [ "$beating" -ge 5 ] && { up=1; break; }
  kill -0 %1 2>/dev/null || break
done
if [ $up -eq 0 ]; then echo "error: the stack did not come up (logs in $run):" >&2; tail -n 5 "$run/supervisord.out" >&2; exit 1; fi
"$bin/vcu" signal set internal.operator.StartStop Start --config "$config" >/dev/null
sleep 5
"$bin/vcu" signal set internal.operator.ConnectDriving 1 --config "$config" >/dev/null
sleep 4
state=$("$bin/vcu" top --once --config "$config" | grep '^FSM')
names=(roudi can-rx can-tx fsm gpio ecu-sim)
declare -A pid
for n in "${names[@]}"; do pid[$n]=$(supervisorctl -c "$run/openvcu.conf" pid "$n"); done
# CPU ns of all threads of a process (threads that ended are lost: the services keep theirs)
cpuns() { cat /proc/"$1"/task/*/schedstat 2>/dev/null | awk '{s += $1} END {printf "%.0f", s}'; }
ticks() { awk '{print $14 + $15}' "/proc/$1/stat"; }
# context switches of all threads (voluntary: it blocked, i.e. one wake-up each; and
# involuntary), to set beside the platform's cost of a wake-up (bench/platform)
switches() { cat /proc/"$1"/task/*/status 2>/dev/null | awk '/^(non)?voluntary_ctxt_switches:/ {s += $2} END {print s + 0}'; }
hz=$(getconf CLK_TCK)
median() { sort -n | awk '{v[NR] = $1} END {if (NR % 2) print v[(NR + 1) / 2]; else printf "%.2f\n", (v[NR / 2] + v[NR / 2 + 1]) / 2}'; }
echo "stack benchmark: $(nproc) cores, $(uname -r), $windows x $seconds s at full HHEA traffic, $state, load $(cut -d' ' -f1-3 /proc/loadavg)"
declare -A series switchSeries
totals=()
switchTotals=()
for w in $(seq 1 "$windows"); do
  declare -A startNs startTicks startSwitches
  for n in "${names[@]}"; do
    startNs[$n]=$(cpuns "${pid[$n]}"); startTicks[$n]=$(ticks "${pid[$n]}"); startSwitches[$n]=$(switches "${pid[$n]}")
  done
  t0=$(date +%s%N)
  sleep "$seconds"
  t1=$(date +%s%N)
  total=0
  totalSwitches=0
  line="window $w:"
  for n in "${names[@]}"; do
    p=${pid[$n]}
    if ! kill -0 "$p" 2>/dev/null; then echo "error: $n (pid $p) ended during window $w" >&2; exit 1; fi
    cpu=$(awk -v a="$(cpuns "$p")" -v b="${startNs[$n]}" -v t="$((t1 - t0))" 'BEGIN {printf "%.2f", 100 * (a - b) / t}')
    tickPct=$(awk -v a="$(ticks "$p")" -v b="${startTicks[$n]}" -v hz="$hz" -v t="$((t1 - t0))" 'BEGIN {printf "%.2f", 100 * (a - b) / hz / (t / 1e9)}')
    perSecond=$(awk -v a="$(switches "$p")" -v b="${startSwitches[$n]}" -v t="$((t1 - t0))" 'BEGIN {printf "%.0f", (a - b) / (t / 1e9)}')
    series[$n]+="$cpu "
    switchSeries[$n]+="$perSecond "
    if [ "$n" != roudi ]; then
      total=$(awk -v a="$total" -v b="$cpu" 'BEGIN {printf "%.2f", a + b}')
      totalSwitches=$((totalSwitches + perSecond))
    fi
    line+=" $n $cpu% (ticks $tickPct%, $perSecond switches/s)"
  done
  totals+=("$total")
  switchTotals+=("$totalSwitches")
  echo "$line; services without roudi $total % of one core; load $(cut -d' ' -f1-3 /proc/loadavg)"
  now=$("$bin/vcu" top --once --config "$config" | grep '^FSM')
  if [[ "$now" != *Driving* ]]; then echo "error: the FSM left Driving during window $w: $now" >&2; exit 1; fi
done
printf '%-9s %12s %11s %9s %9s %9s %9s\n' process "CPU % median" "switches/s" "VmRSS MB" "anon MB" "file MB" "shmem MB"
result=""
for n in "${names[@]}"; do
  p=${pid[$n]}
  med=$(tr ' ' '\n' <<<"${series[$n]}" | grep . | median)
  kb() { awk -v k="$1:" '$1 == k {print $2}' "/proc/$p/status"; }
  swMed=$(tr ' ' '\n' <<<"${switchSeries[$n]}" | grep . | median)
  printf '%-9s %12s %11s %9.1f %9.1f %9.1f %9.1f\n' "$n" "$med" "$swMed" "$(echo "$(kb VmRSS)/1024" | bc -l)" \
    "$(echo "$(kb RssAnon)/1024" | bc -l)" "$(echo "$(kb RssFile)/1024" | bc -l)" "$(echo "$(kb RssShmem)/1024" | bc -l)"
  result+=" ${n//-/_}_pct=$med ${n//-/_}_switches=$swMed"
done
sorted=$(printf '%s\n' "${totals[@]}" | sort -n)
echo "services without roudi, per window: ${totals[*]} % of one core"
# the same figures as an operator sees them (vcu top: CPU over its own 1.5 s window)
echo "vcu top --once (cross-check):"
"$bin/vcu" top --once --config "$config" | sed -n '/^SERVICE/,/^$/p'
echo "RESULT services_cpu_pct=$(printf '%s\n' "${totals[@]}" | median) services_cpu_min=$(head -n1 <<<"$sorted")" \
  "services_cpu_max=$(tail -n1 <<<"$sorted") services_switches_per_s=$(printf '%s\n' "${switchTotals[@]}" | median) windows=$windows seconds=$seconds$result"
