#!/usr/bin/env bash
# can-rx benchmark (docs/benchmarks.md, section "can-rx"). Builds nothing: configure and
# build a Release tree first (not under /tmp: the sandbox's /tmp is private), e.g.
#   cmake -S . -B ../build-bench -G Ninja -DCMAKE_BUILD_TYPE=Release -DOPENVCU_BUILD_BENCH=ON
#   ninja -C ../build-bench vcu vcu-can-rx bench_receiver bench_sim_sender
#
# usage: bench/can-rx/run_can_rx_bench.sh [BUILD_DIR]      (default: <repo>/build)
#
# Everything runs inside tests/harness/run_isolated.sh (private /dev/shm, /tmp, network and
# PIDs: its own iox-roudi, LCM multicast on a private lo):
#   1. bench_receiver: CPU time per frame of canrx::Receiver::onFrame, HHEA configuration;
#   2. iox-roudi, then vcu-can-rx on a two-bus HHEA configuration written to the sandbox's
#      /tmp (sim:battery carries the VIC, OBC and DC-DC messages, sim:vehicle the rest),
#      started and waited for through its "ready" log line;
#   3. idle: vcu-can-rx CPU with no traffic (IDLE_SECONDS);
#   4. two buses: one bench_sim_sender per bus at TWO_BUS_RATE frames/s for TWO_BUS_SECONDS;
#   5. steps on sim:vehicle alone: STEP_RATES frames/s, STEP_SECONDS each.
# CPU of vcu-can-rx over each sending window (from the senders' "sending" line to their
# final line): utime+stime of /proc/<pid>/stat (all threads, clock ticks) and the sum of
# /proc/<pid>/task/*/schedstat run times (ns), in % of one core. After each window the
# heartbeat counters (`vcu status`) must show frames = frames sent and dropped = 0 per bus.
# environment: IDLE_SECONDS (10), TWO_BUS_RATE (4000), TWO_BUS_SECONDS (30),
#              STEP_RATES ("8000 16000 32000 64000"; empty: no steps), STEP_SECONDS (10), SKIP_INPROCESS (unset),
#              PERF_SECONDS (unset: no profile; N: an extra two-bus window under `perf record`),
#              BATCH_WINDOW_US (1000: vcu-can-rx's receive-file batch window),
#              CAN_RX_BIN (BUILD_DIR/bin/vcu-can-rx: another vcu-can-rx to measure, e.g. a copy of
#              an older build kept under BUILD_DIR for a before/after comparison)
# The last line is `RESULT cpu_pct_per_bus=... cpu_pct_two_bus=... wakeups_per_s=... frames_ok=1|0 ...`
# (the two-bus window: CPU % of one core (schedstat) / 2, wake-ups = voluntary context
# switches of all its threads per second).
# exit: 0; 1 when the two-bus run lost or miscounted a frame or something failed to start
# (a step that loses frames is reported and does not count toward the highest rate).
set -euo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
build="$(cd "${1:-$repo/build}" && pwd)"

source "$repo/bench/bench_lib.sh"
bench_isolate "$build" "vcu vcu-can-rx bench_receiver bench_sim_sender" bin/vcu bin/vcu-can-rx bench/bench_receiver bench/bench_sim_sender -- "$0" "$build"

# ---- inside the sandbox ---------------------------------------------------------------
idleSeconds="${IDLE_SECONDS:-10}"
twoBusRate="${TWO_BUS_RATE:-4000}"
twoBusSeconds="${TWO_BUS_SECONDS:-30}"
stepRates="${STEP_RATES-8000 16000 32000 64000}"
stepSeconds="${STEP_SECONDS:-10}"
canRxBin="${CAN_RX_BIN:-$build/bin/vcu-can-rx}"
work=/tmp/can-rx-bench
mkdir -p "$work"
config="$work/vehicle.json"
tick="$(getconf CLK_TCK)"
vcu="$build/bin/vcu"
summary=()
twoBusCpu=0 twoBusTicks=0 twoBusWakeups=0 twoBusSwitches=0 twoBusUsPerFrame=0 twoBusOk=0 twoBusLoad=0


# CPU of process $1: "<ticks> <schedstat ns> <switches>" (ticks: utime+stime of every thread
# that lived; schedstat ns and context switches, voluntary + not, summed over live threads).
cpu_sample() {
  local pid="$1" ticks ns switches voluntary
  ticks="$(awk '{print $14 + $15}' "/proc/$pid/stat")"
  ns="$(cat /proc/"$pid"/task/*/schedstat 2>/dev/null | awk '{ sum += $1 } END { printf "%.0f", sum }')"
  switches="$(cat /proc/"$pid"/task/*/status 2>/dev/null | awk '/ctxt_switches:/ { sum += $2 } END { printf "%.0f", sum }')"
  voluntary="$(cat /proc/"$pid"/task/*/status 2>/dev/null | awk '/^voluntary_ctxt_switches:/ { sum += $2 } END { printf "%.0f", sum }')"
  echo "$ticks $ns $switches $voluntary"
}
ticks_of() { echo "$1" | cut -d' ' -f1; }
ns_of() { echo "$1" | cut -d' ' -f2; }
switches_of() { echo "$1" | cut -d' ' -f3; }
voluntary_of() { echo "$1" | cut -d' ' -f4; }

# The latest heartbeat counters of vcu-can-rx as "name=value" words (one per line).
heartbeat_counters() {
  "$vcu" status --config "$config" --wait 1.2 --stats 2>/dev/null | grep -E '^vcu-can-rx ' | tr ' ' '\n' | grep '=' || true
}

# counter WORDS BUS NAME -> value (0 when absent)
counter() {
  local value
  value="$(grep -E "^$2\.$3=" <<<"$1" | head -n 1 | cut -d= -f2)"
  echo "${value:-0}"
}

# Heartbeat counters once vcu-can-rx has counted `expected` frames on every bus given as
# BUS=EXPECTED, or once they stop changing (two equal beats), or after 20 s.
settled_counters() {
  local previous="" current deadline=$(( $(date +%s) + 20 )) done pair
  while :; do
    current="$(heartbeat_counters)"
    done=1
    for pair in "$@"; do
      (( $(counter "$current" "${pair%%=*}" frames) >= ${pair#*=} )) || done=0
    done
    if (( done )) || [[ -n "$previous" && "$current" == "$previous" ]] || (( $(date +%s) > deadline )); then
      echo "$current"
      return
    fi
    previous="$current"
  done
}

# An error before the windows ran: still one RESULT line, with frames_ok=0.
fail() {
  echo "error: $1" >&2
  echo "RESULT cpu_pct_per_bus=0 cpu_pct_two_bus=0 wakeups_per_s=0 frames_ok=0 error=$2"
  exit 1
}

percent() { awk -v n="$1" -v d="$2" 'BEGIN { printf "%.3f", (d > 0 ? 100 * n / d : 0) }'; }

# run_load LABEL SECONDS RATE BUS...: one sender per bus; CPU of vcu-can-rx over the window.
run_load() {
  local label="$1" seconds="$2" rate="$3"; shift 3
  local buses=("$@") bus before after pids=() logs=() i
  before="$(heartbeat_counters)"
  for bus in "${buses[@]}"; do
    local log="$work/sender-$label-$bus.log"
    : >"$log"
    "$build/bench/bench_sim_sender" --config "$config" --bus "$bus" --rate "$rate" --seconds "$seconds" \
      --seed "$(( ${#pids[@]} + 1 ))" >"$log" 2>&1 &
    pids+=("$!")
    logs+=("$log")
  done
  for log in "${logs[@]}"; do
    wait_until 30 grep -q '^sending on' "$log" || { echo "error: sender did not start: $(cat "$log")" >&2; return 1; }
  done
  local load0 c0 t0 c1 t1
  load0="$(cut -d' ' -f1 /proc/loadavg)"
  c0="$(cpu_sample "$canRxPid")"; t0="$(date +%s%N)"
  for log in "${logs[@]}"; do
    wait_until $(( seconds + 60 )) grep -q '^bench_sim_sender: bus=' "$log" ||
      { echo "error: sender did not finish: $(cat "$log")" >&2; return 1; }
  done
  c1="$(cpu_sample "$canRxPid")"; t1="$(date +%s%N)"
  for i in "${!pids[@]}"; do wait "${pids[$i]}" || true; done

  local wallNs=$(( t1 - t0 ))
  local tickCpu tickNs=$(( ($(ticks_of "$c1") - $(ticks_of "$c0")) * 1000000000 / tick ))
  local schedNs=$(( $(ns_of "$c1") - $(ns_of "$c0") ))
  local switches=$(( $(switches_of "$c1") - $(switches_of "$c0") ))
  local voluntary=$(( $(voluntary_of "$c1") - $(voluntary_of "$c0") ))
  tickCpu="$(percent "$tickNs" "$wallNs")"
  local schedCpu
  schedCpu="$(percent "$schedNs" "$wallNs")"
  local expected=() sentTotal=0
  for i in "${!buses[@]}"; do
    local sent
    sent="$(grep -o 'sent=[0-9]*' "${logs[$i]}" | cut -d= -f2)"
    expected+=("${buses[$i]}=$(( $(counter "$before" "${buses[$i]}" frames) + sent ))")
    sentTotal=$(( sentTotal + sent ))
  done
  after="$(settled_counters "${expected[@]}")"

  local ok=1 line
  echo "== $label: ${#buses[@]} bus(es) x $rate frames/s for $seconds s (load average at start $load0)"
  echo "   vcu-can-rx CPU: $tickCpu % of one core (utime+stime) / $schedCpu % (schedstat), window $(awk -v w="$wallNs" 'BEGIN { printf "%.2f", w / 1e9 }') s"
  awk -v ns="$schedNs" -v n="$sentTotal" -v sw="$switches" -v w="$wallNs" 'BEGIN { if (n > 0) printf "   = %.2f us of CPU per frame (all of vcu-can-rx: wake-ups, iceoryx take, onFrame, rx publish); %.0f context switches/s, %.2f frames per switch\n", ns / n / 1000, sw * 1e9 / w, (sw > 0 ? n / sw : 0) }'
  for i in "${!buses[@]}"; do
    bus="${buses[$i]}"
    local sent busy frames dropped decoded requests unknown late
    sent="$(grep -o 'sent=[0-9]*' "${logs[$i]}" | cut -d= -f2)"
    busy="$(grep -o 'busy=[0-9]*' "${logs[$i]}" | cut -d= -f2)"
    late="$(grep -o 'late_deadlines=[0-9]* max_late_us=[0-9]* max_batch=[0-9]*' "${logs[$i]}")"
    frames=$(( $(counter "$after" "$bus" frames) - $(counter "$before" "$bus" frames) ))
    dropped=$(( $(counter "$after" "$bus" dropped) - $(counter "$before" "$bus" dropped) ))
    decoded=$(( $(counter "$after" "$bus" decoded) - $(counter "$before" "$bus" decoded) ))
    requests=$(( $(counter "$after" "$bus" requests) - $(counter "$before" "$bus" requests) ))
    unknown=$(( $(counter "$after" "$bus" unknown_ids) - $(counter "$before" "$bus" unknown_ids) ))
    line="   $bus: sent $sent (busy $busy; sender $late), can-rx frames $frames, dropped $dropped, decoded $decoded, requests $requests, unknown $unknown"
    if (( frames != sent || dropped != 0 || busy != 0 )); then ok=0; line+="  <- MISMATCH"; fi
    echo "$line"
  done
  if [[ "$label" == two-bus ]]; then
    twoBusCpu="$schedCpu"
    twoBusTicks="$tickCpu"
    twoBusWakeups="$(awk -v s="$voluntary" -v w="$wallNs" 'BEGIN { printf "%.0f", s * 1e9 / w }')"
    twoBusSwitches="$(awk -v s="$switches" -v w="$wallNs" 'BEGIN { printf "%.0f", s * 1e9 / w }')"
    twoBusUsPerFrame="$(awk -v ns="$schedNs" -v n="$sentTotal" 'BEGIN { printf "%.2f", (n > 0 ? ns / n / 1000 : 0) }')"
    twoBusOk="$ok"
    twoBusLoad="$load0"
  fi
  summary+=("$(printf '%-10s %-16s %6s fr/s x %3s s  CPU %7s %% (ticks) %7s %% (schedstat)  %s' "$label" "${buses[*]}" "$rate" "$seconds" "$tickCpu" "$schedCpu" "$( ((ok)) && echo 'all frames counted, 0 dropped' || echo 'FRAMES LOST or not sent')")")
  return $(( ok ? 0 : 2 ))
}

machine
echo "sandbox: $(ls /dev/shm | wc -l) entries in /dev/shm; build $build"

if [[ -z "${SKIP_INPROCESS:-}" ]]; then
  echo "== bench_receiver (in process, config/hhea/vehicle.json)"
  "$build/bench/bench_receiver" --config "$repo/config/hhea/vehicle.json"
fi

# can-rx's batch window (receive file "batchWindowUs"; 1000 is the default).
echo "{\"batchWindowUs\": ${BATCH_WINDOW_US:-1000}}" >"$work/receive.json"

# The two-bus configuration: the VIC, charger and DC-DC traffic on "battery", the rest
# (PDU, Editron, HVLP inverters and the VCU's own commands to them) on "vehicle".
cat >"$config" <<EOF
{
  "comment": "can-rx benchmark: the HHEA messages split over two sim buses",
  "instance": "canrxbench",
  "node": "Vehicle_Control_Unit",
  "dbc": ["$repo/config/hhea/hhea.dbc"],
  "receive": "$work/receive.json",
  "buses": [
    {"name": "battery", "link": "sim:battery", "bitrate": 500000,
     "messages": ["HVESSS1_PGN61590", "PropA_C3_PGN61184", "HVESSD1_PGN61584", "HVESSD2_PGN61585",
                  "HVESSD3_PGN61586", "HVESSHIST_PGN64606", "RQST_VIC_PGN59904", "OBC", "DCDC",
                  "HVESSC1_PGN6912", "S1_ES_PGN61427", "SHM_VCU_to_VIC", "PropA_C4_PGN61184",
                  "RQST_ES_PGN59904", "BMS", "VCU"]},
    {"name": "vehicle", "link": "sim:vehicle", "bitrate": 500000, "messages": "all"}
  ]
}
EOF

iox-roudi -c "$repo/config/iceoryx/roudi.toml" >"$work/roudi.log" 2>&1 &
roudiPid=$!
wait_until 10 test -S /tmp/roudi || fail "iox-roudi did not start: $(cat "$work/roudi.log")" roudi_not_started

"$canRxBin" --config "$config" >"$work/can-rx.log" 2>&1 &
canRxPid=$!
if ! wait_until 30 grep -q ']: ready (' "$work/can-rx.log"; then
  fail "vcu-can-rx not ready: $(cat "$work/can-rx.log")" can_rx_not_ready
fi
echo "== vcu-can-rx ready (pid $canRxPid, $(ls /proc/$canRxPid/task | wc -l) threads)"
wait_until 10 test -n "$(heartbeat_counters)" || fail "no heartbeat from vcu-can-rx" no_heartbeat

c0="$(cpu_sample "$canRxPid")"; t0="$(date +%s%N)"
sleep "$idleSeconds"  # a measurement window, not a readiness wait
c1="$(cpu_sample "$canRxPid")"; t1="$(date +%s%N)"
idleTicks="$(percent $(( ($(ticks_of "$c1") - $(ticks_of "$c0")) * 1000000000 / tick )) $(( t1 - t0 )))"
idleSched="$(percent $(( $(ns_of "$c1") - $(ns_of "$c0") )) $(( t1 - t0 )))"
idleSwitches="$(awk -v s=$(( $(switches_of "$c1") - $(switches_of "$c0") )) -v w=$(( t1 - t0 )) 'BEGIN { printf "%.0f", s * 1e9 / w }')"
idleWakeups="$(awk -v s=$(( $(voluntary_of "$c1") - $(voluntary_of "$c0") )) -v w=$(( t1 - t0 )) 'BEGIN { printf "%.0f", s * 1e9 / w }')"
echo "== idle: vcu-can-rx CPU $idleTicks % (ticks) / $idleSched % (schedstat) over $idleSeconds s without traffic; $idleSwitches context switches/s ($idleWakeups voluntary)"
summary+=("$(printf '%-10s %-16s %6s fr/s x %3s s  CPU %7s %% (ticks) %7s %% (schedstat)' idle - 0 "$idleSeconds" "$idleTicks" "$idleSched")")

status=0
run_load two-bus "$twoBusSeconds" "$twoBusRate" battery vehicle || status=1
highest=0
for rate in $stepRates; do
  if run_load "step-$rate" "$stepSeconds" "$rate" vehicle; then
    (( rate > highest )) && highest=$rate
  fi
done

echo "== summary (load average now $(cut -d' ' -f1-3 /proc/loadavg))"
printf '   %s\n' "${summary[@]}"
echo "   highest step rate on one sim bus with every frame counted and 0 dropped: $highest frames/s"
if [[ -n "${PERF_SECONDS:-}" ]]; then
  # Where vcu-can-rx spends its CPU (flat cpu-clock profile; the VM has no hardware counters).
  # A separate window: sampling costs CPU, so it is not one of the figures above.
  perf record -q -e cpu-clock -F 4000 -p "$canRxPid" -o "$work/perf.data" -- sleep $(( PERF_SECONDS + 4 )) \
    >"$work/perf.log" 2>&1 &
  perfPid=$!
  run_load perf "$PERF_SECONDS" "$twoBusRate" battery vehicle || true
  wait "$perfPid" || true
  echo "== perf: vcu-can-rx by shared object, then the top symbols (two buses x $twoBusRate frames/s)"
  perf report -i "$work/perf.data" --no-children --stdio --sort dso 2>/dev/null | grep '%' | sed 's/  */ /g' |
    head -n 12 || true
  perf report -i "$work/perf.data" --no-children --stdio --sort dso,symbol 2>/dev/null | grep '%' |
    sed -e 's/  */ /g' -e 's/ - - *$//' | cut -c1-150 | head -n 40 || true
fi
echo "== vcu-can-rx log (last lines)"
tail -n 5 "$work/can-rx.log"
kill -TERM "$canRxPid" 2>/dev/null || true
wait "$canRxPid" 2>/dev/null || true
kill -TERM "$roudiPid" 2>/dev/null || true
wait "$roudiPid" 2>/dev/null || true
echo "RESULT cpu_pct_per_bus=$(awk -v c="$twoBusCpu" 'BEGIN { printf "%.3f", c / 2 }') cpu_pct_two_bus=$twoBusCpu" \
  "cpu_pct_two_bus_ticks=$twoBusTicks wakeups_per_s=$twoBusWakeups context_switches_per_s=$twoBusSwitches" \
  "us_per_frame=$twoBusUsPerFrame frames_ok=$twoBusOk idle_cpu_pct=$idleSched idle_wakeups_per_s=$idleWakeups" \
  "rate_per_bus=$twoBusRate seconds=$twoBusSeconds batch_window_us=${BATCH_WINDOW_US:-1000} load_average=$twoBusLoad"
exit "$status"
