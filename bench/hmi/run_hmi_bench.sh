#!/bin/bash
# vcu-hmi frame rate, CPU and memory with the whole HHEA stack at full traffic and a live
# plot of 4 signals, offscreen and under Xvfb (docs/benchmarks.md "## hmi").
# Runs inside tests/harness/run_isolated.sh (private /dev/shm, /tmp, network):
#   tests/harness/run_isolated.sh --keep $PWD -- env OPENVCU_BIN=$PWD/build-hmi/bin bench/hmi/run_hmi_bench.sh [SECONDS]
# The stack runs under supervisord (config/supervisor/openvcu.conf) with the simulated
# vehicle, driven to Driving; then vcu-hmi runs SECONDS (default 30) on the CAN Data tab
# with 4 signals plotted and --report-fps (frames actually rendered per second; the plot
# scrolls at 60 Hz, so 60 is the most a healthy run can show). Reported: the median of its
# per-second fps lines, its CPU (utime + stime over the run) and VmRSS at the end.
# Also offscreen: the CAN Data tab's Frames page instead of the plot (the raw-frame trace
# of every rx and tx frame), and with HMI_BENCH_LONG=S a run of S seconds with the plot's
# 10-min window (S >= 620 fills it: the per-pixel decimation then walks 10 min of samples).
set -uo pipefail
seconds=${1:-30}
root=$(cd "$(dirname "$0")/../.." && pwd)
bin=${OPENVCU_BIN:-$root/build/bin}
config=$root/config/hhea/vehicle.json
run=$(mktemp -d)
export OPENVCU_BIN=$bin OPENVCU_CONFIG=$config OPENVCU_RUN=$run XDG_RUNTIME_DIR=$run/xdg OPENVCU_ROUDI=$root/config/iceoryx/iox-roudi.sh
mkdir -m 700 "$run/xdg"
sed -e 's/^;user=root.*/user=root/' "$root/config/supervisor/openvcu.conf" > "$run/openvcu.conf"
supervisord -n -c "$run/openvcu.conf" > "$run/supervisord.out" 2>&1 &
xvfb_pid=
trap 'supervisorctl -c "$run/openvcu.conf" shutdown >/dev/null 2>&1; [ -n "$xvfb_pid" ] && kill "$xvfb_pid"; wait' EXIT
sleep 6
"$bin/vcu" signal set internal.operator.StartStop Start --config "$config" >/dev/null
sleep 5
"$bin/vcu" signal set internal.operator.ConnectDriving 1 --config "$config" >/dev/null
sleep 4
state=$("$bin/vcu" top --once --config "$config" | grep '^FSM')
keys=VIC.HVESSD1_PGN61584.HS_ULvl,VIC.HVESSD1_PGN61584.HS_I,VIC.HVESSD2_PGN61585.HS_FastUpdSOC,HVLP_SA71.HS2_Status_Feedback.InverterStatus
hz=$(getconf CLK_TCK)
echo "hmi benchmark: $(nproc) cores, $(uname -r), $seconds s per run at full HHEA traffic, $state"
echo "plot: $keys (window 30 s), CAN Data tab, 720x600"
printf '%-10s %8s %8s %8s %10s\n' platform "fps p50" "fps min" "CPU %" "VmRSS MB"

measure() {  # $1 = label, $2 = --renderer, $3 = more vcu-hmi options, $4 = seconds, rest = environment
  local label=$1 renderer=$2 extra=$3 seconds=$4
  shift 4
  # shellcheck disable=SC2086  # $extra: several options
  env "$@" "$bin/vcu-hmi" --config "$config" --dashboard "$root/config/hhea/dashboard.json" --tab 2 --renderer "$renderer" \
    --plot "$keys" $extra --report-fps --quit-after "$seconds" > "$run/$label.out" 2>&1 &
  local pid=$!
  sleep 2  # start-up is not measured
  local start
  start=$(awk '{print $14 + $15}' "/proc/$pid/stat")
  local t0
  t0=$(date +%s.%N)
  sleep $((seconds - 4))
  local used=$(( $(awk '{print $14 + $15}' "/proc/$pid/stat") - start ))
  local t1
  t1=$(date +%s.%N)
  local rss
  rss=$(awk '$1 == "VmRSS:" {print $2}' "/proc/$pid/status")
  wait "$pid"
  local fps
  fps=$(grep '^fps ' "$run/$label.out" | tail -n +3 | awk '{print $2}' | sort -n)
  local n
  n=$(echo "$fps" | wc -l)
  local p50 cpu mb
  p50=$(echo "$fps" | sed -n "$(( (n + 1) / 2 ))p")
  cpu=$(printf '%.1f' "$(echo "100 * $used / $hz / ($t1 - $t0)" | bc -l)")
  mb=$(printf '%.1f' "$(echo "$rss / 1024" | bc -l)")
  printf '%-10s %8s %8s %8s %10s\n' "$label" "$p50" "$(echo "$fps" | head -1)" "$cpu" "$mb"
  result+=" ${label//[-+]/_}_fps=${p50:-0} ${label//[-+]/_}_cpu_pct=$cpu ${label//[-+]/_}_rss_mb=$mb"
}
result=""

measure offscreen software "" "$seconds" QT_QPA_PLATFORM=offscreen
measure off-frames software "--can-page frames" "$seconds" QT_QPA_PLATFORM=offscreen
if [ -n "${HMI_BENCH_LONG:-}" ]; then
  measure off-10min software "--plot-window 600" "$HMI_BENCH_LONG" QT_QPA_PLATFORM=offscreen
fi
if command -v Xvfb >/dev/null; then
  Xvfb :7 -screen 0 1024x768x24 -nolisten tcp > "$run/xvfb.out" 2>&1 &
  xvfb_pid=$!
  for _ in $(seq 50); do [ -e /tmp/.X11-unix/X7 ] && break; sleep 0.1; done
  measure xvfb-gl gpu "" "$seconds" QT_QPA_PLATFORM=xcb DISPLAY=:7
  measure xvfb-sw software "" "$seconds" QT_QPA_PLATFORM=xcb DISPLAY=:7
  measure xvfb-frames software "--can-page frames" "$seconds" QT_QPA_PLATFORM=xcb DISPLAY=:7
fi
echo "RESULT${result}"
