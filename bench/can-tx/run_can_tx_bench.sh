#!/usr/bin/env bash
# can-tx benchmark (docs/benchmarks.md, section "can-tx"). Builds nothing: configure and
# build a Release tree first (not under /tmp: the sandbox's /tmp is private), e.g.
#   cmake -S . -B ../build-bench -G Ninja -DCMAKE_BUILD_TYPE=Release
#   ninja -C ../build-bench vcu vcu-can-tx bench_tx_listener
#
# usage: bench/can-tx/run_can_tx_bench.sh [BUILD_DIR] [SECONDS]   (defaults: <repo>/build, 60)
#
# Everything runs inside tests/harness/run_isolated.sh (private /dev/shm, /tmp, network and
# PIDs: its own iox-roudi, LCM multicast on a private lo):
#   1. iox-roudi, then vcu-can-tx with CONFIG (default config/hhea/vehicle.json: the HHEA
#      schedule on sim:vehicle), pinned with taskset to TX_CPU (default 0), awaited through
#      its "ready" log line and a first heartbeat;
#   2. no FSM runs, so can-tx commands its safe values when the FSM's heartbeat has been
#      missing for 3 s (writers_lost = 1); that one-time change is waited for (heartbeat
#      counter) so that it does not fall into the window;
#   3. `vcu signal set internal.tx.keepAlive 1` (can-tx answers it): the keep-alive group,
#      with the five J1939-76 safety pairs, starts sending;
#   4. HOG=1 (default): a busy loop `sh -c 'while :; do :; done'` pinned to HOG_CPU
#      (default 1), i.e. the other core is 100 % busy for the whole window; HOG=0: none;
#   5. bench_tx_listener (pinned to LISTENER_CPU, default HOG_CPU) records sim:vehicle for
#      SECONDS and checks every stream's period error and the safety pairs (its header);
#   6. CPU of vcu-can-tx over the listener's window (from its "listening" line to its
#      "window closed" line): utime+stime of /proc/<pid>/stat (all threads, clock ticks) and
#      the sum of /proc/<pid>/task/*/schedstat run times (ns), in % of one core; context
#      switches and the transmit thread's wake-ups (heartbeat counter "wakeups") per second;
#      for the causes of late frames: its page faults, the hypervisor's steal time and how
#      busy each CPU was (all processes, /proc/stat) over the window, and the scheduling
#      class of each of its threads;
#   7. can-tx's own statistics (`vcu status --stats`): tx.<Msg>.period_err_* and
#      delta_err_* (since can-tx started, so they include the time before the window);
#   8. the platform beside it (issue 27): `cyclictest` on TX_CPU at the transmit thread's
#      priority (SCHED_FIFO RT_PRIORITY, else normal), one thread waking every 1 ms
#      (-i1000), started with the listener for the same SECONDS; its histogram (1 us
#      buckets up to 30 ms) gives the platform's wake-up latency p99 and max. CYCLICTEST=0:
#      not run (platform_* = none).
# Last line: RESULT
#   tx_p99_us: the worst p99 period error of the streams with at least 1,000 intervals in the
#     window, so that 10 or more lie beyond it (in 60 s the 10 and 20 ms streams; for a 1 s
#     stream the p99 is its maximum);
#   tx_max_us: the worst stream's maximum;
#   tx_pooled_p99_us: all streams' intervals together, as cyclictest pools its wake-ups;
#   tx_all_streams_p99_us: the worst p99 of every stream, the 1 s ones' maxima included
#     (this was tx_p99_us before 2026-11-27 23:00);
#   platform_p99_us platform_max_us: cyclictest;
#   delta_p99_us delta_max_us: the worst safety pair's;
#   pair_faults; tx_cpu_pct: schedstat, all threads; spin_cpu_pct: the transmit thread's
#     on-CPU waits for SDMs (heartbeat sdm_spin_us; 0 for a build without it).
# LISTENER_ARGS: more options for bench_tx_listener, e.g. "--late-events 100" or
# "--dump /work/tx.csv" (a path outside /tmp: the sandbox's /tmp is private).
# Set TX_CPU= (empty) to run vcu-can-tx unpinned, LISTENER_CPU= for an unpinned listener.
# RT_PRIORITY=N (1..99, default 50; 0 normal scheduling): run with a copy of the
# configuration in the sandbox's /tmp whose schedule has "realtimePriority": N (the transmit
# thread SCHED_FIFO; needs CAP_SYS_NICE); RT_PRIORITY= (empty): the configuration as it is.
# SDM_SPIN_US=N: the copy also has "sdmSpinUs": N (unset: the schedule's, default 500).
# CAN_TX_BIN=FILE: run this vcu-can-tx instead of BUILD/bin/vcu-can-tx (e.g. a copy of a
# baseline build); a file under /tmp is copied to BUILD/can-tx-bench/ first (the sandbox's
# /tmp is private).
# Only processes this script started are ended, by PID (the sandbox's PID namespace ends
# anything left when the script exits).
# exit: 0 every target met (the listener's, and vcu-can-tx CPU <= CPU_TARGET % of one core,
# default 2); 2 a target missed; 1 something failed to start.
set -euo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
build="$(cd "${1:-$repo/build}" && pwd)"
seconds="${2:-60}"

source "$repo/bench/bench_lib.sh"
if [[ -n "${CAN_TX_BIN:-}" && "${OPENVCU_ISOLATED:-}" != 1 ]]; then
  [[ -x "$CAN_TX_BIN" ]] || { echo "error: CAN_TX_BIN=$CAN_TX_BIN is not an executable" >&2; exit 1; }
  case "$CAN_TX_BIN" in
    "$build"/*) ;;
    /tmp/*)
      mkdir -p "$build/can-tx-bench"
      cp "$CAN_TX_BIN" "$build/can-tx-bench/$(basename "$CAN_TX_BIN")"
      export CAN_TX_BIN="$build/can-tx-bench/$(basename "$CAN_TX_BIN")" ;;
  esac
fi
bench_isolate "$build" "vcu vcu-can-tx bench_tx_listener" bin/vcu bin/vcu-can-tx bench/bench_tx_listener -- "$0" "$build" "$seconds"

# ---- inside the sandbox ---------------------------------------------------------------
config="${CONFIG:-$repo/config/hhea/vehicle.json}"
hog="${HOG:-1}"
hogCpu="${HOG_CPU:-1}"
txCpu="${TX_CPU-0}"
listenerCpu="${LISTENER_CPU-$hogCpu}"
cpuTarget="${CPU_TARGET:-2}"
canTxBin="${CAN_TX_BIN:-$build/bin/vcu-can-tx}"
rtPriority="${RT_PRIORITY-50}"
work=/tmp/can-tx-bench
mkdir -p "$work"
tick="$(getconf CLK_TCK)"
vcu="$build/bin/vcu"
# CPU of process $1: "<ticks> <schedstat ns> <switches>" (ticks: utime+stime of every thread
# that lived; schedstat ns and context switches, voluntary + not, summed over live threads).
cpu_sample() {
  local pid="$1" ticks ns switches
  ticks="$(awk '{print $14 + $15}' "/proc/$pid/stat")"
  ns="$(cat /proc/"$pid"/task/*/schedstat 2>/dev/null | awk '{ sum += $1 } END { printf "%.0f", sum }')"
  switches="$(cat /proc/"$pid"/task/*/status 2>/dev/null | awk '/ctxt_switches:/ { sum += $2 } END { printf "%.0f", sum }')"
  echo "$ticks $ns $switches"
}
ticks_of() { echo "${1%% *}"; }
ns_of() { local rest="${1#* }"; echo "${rest%% *}"; }
switches_of() { echo "${1##* }"; }
# "<minor faults> <major faults>" of process $1 (all threads).
faults_sample() { awk '{print $10, $12}' "/proc/$1/stat"; }
# Steal ticks of CPU $1 (the hypervisor ran something else while this vCPU wanted to run).
steal_sample() { awk -v cpu="cpu$1" '$1 == cpu {print $9}' /proc/stat; }
# "<busy ticks> <all ticks>" of CPU $1 (busy: everything but idle and iowait), machine-wide.
busy_sample() { awk -v cpu="cpu$1" '$1 == cpu { all = 0; for (i = 2; i <= 9; ++i) all += $i; print all - $5 - $6, all }' /proc/stat; }
percent() { awk -v n="$1" -v d="$2" 'BEGIN { printf "%.3f", (d > 0 ? 100 * n / d : 0) }'; }

# The latest heartbeat counters of vcu-can-tx as "name=value" words (one per line).
heartbeat_counters() {
  "$vcu" status --config "$config" --wait 1.2 --stats 2>/dev/null | grep -E '^vcu-can-tx ' | tr ' ' '\n' | grep '=' || true
}
# counter WORDS NAME -> value (0 when absent)
counter() {
  local value
  value="$(grep -E "^$2=" <<<"$1" | head -n 1 | cut -d= -f2)"
  echo "${value:-0}"
}
writer_lost() { (( $(counter "$(heartbeat_counters)" writers_lost) >= 1 )); }

if [[ -n "$rtPriority" ]]; then
  # A copy of the configuration with the schedule's realtimePriority set; relative paths of
  # vehicle.json made absolute so that they still point into the repository.
  configDir="$(cd "$(dirname "$config")" && pwd)"
  scheduleFile="$(jq -r '.schedule // empty' "$config")"
  [[ -n "$scheduleFile" ]] || { echo "error: $config names no schedule file" >&2; exit 1; }
  [[ "$scheduleFile" == /* ]] || scheduleFile="$configDir/$scheduleFile"
  jq --argjson priority "$rtPriority" --arg spin "${SDM_SPIN_US:-}" '
    .realtimePriority = $priority | if $spin == "" then . else .sdmSpinUs = ($spin | tonumber) end' \
    "$scheduleFile" >"$work/schedule.json"
  jq --arg dir "$configDir" --arg schedule "$work/schedule.json" '
    def absolute: if startswith("/") then . else $dir + "/" + . end;
    .dbc |= map(absolute) | .schedule = $schedule |
    with_entries(if (.key | IN("fsm", "gpio", "simulation", "receive", "dashboard", "diagnostics", "web", "telemetry", "safety")) then .value |= absolute else . end)' \
    "$config" >"$work/vehicle.json"
  config="$work/vehicle.json"
  echo "RT_PRIORITY=$rtPriority${SDM_SPIN_US:+ SDM_SPIN_US=$SDM_SPIN_US}: configuration copied to $config" \
    "(\"realtimePriority\": $rtPriority${SDM_SPIN_US:+, \"sdmSpinUs\": $SDM_SPIN_US})"
fi

machine
echo "sandbox: build $build, vcu-can-tx $canTxBin, config $config, window $seconds s"
overlay="$(dirname "$config")/schedule.overlay.json"
[[ -e "$overlay" ]] && echo "note: $overlay exists and is applied by vcu-can-tx: $(tr -d '\n' <"$overlay")"

iox-roudi -c "$repo/config/iceoryx/roudi.toml" >"$work/roudi.log" 2>&1 &
started+=("$!")
wait_until 10 test -S /tmp/roudi || { echo "error: iox-roudi did not start: $(cat "$work/roudi.log")" >&2; exit 1; }

(pinned "$txCpu" "$canTxBin" --config "$config") >"$work/can-tx.log" 2>&1 &
canTxPid=$!
started+=("$canTxPid")
if ! wait_until 30 grep -q ']: ready (' "$work/can-tx.log"; then
  echo "error: vcu-can-tx not ready: $(cat "$work/can-tx.log")" >&2
  exit 1
fi
echo "== vcu-can-tx ready (pid $canTxPid, $(ls /proc/$canTxPid/task | wc -l) threads, affinity $(taskset -pc "$canTxPid" | sed 's/.*: //'))"
wait_until 10 test -n "$(heartbeat_counters)" || { echo "error: no heartbeat from vcu-can-tx" >&2; exit 1; }
if wait_until 15 writer_lost; then
  echo "== no FSM heartbeat: vcu-can-tx has commanded its safe values (writers_lost=1), before the window"
else
  echo "warning: vcu-can-tx did not report writers_lost=1 within 15 s"
fi
"$vcu" signal set --config "$config" internal.tx.keepAlive 1 ||
  { echo "error: vcu signal set internal.tx.keepAlive 1 was not accepted" >&2; exit 1; }

if [[ "$hog" == 1 ]]; then
  (pinned "$hogCpu" sh -c 'while :; do :; done') &
  hogPid=$!
  started+=("$hogPid")
  echo "== CPU hog: pid $hogPid, a busy loop on CPU $hogCpu for the whole window"
else
  echo "== no CPU hog"
fi

before="$(heartbeat_counters)"; tBefore="$(date +%s%N)"
listenerLog="$work/listener.log"
# shellcheck disable=SC2086  # LISTENER_ARGS is split into words on purpose
(pinned "$listenerCpu" "$build/bench/bench_tx_listener" --config "$config" --seconds "$seconds" \
  ${LISTENER_ARGS:-}) >"$listenerLog" 2>&1 &
listenerPid=$!
started+=("$listenerPid")
wait_until 30 grep -q '^listening on' "$listenerLog" || { echo "error: listener did not start: $(cat "$listenerLog")" >&2; exit 1; }
cyclictestLog="$work/cyclictest.log"
if [[ "${CYCLICTEST:-1}" == 1 ]]; then
  command -v cyclictest >/dev/null || { echo "error: cyclictest not installed (apt-get install rt-tests; CYCLICTEST=0 skips it)" >&2; exit 1; }
  policy=(--policy=normal)
  (( ${rtPriority:-0} > 0 )) && policy=(-p "$rtPriority")
  (pinned "$txCpu" cyclictest -m -q -t1 ${txCpu:+-a "$txCpu"} "${policy[@]}" -i1000 -D "$seconds" -h 30000) \
    >"$cyclictestLog" 2>&1 &
  cyclictestPid=$!
  started+=("$cyclictestPid")
fi
load0="$(cut -d' ' -f1 /proc/loadavg)"
f0="$(faults_sample "$canTxPid")"; s0="$(steal_sample 0) $(steal_sample 1)"; b0="$(busy_sample 0) $(busy_sample 1)"
c0="$(cpu_sample "$canTxPid")"; t0="$(date +%s%N)"
wait_until $(( seconds + 30 )) grep -q '^window closed' "$listenerLog" ||
  { echo "error: listener did not finish: $(cat "$listenerLog")" >&2; exit 1; }
c1="$(cpu_sample "$canTxPid")"; t1="$(date +%s%N)"
f1="$(faults_sample "$canTxPid")"; s1="$(steal_sample 0) $(steal_sample 1)"; b1="$(busy_sample 0) $(busy_sample 1)"
load1="$(cut -d' ' -f1 /proc/loadavg)"
listenerStatus=0
wait "$listenerPid" || listenerStatus=$?
forget "$listenerPid"
if [[ -n "${cyclictestPid:-}" ]]; then
  wait_until 20 grep -q '^# Max Latencies' "$cyclictestLog" || echo "warning: cyclictest did not finish: $(tail -n 3 "$cyclictestLog")"
  wait "$cyclictestPid" 2>/dev/null || true
  forget "$cyclictestPid"
fi
if [[ "$hog" == 1 ]]; then
  kill -TERM "$hogPid" 2>/dev/null || true
  wait "$hogPid" 2>/dev/null || true
  forget "$hogPid"
fi
after="$(heartbeat_counters)"; tAfter="$(date +%s%N)"

cat "$listenerLog"

wallNs=$(( t1 - t0 ))
tickCpu="$(percent $(( ($(ticks_of "$c1") - $(ticks_of "$c0")) * 1000000000 / tick )) "$wallNs")"
schedCpu="$(percent $(( $(ns_of "$c1") - $(ns_of "$c0") )) "$wallNs")"
switches=$(( $(switches_of "$c1") - $(switches_of "$c0") ))
wakeups=$(( $(counter "$after" wakeups) - $(counter "$before" wakeups) ))
framesSent=$(( $(counter "$after" vehicle.frames_sent) - $(counter "$before" vehicle.frames_sent) ))
echo "== vcu-can-tx over the window ($(awk -v w="$wallNs" 'BEGIN { printf "%.2f", w / 1e9 }') s, load average $load0 at the start, $load1 at the end)"
echo "   CPU: $tickCpu % of one core (utime+stime) / $schedCpu % (schedstat)"
awk -v s="$switches" -v k="$wakeups" -v f="$framesSent" -v w="$wallNs" -v hb="$(( tAfter - tBefore ))" 'BEGIN {
  printf "   %.0f context switches/s (all threads); transmit-thread wake-ups %.0f/s and frames sent %.0f/s (heartbeat counters, between two heartbeats %.1f s apart, +-1 s)\n",
    s * 1e9 / w, k * 1e9 / hb, f * 1e9 / hb, hb / 1e9 }'
read -r minor0 major0 <<<"$f0"; read -r minor1 major1 <<<"$f1"
read -r steal00 steal10 <<<"$s0"; read -r steal01 steal11 <<<"$s1"
echo "   page faults in the window: $(( minor1 - minor0 )) minor, $(( major1 - major0 )) major;" \
  "steal time (hypervisor): CPU 0 $(( (steal01 - steal00) * 1000 / tick )) ms, CPU 1 $(( (steal11 - steal10) * 1000 / tick )) ms"
read -r busy00 all00 busy10 all10 <<<"$b0"; read -r busy01 all01 busy11 all11 <<<"$b1"
echo "   machine: CPU 0 busy $(percent $(( busy01 - busy00 )) $(( all01 - all00 ))) %, CPU 1 busy" \
  "$(percent $(( busy11 - busy10 )) $(( all11 - all10 ))) % over the window (all processes, /proc/stat)"
echo "   threads (tid, class, rt priority, last CPU, name):"
ps -L -o tid=,cls=,rtprio=,psr=,comm= -p "$canTxPid" | sed 's/^ */     /'
echo "== vcu-can-tx's own statistics (heartbeat, since it started; us)"
printf '   %-24s %8s %6s %6s %7s %7s %7s %7s %7s %7s\n' message frames missed fail per_p50 per_p99 per_max dlt_p50 dlt_p99 dlt_max
grep -E '^tx\.[^.]+\.frames=' <<<"$after" | sed -E 's/^tx\.([^.]+)\.frames=.*/\1/' | while read -r message; do
  c() { local v; v="$(grep -E "^tx\.$message\.$1=" <<<"$after" | cut -d= -f2)"; echo "${v:--}"; }
  printf '   %-24s %8s %6s %6s %7s %7s %7s %7s %7s %7s\n' "$message" "$(c frames)" "$(c missed)" "$(c send_failures)" \
    "$(c period_err_p50_us)" "$(c period_err_p99_us)" "$(c period_err_max_us)" \
    "$(c delta_err_p50_us)" "$(c delta_err_p99_us)" "$(c delta_err_max_us)"
done
echo "   bus: frames_sent=$(counter "$after" vehicle.frames_sent) send_failures=$(counter "$after" vehicle.send_failures) publish_failures=$(counter "$after" vehicle.publish_failures) inbox_refused=$(counter "$after" inbox_refused)"

status=0
cpuMet="$(awk -v c="$tickCpu" -v s="$schedCpu" -v t="$cpuTarget" 'BEGIN { print (c <= t && s <= t) ? "met" : "NOT met" }')"
[[ "$cpuMet" == met ]] || status=2
(( listenerStatus == 0 )) || status=2
echo "== summary ($( [[ "$hog" == 1 ]] && echo "busy loop on CPU $hogCpu" || echo "no hog"), vcu-can-tx on CPU ${txCpu:-any}${RT_PRIORITY:+ with its transmit thread SCHED_FIFO $RT_PRIORITY}, listener on CPU ${listenerCpu:-any})"
grep '^bench_tx_listener:' "$listenerLog" | sed 's/^/   /'
echo "   listener targets (p99 <= 200 us, max <= 1000 us, no pair fault): $( ((listenerStatus == 0)) && echo met || echo "NOT met (exit $listenerStatus)")"
echo "   vcu-can-tx CPU $tickCpu % (ticks) / $schedCpu % (schedstat) of one core, target <= $cpuTarget %: $cpuMet"
spins=$(( $(counter "$after" sdm_spins) - $(counter "$before" sdm_spins) ))
spinUs=$(( $(counter "$after" sdm_spin_us) - $(counter "$before" sdm_spin_us) ))
spinCpu="$(percent $(( spinUs * 1000 )) "$(( tAfter - tBefore ))")"
echo "   wake guard at the end (heartbeat sdm_guard_us; 0 for a build without it): $(counter "$after" sdm_guard_us) us"
echo "   on-CPU waits for SDMs (heartbeat sdm_spins, sdm_spin_us): $spins, $spinUs us = $spinCpu % of one core" \
  "(between two heartbeats $(awk -v w="$(( tAfter - tBefore ))" 'BEGIN { printf "%.1f", w / 1e9 }') s apart)"

# The platform: cyclictest's histogram (1 us buckets; "# Histogram Overflows" above 30 ms,
# not in "# Total"), nearest-rank p99.
platformP99=none; platformMax=none
if [[ -s "$cyclictestLog" ]] && grep -q '^# Max Latencies' "$cyclictestLog"; then
  read -r platformP99 platformMax platformCount platformP999 platformOver1ms < <(awk '
    /^[0-9]+ [0-9]+$/ { count[$1 + 0] = $2 + 0; total += $2; if ($1 + 0 > top) top = $1 + 0 }
    /^# Max Latencies:/ { max = $4 + 0 }
    /^# Histogram Overflows:/ { over = $4 + 0 }
    END {
      all = total + over
      r99 = int(0.99 * all); if (r99 < 0.99 * all) r99++
      r999 = int(0.999 * all); if (r999 < 0.999 * all) r999++
      p99 = "30000"; p999 = "30000"; seen = 0; over1 = over
      for (b = 0; b <= top; ++b) {
        seen += count[b]
        if (b > 1000) over1 += count[b]
        if (seen >= r99 && p99 == "30000") p99 = b
        if (seen >= r999 && p999 == "30000") p999 = b
      }
      print p99, max, all, p999, over1
    }' "$cyclictestLog")
  echo "== platform: cyclictest on CPU ${txCpu:-any}, $( (( ${rtPriority:-0} > 0 )) && echo "SCHED_FIFO $rtPriority" || echo normal)," \
    "-i1000, same window: $platformCount wake-ups, latency p99 $platformP99 us, p99.9 $platformP999 us," \
    "max $platformMax us, $platformOver1ms over 1 ms"
fi
echo "== vcu-can-tx log (last lines)"
tail -n 5 "$work/can-tx.log"
# the worst stream's and the worst pair's p99 and max, from the listener's target lines
txP99="$(sed -n 's/^bench_tx_listener:.* sampled_stream_p99_us=\([0-9.]*\).*/\1/p' "$listenerLog")"
txAllP99="$(sed -n 's/^bench_tx_listener:.* worst_stream_p99_us=\([0-9.]*\).*/\1/p' "$listenerLog")"
txPooledP99="$(sed -n 's/^bench_tx_listener:.* period_p99_us=\([0-9.]*\).*/\1/p' "$listenerLog")"
txMax="$(sed -n 's/^bench_tx_listener:.* worst_stream_max_us=\([0-9.]*\).*/\1/p' "$listenerLog")"
deltaP99="$(sed -n 's/^   p99 <= .*pair delta \([0-9.]*\) us)$/\1/p' "$listenerLog")"
deltaMax="$(sed -n 's/^   max <= .*pair delta \([0-9.]*\) us)$/\1/p' "$listenerLog")"
pairFaults="$(sed -n 's/^bench_tx_listener:.* pair_faults=\([0-9]*\).*/\1/p' "$listenerLog")"
echo "RESULT tx_p99_us=${txP99:-none} tx_max_us=${txMax:-none} tx_pooled_p99_us=${txPooledP99:-none}" \
  "tx_all_streams_p99_us=${txAllP99:-none} platform_p99_us=$platformP99" \
  "platform_max_us=$platformMax delta_p99_us=${deltaP99:-none} delta_max_us=${deltaMax:-none}" \
  "pair_faults=${pairFaults:-none} tx_cpu_pct=$schedCpu spin_cpu_pct=$spinCpu"
exit "$status"
