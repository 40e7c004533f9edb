#!/bin/bash
# Whole-stack CPU and memory per service at full HHEA traffic (docs/benchmarks.md "## stack").
# Runs inside tests/harness/run_isolated.sh (private /dev/shm, /tmp, network):
#   tests/harness/run_isolated.sh --keep $PWD -- env OPENVCU_BIN=$PWD/build/bin bench/stack/run_stack_bench.sh [SECONDS]
# The HHEA stack under supervisord with the simulated vehicle, driven to Driving (every
# periodic message of both sides on the bus, the inverters enabled); then for SECONDS
# (default 60) the CPU time of each process (utime + stime from /proc/PID/stat) and its
# memory (/proc/PID/status: VmRSS = RssAnon + RssFile + RssShmem; the shared segments of
# iceoryx and the signal table count in RssShmem and are reported apart).
set -uo pipefail
seconds=${1:-60}
root=$(cd "$(dirname "$0")/../.." && pwd)
bin=${OPENVCU_BIN:-$root/build/bin}
config=$root/config/hhea/vehicle.json
run=$(mktemp -d)
export OPENVCU_BIN=$bin OPENVCU_CONFIG=$config OPENVCU_RUN=$run
sed -e 's/^;user=root.*/user=root/' "$root/config/supervisor/openvcu.conf" > "$run/openvcu.conf"
supervisord -n -c "$run/openvcu.conf" > "$run/supervisord.out" 2>&1 &
trap 'supervisorctl -c "$run/openvcu.conf" shutdown >/dev/null 2>&1; wait' EXIT
sleep 6
"$bin/vcu" signal set internal.operator.StartStop Start --config "$config" >/dev/null
sleep 5
"$bin/vcu" signal set internal.operator.ConnectDriving 1 --config "$config" >/dev/null
sleep 4
state=$("$bin/vcu" top --once --config "$config" | grep '^FSM')
names=(roudi can-rx can-tx fsm gpio ecu-sim)
declare -A pid start
ticks() { awk '{print $14 + $15}' "/proc/$1/stat"; }
for n in "${names[@]}"; do pid[$n]=$(supervisorctl -c "$run/openvcu.conf" pid "$n"); start[$n]=$(ticks "${pid[$n]}"); done
t0=$(date +%s.%N)
sleep "$seconds"
t1=$(date +%s.%N)
hz=$(getconf CLK_TCK)
echo "stack benchmark: $(nproc) cores, $(uname -r), $seconds s at full HHEA traffic, $state"
printf '%-9s %8s %9s %9s %9s %9s\n' process "CPU %" "VmRSS MB" "anon MB" "file MB" "shmem MB"
total=0
for n in "${names[@]}"; do
  p=${pid[$n]}
  used=$(( $(ticks "$p") - ${start[$n]} ))
  cpu=$(echo "scale=2; 100 * $used / $hz / ($t1 - $t0)" | bc)
  [ "$n" != roudi ] && total=$(echo "$total + $cpu" | bc)
  kb() { awk -v k="$1:" '$1 == k {print $2}' "/proc/$p/status"; }
  printf '%-9s %8s %9.1f %9.1f %9.1f %9.1f\n' "$n" "$cpu" "$(echo "$(kb VmRSS)/1024" | bc -l)" \
    "$(echo "$(kb RssAnon)/1024" | bc -l)" "$(echo "$(kb RssFile)/1024" | bc -l)" "$(echo "$(kb RssShmem)/1024" | bc -l)"
done
echo "services without roudi: $total % of one core"
# the same figures as an operator sees them (vcu top: CPU over its own 1.5 s window)
echo "vcu top --once (cross-check):"
"$bin/vcu" top --once --config "$config" | sed -n '/^SERVICE/,/^$/p'
