#!/usr/bin/env bash
# vcu-telemetry benchmark (issue 25; docs/benchmarks.md, "Telemetry: CPU, RSS, drain and
# payload"). Builds nothing: configure and build a Release tree first (not under /tmp: the
# sandbox's /tmp is private), e.g.
#   cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release
#   ninja -C build vcu-telemetry bench_telemetry_load
#
# usage: bench/telemetry/run_telemetry_bench.sh [BUILD_DIR] [SECONDS]   (defaults: <repo>/build, 60)
#   environment: OUTAGE (s, default 30), FILL_SMALL (records, default 20000, 300 bytes each),
#   FILL_BIG (records, default 500, 32 KiB each), QUEUE_MB (maxQueueMB, default 64), PERF (1: perf record 20 s if perf works; default 1)
#
# Everything runs inside tests/harness/run_isolated.sh (private network, /dev/shm, /tmp, PIDs):
#   0. a copy of config/hhea whose telemetry.json lists 200 DBC signals at maxRateHz 10,
#      deadband 0 (bench_telemetry_load select), broker mqtt://127.0.0.1:1883, queue in /tmp;
#   1. a real mosquitto (anonymous, loopback), the watcher (bench_telemetry_load watch: one
#      line per message, with the size of the binary prototype of each signals message), the
#      writer (bench_telemetry_load write: each of the 200 signals gets a new value 20 times a
#      second, so neither the rate limit's phase nor the deadband ever leaves a signal out)
#      and the real vcu-telemetry; 5 s to settle after its "online";
#   2. steady: over SECONDS, vcu-telemetry's CPU (utime+stime of /proc/PID/stat and the sum of
#      /proc/PID/task/*/schedstat, in % of one core; per thread with its context switches/s),
#      VmRSS every second (max), VmHWM, RSS and PSS by kind, the largest mappings;
#      from the watcher: messages/s and bytes/s per topic, samples/s, the binary form's bytes/s;
#   3. perf record -g of vcu-telemetry for 20 s (when perf works here): where its CPU goes;
#   4. encode: bench_telemetry_load encode, in process: Engine::sample and Engine::tick (JSON)
#      against the binary prototype for the same 200 x 10 samples per second;
#   5. outage: mosquitto SIGKILLed for OUTAGE s while the writer goes on, restarted (vcu-telemetry
#      held with SIGSTOP until the new watcher's subscription is confirmed); from the watcher: the records made before vcu-telemetry reconnected (the backlog), the time from
#      its "online" to the last of them, records/s and MB/s;
#   6. prefilled drains: vcu-telemetry stopped (SIGTERM), its queue given FILL_SMALL records of
#      300 bytes (then FILL_BIG of 32 KiB: a full signals message) by bench_telemetry_load fill,
#      vcu-telemetry started again: the time from its "online" to the last filled record.
# Output: the sections above, then one line `RESULT key=value ...`.
# exit: 0 targets met (steady CPU <= 1 % of one core, RSS <= 15 MB), 2 a target missed,
# 1 something failed (also: vcu-telemetry logged an error, e.g. a record it could not queue). Only processes this script started are ended, by PID.
set -euo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
build="$(cd "${1:-$repo/build}" && pwd)"
seconds="${2:-60}"

source "$repo/bench/bench_lib.sh"
bench_isolate "$build" "vcu-telemetry bench_telemetry_load" bin/vcu-telemetry bench/bench_telemetry_load -- "$0" "$build" "$seconds"

# ---- inside the sandbox ---------------------------------------------------------------
outage="${OUTAGE:-30}"
fillSmall="${FILL_SMALL:-20000}"
fillBig="${FILL_BIG:-500}"
usePerf="${PERF:-1}"
queueMb="${QUEUE_MB:-64}"
work=/tmp/telemetry-bench
rm -rf "$work"
mkdir -p "$work/vehicle" "$work/broker"
tick="$(getconf CLK_TCK)"
load="$build/bench/bench_telemetry_load"
telemetry="$build/bin/vcu-telemetry"

machine
echo "date $(date -u '+%Y-%m-%d %H:%M UTC')"

# 0. the configuration
cp "$repo"/config/hhea/* "$work/vehicle/"
config="$work/vehicle/vehicle.json"
signals="$("$load" select --config "$config" --count 200 --rate-hz 10)"
jq -n --argjson signals "$signals" --arg queue "$work/queue" --argjson mb "$queueMb" \
  '{broker: "mqtt://127.0.0.1:1883", vehicleId: "bench-01", queueFolder: $queue, maxQueueMB: $mb, signals: $signals}' \
  >"$work/vehicle/telemetry.json"
# max_queued_messages 0: no limit on what the broker holds for the watcher (QoS 1). With the
# default 1000 a drain faster than the watcher reads makes the broker drop messages to it.
printf 'listener 1883 127.0.0.1\nallow_anonymous true\npersistence false\nmax_queued_messages 0\nuser root\nlog_dest file %s\n' "$work/broker/mosquitto.log" >"$work/broker/mosquitto.conf"

brokerPid=""
start_broker() {
  : >"$work/broker/mosquitto.log"
  /usr/sbin/mosquitto -c "$work/broker/mosquitto.conf" >>"$work/broker/mosquitto.out" 2>&1 &
  brokerPid=$!
  started+=("$brokerPid")
  wait_until 10 grep -q "running" "$work/broker/mosquitto.log" || { echo "error: mosquitto did not start: $(tail -n 3 "$work/broker/mosquitto.log")" >&2; exit 1; }
}
watchPid=""
start_watcher() {  # FILE
  "$load" watch --port 1883 --out "$1" 2>"$1.err" &
  watchPid=$!
  started+=("$watchPid")
  wait_until 10 grep -q subscribed "$1.err" || { echo "error: the watcher did not subscribe: $(cat "$1.err")" >&2; exit 1; }
}
stop_pid() {  # PID SIGNAL
  kill "-$2" "$1" 2>/dev/null || true
  wait "$1" 2>/dev/null || true
  forget "$1"
}
telemetryPid=""
start_telemetry() {
  "$telemetry" --config "$config" >>"$work/telemetry.log" 2>&1 &
  telemetryPid=$!
  started+=("$telemetryPid")
}
# the line number of the first "online" status in FILE after line FROM (waits up to 40 s)
online_line() {
  local file="$1" from="$2" line=""
  wait_until 40 awk -v f="$from" 'NR > f && $3 == "status" { found = 1 } END { exit !found }' "$file" ||
    { echo "error: vcu-telemetry did not come online: $(tail -n 5 "$work/telemetry.log")" >&2; exit 1; }
  awk -v f="$from" 'NR > f && $3 == "status" { print NR; exit }' "$file"
}
cpu_sample() {  # PID -> "<ticks> <schedstat ns>"
  local ticks ns
  ticks="$(awk '{print $14 + $15}' "/proc/$1/stat")"
  ns="$(cat /proc/"$1"/task/*/schedstat 2>/dev/null | awk '{ sum += $1 } END { printf "%.0f", sum }')"
  echo "$ticks $ns"
}

# 1. broker, watcher, writer, vcu-telemetry
start_broker
start_watcher "$work/steady.txt"
"$load" write --config "$config" --telemetry "$work/vehicle/telemetry.json" --write-hz 20 >"$work/writer.log" 2>&1 &
writerPid=$!
started+=("$writerPid")
start_telemetry
online_line "$work/steady.txt" 0 >/dev/null
sleep 5
echo "== vcu-telemetry (pid $telemetryPid, $(ls /proc/$telemetryPid/task | wc -l) threads): 200 signals at maxRateHz 10, written at 20 Hz"

# "<tid> <comm> <schedstat ns> <switches>" per thread of process $1
thread_sample() {
  local task
  for task in /proc/"$1"/task/*; do
    echo "$(basename "$task") $(tr ' ' '_' <"$task/comm") $(awk '{print $1}' "$task/schedstat") $(awk '/ctxt_switches:/ { s += $2 } END { print s }' "$task/status")"
  done
}

# 2. steady
thread_sample "$telemetryPid" >"$work/threads0.txt"
read -r k0 n0 <<<"$(cpu_sample "$telemetryPid")"
read -r bk0 bn0 <<<"$(cpu_sample "$brokerPid")"
t0ms=$(( $(date +%s%N) / 1000000 )); t0=$(date +%s%N)
rssMax=0
for (( i = 0; i < seconds; i++ )); do
  sleep 1
  rss="$(awk '/^VmRSS:/ {print $2}' "/proc/$telemetryPid/status")"
  (( rss > rssMax )) && rssMax=$rss
done
read -r k1 n1 <<<"$(cpu_sample "$telemetryPid")"
thread_sample "$telemetryPid" >"$work/threads1.txt"
read -r bk1 bn1 <<<"$(cpu_sample "$brokerPid")"
t1=$(date +%s%N); t1ms=$(( t1 / 1000000 ))
hwm="$(awk '/^VmHWM:/ {print $2}' "/proc/$telemetryPid/status")"
rssParts="$(awk '/^Rss(Anon|File|Shmem):/ { printf "%s %s kB, ", $1, $2 }' "/proc/$telemetryPid/status")"
wall=$(( t1 - t0 ))
cpuTicks="$(awk -v k=$(( k1 - k0 )) -v t="$tick" -v w="$wall" 'BEGIN { printf "%.2f", 100 * k / t * 1e9 / w }')"
cpuSched="$(awk -v n=$(( n1 - n0 )) -v w="$wall" 'BEGIN { printf "%.2f", 100 * n / w }')"
brokerCpu="$(awk -v n=$(( bn1 - bn0 )) -v w="$wall" 'BEGIN { printf "%.2f", 100 * n / w }')"
echo "== steady ($(awk -v w="$wall" 'BEGIN { printf "%.1f", w / 1e9 }') s)"
echo "   vcu-telemetry CPU: $cpuTicks % of one core (ticks), $cpuSched % (schedstat); VmRSS max $rssMax kB, VmHWM $hwm kB"
echo "   VmRSS at the end: ${rssParts%, } (RssShmem: the signal table's pages it touched)"
echo "   PSS (its share of pages shared with other processes): $(awk '/^Pss(_Anon|_File|_Shmem)?:/ { printf "%s %s kB, ", $1, $2 }' "/proc/$telemetryPid/smaps_rollup" | sed 's/, $//')"
echo "   per thread (CPU in % of one core, context switches/s):"
awk -v w="$wall" 'NR == FNR { ns[$1] = $3; sw[$1] = $4; next }
  ($1 in ns) { printf "   %-16s %6.3f %% %7.1f/s\n", $2, 100 * ($3 - ns[$1]) / w, ($4 - sw[$1]) * 1e9 / w }' \
  "$work/threads0.txt" "$work/threads1.txt"
echo "   the largest mappings by Rss (kB, /proc/PID/smaps):"
awk '/^[0-9a-f]+-[0-9a-f]+ / { name = (NF >= 6 ? $6 : "[anon]") } /^Rss:/ { rss[name] += $2 }
     END { for (n in rss) printf "%8d %s\n", rss[n], n }' "/proc/$telemetryPid/smaps" | sort -rn | head -n 8 | sed 's/^/   /'
echo "   mosquitto CPU: $brokerCpu % (schedstat)"
awk -v a="$t0ms" -v b="$t1ms" '$1 >= a && $1 < b {
    n[$3]++; bytes[$3] += $4
    if ($3 == "signals") { samples += $7; bin += $8 }
  } END {
    s = (b - a) / 1000
    for (topic in n) printf "   %-8s %6.2f messages/s %9.0f bytes/s\n", topic, n[topic] / s, bytes[topic] / s
    printf "   samples %.0f/s; signals as JSON %.0f bytes/s (%.1f bytes/sample), as the binary prototype %.0f bytes/s (%.1f bytes/sample)\n",
      samples / s, bytes["signals"] / s, bytes["signals"] / (samples ? samples : 1), bin / s, bin / (samples ? samples : 1)
    printf "STEADY samples_per_s=%.0f json_bytes_per_s=%.0f binary_bytes_per_s=%.0f\n", samples / s, bytes["signals"] / s, bin / s
  }' "$work/steady.txt" | tee "$work/steady.summary" | grep -v '^STEADY'
steadyLine="$(grep '^STEADY' "$work/steady.summary" | cut -d' ' -f2-)"

# 3. perf
if [[ "$usePerf" == 1 ]] && command -v perf >/dev/null &&
   perf record -q -F 2999 -g -p "$telemetryPid" -o "$work/perf.data" -- sleep 20 >"$work/perf.log" 2>&1; then
  echo "== perf record -F 2999 -g, 20 s: vcu-telemetry's samples by shared object and symbol (self)"
  perf report -i "$work/perf.data" --stdio --no-children --sort dso,symbol 2>/dev/null |
    grep -E '^ +[0-9.]+%' | head -n 25 | sed -e 's/ *- *- *$//' -e 's/^/   /' || true
  echo "   by shared object:"
  perf report -i "$work/perf.data" --stdio --no-children --sort dso 2>/dev/null | grep -E '^ +[0-9.]+%' | head -n 10 |
    sed -e 's/ *$//' -e 's/^/   /' || true
  echo "   samples: $(perf report -i "$work/perf.data" --stdio 2>/dev/null | sed -n 's/^# Samples: \([^ ]*\).*/\1/p' | head -n 1)"
else
  echo "== perf: not available here ($(tail -n 1 "$work/perf.log" 2>/dev/null || echo 'PERF=0'))"
fi

# 4. encode
echo "== encode (in process, 60 simulated seconds of 200 signals x 10 samples)"
"$load" encode --config "$config" --telemetry "$work/vehicle/telemetry.json" --seconds 60 | tee "$work/encode.txt" | sed 's/^/   /'
encodeLine="$(awk '{ for (i = 2; i < NF; i += 2) if ($i != "seconds" && $i != "signals") printf "encode_%s=%s ", $i, $(i + 1) }' "$work/encode.txt")"

# 5. outage
echo "== outage: mosquitto SIGKILLed for $outage s"
stop_pid "$brokerPid" KILL
stop_pid "$watchPid" TERM
sleep "$outage"
# vcu-telemetry is stopped (SIGSTOP) while the broker starts and the new watcher subscribes, so
# that it cannot reconnect and send the backlog before the watcher listens; then SIGCONT
kill -STOP "$telemetryPid"
brokerStartMs=$(( $(date +%s%N) / 1000000 ))
start_broker
start_watcher "$work/drain.txt"
kill -CONT "$telemetryPid"
onlineLine="$(online_line "$work/drain.txt" 0)"
sleep 5
read -r dk dn <<<"$(cpu_sample "$telemetryPid")"
awk -v l="$onlineLine" -v bs="$brokerStartMs" '
  NR == l { online = $1; next }
  NR > l && $5 != "-" && $6 < online { n++; bytes += $4; last = $1; if (first == "") first = $1 }
  END {
    d = (last - online) / 1000
    printf "   reconnect %.1f s after the broker started; backlog %d records (%.2f MB) arrived %.3f s after \"online\" (first after %.3f s): %.0f records/s, %.2f MB/s\n",
      (online - bs) / 1000, n, bytes / 1e6, d, (first - online) / 1000, (d > 0 ? n / d : 0), (d > 0 ? bytes / 1e6 / d : 0)
    printf "OUTAGE outage_backlog_records=%d outage_drain_s=%.3f outage_records_per_s=%.0f\n", n, d, (d > 0 ? n / d : 0)
  }' "$work/drain.txt" | tee "$work/outage.summary" | grep -v '^OUTAGE'
outageLine="$(grep '^OUTAGE' "$work/outage.summary" | cut -d' ' -f2-)"
# the seq across the outage: no gap among the records the watchers saw
awk '$5 != "-" { print $5 }' "$work/steady.txt" "$work/drain.txt" | sort -n | uniq |
  awk 'NR > 1 && $1 != prev + 1 { gaps++ } { prev = $1 } END { printf "   seq gaps across the outage: %d\n", gaps }'

# 6. prefilled drains
fillResults=""
drain_fill() {  # NAME RECORDS BYTES
  local name="$1" records="$2" bytes="$3" from lastSeq line k0 n0 k1 n1
  stop_pid "$telemetryPid" TERM
  "$load" fill --queue "$work/queue" --records "$records" --bytes "$bytes" | tee "$work/fill-$name.txt" | sed 's/^/   /'
  lastSeq="$(sed -n 's/.*last seq \([0-9]*\).*/\1/p' "$work/fill-$name.txt")"
  from="$(wc -l <"$work/drain.txt")"
  start_telemetry
  read -r k0 n0 <<<"$(cpu_sample "$telemetryPid")"
  line="$(online_line "$work/drain.txt" "$from")"
  wait_until 120 awk -v s="$lastSeq" '$5 == s { found = 1 } END { exit !found }' "$work/drain.txt" ||
    { echo "error: the filled records did not all arrive" >&2; exit 1; }
  read -r k1 n1 <<<"$(cpu_sample "$telemetryPid")"
  awk -v l="$line" -v s="$lastSeq" -v name="$name" -v cpu=$(( n1 - n0 )) '
    NR == l { online = $1 }
    NR > l && $3 == "bench" { n++; bytes += $4; if ($5 == s) last = $1 }
    END {
      d = (last - online) / 1000
      printf "   %s: %d records (%.1f MB) %.3f s after \"online\": %.0f records/s, %.2f MB/s; vcu-telemetry CPU %.2f s in that time\n",
        name, n, bytes / 1e6, d, n / d, bytes / 1e6 / d, cpu / 1e9
      printf "FILL fill_%s_records_per_s=%.0f fill_%s_mb_per_s=%.2f\n", name, n / d, name, bytes / 1e6 / d
    }' "$work/drain.txt" | tee "$work/fill-$name.summary" | grep -v '^FILL'
  fillResults+="$(grep '^FILL' "$work/fill-$name.summary" | cut -d' ' -f2-) "
}
echo "== prefilled drains (vcu-telemetry restarted on a queue of N records; the writer goes on)"
drain_fill small "$fillSmall" 300
drain_fill big "$fillBig" 32000

echo "== vcu-telemetry log: errors and warnings but the DBC's ($(grep -c ' error ' "$work/telemetry.log" || true) error lines)"
grep -E ' (error|warning) ' "$work/telemetry.log" | grep -v 'hhea.dbc' | sort | uniq -c | sort -rn | head -n 5 | cut -c1-220 | sed 's/^/   /' || true

status=0
logErrors="$(grep -c ' error ' "$work/telemetry.log" || true)"
awk -v c="$cpuSched" -v r="$rssMax" -v h="$hwm" 'BEGIN { exit !(c <= 1.0 && r <= 15360 && h <= 15360) }' || status=2
echo "   targets: steady CPU <= 1 % of one core, RSS <= 15 MB: $( ((status == 0)) && echo met || echo "NOT met")"
if (( logErrors > 0 )); then
  echo "   vcu-telemetry logged $logErrors error(s): the figures above are not those of a healthy run"
  status=1
fi
echo "RESULT cpu_pct=$cpuSched cpu_ticks_pct=$cpuTicks rss_max_kb=$rssMax hwm_kb=$hwm broker_cpu_pct=$brokerCpu $steadyLine ${encodeLine}${outageLine} ${fillResults}log_errors=$logErrors targets_met=$( ((status == 0)) && echo 1 || echo 0)"
exit "$status"
