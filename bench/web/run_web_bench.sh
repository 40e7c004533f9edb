#!/bin/bash
# vcu-web at full HHEA traffic (docs/benchmarks.md "## vcu-web"; issue 23, "Benchmark").
# Runs inside tests/harness/run_isolated.sh (private /dev/shm, /tmp, network):
#   tests/harness/run_isolated.sh --keep $PWD -- env OPENVCU_BIN=$PWD/build/bin bench/web/run_web_bench.sh [SECONDS] [SAMPLES]
# The HHEA stack under supervisord with the simulated vehicle, driven to Driving (as
# bench/stack/run_stack_bench.sh). vcu-web is supervisord's program `web` (turned on in the
# copy of openvcu.conf as ./run.sh does, on 127.0.0.1:$WEB_PORT, default 8080; its data folder
# OPENVCU_RUN/data; no users file: read-only), or, with a configuration that has no such
# program, started here with the same arguments and --www services/web/www. Then, one after
# the other:
#   1. three windows of SECONDS (default 30) with 0, 1 and 10 live pages: bench/web/web_clients.py
#      holds that many GET /api/live?signals=<4 signals> streams, each read and parsed as a
#      browser's EventSource does; vcu-web's CPU over the window is the sum of
#      /proc/PID/task/*/schedstat (ns on a CPU, all threads; utime + stime as a cross-check),
#      its VmRSS read at the end of the window; the clients report their update events/s;
#   2. bench/web/dom_latency.py: headless Chromium (chromium-driver, python3-selenium) opens the
#      page and measures, for SAMPLES (default 500) changes of a signal's text in the DOM, the
#      time from the table write (event.t - ageMs) to the DOM change.
# The 4 signals (WEB_BENCH_SIGNALS overrides): the bus signals whose values change while the
# simulated vehicle drives (a scan of the received and internal signals): the battery's SOC (HVESSD2, about 9
# changes/s) and voltage (HVESSD1, the HMI's voltage dial), the PDU's and the Editron's view of
# the HV bus voltage (each < 1 change/s); vcu-can-rx writes each every 100 ms.
# Ends with one line
#   RESULT web_cpu_pct_1=.. web_cpu_pct_10=.. web_cpu_pct_0=.. web_rss_mb=<max> dom_latency_p50_ms=.. dom_latency_p99_ms=.. events_per_s_per_client=<10-page mean>
set -uo pipefail
seconds=${1:-30}
samples=${2:-500}
root=$(cd "$(dirname "$0")/../.." && pwd)
bin=${OPENVCU_BIN:-$root/build/bin}
config=$root/config/hhea/vehicle.json
signals=${WEB_BENCH_SIGNALS:-VIC.HVESSD2_PGN61585.HS_FastUpdSOC,VIC.HVESSD1_PGN61584.HS_ULvl,PDU.PDU_Tx_2.HV_DC_1_U_V,Editron.ST_MOT_3.st_mot_u_dc}
port=${WEB_PORT:-8080}
python=/usr/bin/python3  # Debian's, for python3-selenium
here=$root/bench/web
if [ "${OPENVCU_ISOLATED:-}" != 1 ]; then
  echo "error: run me inside tests/harness/run_isolated.sh (see the first lines of $0)" >&2
  exit 2
fi
if [ ! -x "$bin/vcu-web" ]; then echo "error: $bin/vcu-web is missing (build the target vcu-web)" >&2; exit 2; fi
run=$(mktemp -d)
export OPENVCU_BIN=$bin OPENVCU_CONFIG=$config OPENVCU_RUN=$run OPENVCU_ROUDI=$root/config/iceoryx/iox-roudi.sh
mkdir -p "$run/data"
sed -e 's/^;user=root.*/user=root/' \
  -e '/^\[program:web\]/,/^$/{s/^autostart=false/autostart=true/;s/127\.0\.0\.1:8080/127.0.0.1:'"$port"'/}' \
  "$root/config/supervisor/openvcu.conf" > "$run/openvcu.conf"
supervisord -n -c "$run/openvcu.conf" > "$run/supervisord.out" 2>&1 &
webPid=""
ownWeb=""
cleanup() {
  [ -n "$ownWeb" ] && kill "$ownWeb" 2>/dev/null
  supervisorctl -c "$run/openvcu.conf" shutdown >/dev/null 2>&1
  wait
}
trap cleanup EXIT
fail() { echo "error: $*" >&2; echo "logs in $run" >&2; exit 1; }

# up when the five services beat (vcu status lists one line per service heard)
up=0
for _ in $(seq 1 30); do
  beating=$("$bin/vcu" status --config "$config" --wait 1 2>/dev/null | grep -c '^vcu-' || true)
  [ "$beating" -ge 5 ] && { up=1; break; }
  kill -0 %1 2>/dev/null || break
done
[ $up -eq 1 ] || { tail -n 5 "$run/supervisord.out" >&2; fail "the stack did not come up"; }
"$bin/vcu" signal set internal.operator.StartStop Start --config "$config" >/dev/null
sleep 5
"$bin/vcu" signal set internal.operator.ConnectDriving 1 --config "$config" >/dev/null
sleep 4
state=$("$bin/vcu" top --once --config "$config" | grep '^FSM')
[[ "$state" == *Driving* ]] || fail "the FSM is not in Driving: $state"

# vcu-web: supervisord's when its configuration has the program, else ours
if grep -q '^\[program:web\]' "$run/openvcu.conf"; then
  for _ in $(seq 1 20); do
    webPid=$(supervisorctl -c "$run/openvcu.conf" pid web 2>/dev/null)
    [[ "$webPid" =~ ^[1-9][0-9]*$ ]] && break
    webPid=""
    sleep 0.5
  done
  [ -n "$webPid" ] || fail "supervisord's vcu-web is not running: $(supervisorctl -c "$run/openvcu.conf" status web; tail -n 3 "$run/web.log")"
  listen=$(tr '\0' '\n' < "/proc/$webPid/cmdline" | sed -n '/^--listen$/{n;p}')
  [ -n "$listen" ] || listen=$(ss -ltnpH 2>/dev/null | awk -v p="pid=$webPid," 'index($0, p) {print $4; exit}')
  [ -n "$listen" ] || fail "cannot tell where supervisord's vcu-web (pid $webPid) listens"
  how="supervisord's program web"
else
  listen=127.0.0.1:$port
  "$bin/vcu-web" --config "$config" --listen "$listen" --data-folder "$run/data" --users "$run/data/web-users.json" \
    --www "$root/services/web/www" > "$run/web.log" 2>&1 &
  ownWeb=$!
  webPid=$ownWeb
  how="started by the bench ($(basename "$bin")/vcu-web --listen $listen)"
fi
url=http://$listen
for _ in $(seq 1 40); do
  curl -fsS -o /dev/null --max-time 1 "$url/api/info" 2>/dev/null && break
  kill -0 "$webPid" 2>/dev/null || fail "vcu-web (pid $webPid) ended: $(tail -n 3 "$run/web.log" 2>/dev/null)"
  sleep 0.5
done
curl -fsS -o /dev/null --max-time 2 "$url/api/info" || fail "vcu-web does not answer GET $url/api/info"
"$python" "$here/web_clients.py" catalog --url "$url" --signals "$signals" || fail "a picked signal is not in the catalog"

cpuns() { cat /proc/"$1"/task/*/schedstat 2>/dev/null | awk '{s += $1} END {printf "%.0f", s}'; }
ticks() { awk '{print $14 + $15}' "/proc/$1/stat"; }
rssMb() { awk '$1 == "VmRSS:" {printf "%.1f", $2 / 1024}' "/proc/$1/status"; }
threads() { awk '$1 == "Threads:" {print $2}' "/proc/$1/status"; }
hz=$(getconf CLK_TCK)
echo "vcu-web benchmark: $(nproc) cores, $(uname -r), $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')"
echo "vcu-web: $how, pid $webPid, $url; $state; load $(cut -d' ' -f1-3 /proc/loadavg)"
echo "signals: $signals"
declare -A cpu rate
rssMax=0
for pages in 0 1 10; do
  client=""
  if [ "$pages" -gt 0 ]; then
    rm -f "$run/ready"
    "$python" "$here/web_clients.py" streams --url "$url" --signals "$signals" --clients "$pages" \
      --ready-file "$run/ready" --max-seconds $((seconds + 60)) > "$run/clients-$pages.json" 2> "$run/clients-$pages.err" &
    client=$!
    for _ in $(seq 1 100); do [ -e "$run/ready" ] && break; kill -0 "$client" 2>/dev/null || break; sleep 0.2; done
    [ -e "$run/ready" ] || fail "$pages live pages: not every stream delivered an update within 20 s: $(cat "$run/clients-$pages.json" "$run/clients-$pages.err")"
    sleep 2  # past the connections' start
  fi
  a=$(cpuns "$webPid"); ta=$(ticks "$webPid"); t0=$(date +%s%N)
  sleep "$seconds"
  b=$(cpuns "$webPid"); tb=$(ticks "$webPid"); t1=$(date +%s%N)
  kill -0 "$webPid" 2>/dev/null || fail "vcu-web (pid $webPid) ended during the window with $pages pages"
  rss=$(rssMb "$webPid")
  rssMax=$(awk -v a="$rssMax" -v b="$rss" 'BEGIN {print (b > a) ? b : a}')
  cpu[$pages]=$(awk -v a="$a" -v b="$b" -v t="$((t1 - t0))" 'BEGIN {printf "%.2f", 100 * (b - a) / t}')
  tickPct=$(awk -v a="$ta" -v b="$tb" -v hz="$hz" -v t="$((t1 - t0))" 'BEGIN {printf "%.2f", 100 * (b - a) / hz / (t / 1e9)}')
  line="$pages live pages: vcu-web ${cpu[$pages]} % of one core (ticks $tickPct %), VmRSS $rss MB, $(threads "$webPid") threads"
  if [ -n "$client" ]; then
    kill -TERM "$client"
    wait "$client"
    status=$?
    summary=$(cat "$run/clients-$pages.json")
    [ -n "$summary" ] || fail "the $pages-page client printed nothing: $(cat "$run/clients-$pages.err")"
    rate[$pages]=$(jq -r .eventsPerSMean <<<"$summary")
    line+="; update events/s per page: mean ${rate[$pages]}, min $(jq -r .eventsPerSMin <<<"$summary")"
    line+="; value changes/s per signal (page 0): $(jq -r '.perClient[0].changesPerS | to_entries | map("\(.key | split(".") | last) \(.value)") | join(", ")' <<<"$summary")"
    line+="; not Ready: $(jq '[.perClient[].notReady] | add' <<<"$summary")"
    if [ "$status" -ne 0 ]; then
      echo "$line"
      fail "$pages live pages: streams failed: $(jq -c .failed <<<"$summary")"
    fi
    awk -v r="${rate[$pages]}" 'BEGIN {exit !(r > 0)}' || { echo "$line"; fail "$pages live pages received no update events"; }
  fi
  echo "$line; load $(cut -d' ' -f1-3 /proc/loadavg)"
done

echo "DOM latency (headless Chromium, $samples samples):"
"$python" "$here/dom_latency.py" --url "$url" --signals "$signals" --samples "$samples" \
  --screenshot "$run/dom-latency.png" > "$run/dom.out" 2> "$run/dom.err"
domStatus=$?
sed 's/^/  /' "$run/dom.out"
dom=$(grep '^DOM ' "$run/dom.out")
[ -n "$dom" ] || fail "dom_latency.py failed ($domStatus): $(tail -n 5 "$run/dom.err")"
[ "$domStatus" -eq 0 ] || echo "warning: fewer than $samples DOM samples (dom_latency.py exit $domStatus)"
field() { tr ' ' '\n' <<<"$dom" | sed -n "s/^$1=//p"; }
kill -0 "$webPid" 2>/dev/null || fail "vcu-web (pid $webPid) ended during the DOM latency run"
rss=$(rssMb "$webPid")
rssMax=$(awk -v a="$rssMax" -v b="$rss" 'BEGIN {print (b > a) ? b : a}')
now=$("$bin/vcu" top --once --config "$config" | grep '^FSM')
[[ "$now" == *Driving* ]] || fail "the FSM left Driving during the bench: $now"
echo "vcu-web VmRSS after the browser: $rss MB (largest seen $rssMax MB)"
echo "RESULT web_cpu_pct_1=${cpu[1]} web_cpu_pct_10=${cpu[10]} web_cpu_pct_0=${cpu[0]} web_rss_mb=$rssMax" \
  "dom_latency_p50_ms=$(field p50_ms) dom_latency_p99_ms=$(field p99_ms) events_per_s_per_client=${rate[10]}"
