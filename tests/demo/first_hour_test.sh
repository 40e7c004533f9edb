#!/bin/bash
# A new user's first hour, end to end, inside run_isolated.sh (private /dev/shm, /tmp, network
# and PIDs), with the tree already built (OPENVCU_BIN), from the repository root as README.md
# says:
#   1. `./run.sh --isolated --headless` in a process group of its own (as a terminal's job)
#      until its first status line: every service beats (--isolated is a no-op inside the
#      sandbox, where run.sh already is);
#   2. `vcu check config/hhea`: the vehicle's folder as a positional path, exit 0;
#   3. vcu-web at rest (Standby, nothing started): every /api/live update of 2 s lists no
#      active fault (the faults of the web page's ACTIVE FAULTS);
#   4. a recording from the HMI's Record page (record_page_driver: the page's RecordController
#      in a process set up as vcu-hmi; without vcu-hmi built, the argv the page builds, run
#      here) while the operator starts the vehicle and the simulated VIC reports a battery
#      fault (`vcu sim fault battery on`: Battery Fault, the VCU's DM1 raises a DTC), stopped
#      as the page's Stop (SIGTERM): it ends well, the Statistics tab's model and
#      `vcu trace stats` read it with no malformed line and no backward step;
#   5. `vcu trace check` on it names the raised DTC at a time after the fault, and that time
#      is found verbatim in the recording's vehicle.log as the VCU's DM1 (grep -F '(TIME)');
#   6. Ctrl-C (SIGINT to the group): run.sh stops (130), no process, no shared memory left.
# About 15-20 s. Prints each step and its time; the first failing step ends the test.
set -uo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
bin=${OPENVCU_BIN:-$root/build/bin}
vcu=$bin/vcu
config=$root/config/hhea/vehicle.json
UP_SECONDS=90
STOP_SECONDS=20
RECORD_STOP_SECONDS=10  # RecordController::STOP_TIMEOUT_MS: the page kills vcu record after it
DTC_WAIT_SECONDS=8
VCU_DM1=18FECA21  # DM1 (PGN 65226, 0xFECA), priority 6, from the VCU (0x21)
work=$(mktemp -d)
log=$work/run.log
started=$(date +%s.%N)

elapsed() { awk -v a="$started" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f s", b - a }'; }
step() { echo "first_hour_test: [$(elapsed)] $*"; }
stack_processes() { pgrep -a -f 'vcu-(can-rx|can-tx|fsm|gpio|ecu-sim|hmi|web|watchdog)|iox-roudi|supervisord|lcm-logger' || true; }
shared_memory() { ls /dev/shm | grep -E '^(openvcu-|iceoryx_)' || true; }
group=""; recorder=""
fail() {
  echo "first_hour_test: FAIL: $*"
  echo "---- run.sh's output"; cat "$log" 2>/dev/null
  [ -n "$recorder" ] && kill -KILL "$recorder" 2>/dev/null
  [ -n "$group" ] && kill -INT -- "-$group" 2>/dev/null && wait "$group" 2>/dev/null
  exit 1
}

# 1. the README's command from the repository root; setsid and env --default-signal as in
# run_stop_test.sh: the job's group gets the Ctrl-C, which a job started with '&' ignores
cd "$root" || fail "cannot enter $root"
setsid env --default-signal=INT bash -c 'trap : INT; ./run.sh --isolated --headless > "$1" 2>&1; echo $? > "$2"' \
  run-pipeline "$log" "$work/status" &
group=$!
up=0
for _ in $(seq 1 $((UP_SECONDS * 10))); do
  if grep -qE '^[0-9]{2}:[0-9]{2}:[0-9]{2} FSM ' "$log" 2>/dev/null; then up=1; break; fi
  kill -0 "$group" 2>/dev/null || fail "run.sh ended before the stack was up"
  sleep 0.1
done
[ $up -eq 1 ] || fail "no status line from run.sh within ${UP_SECONDS} s"
grep -q '^web: http://127.0.0.1:8080 ' "$log" || fail "run.sh did not announce vcu-web on http://127.0.0.1:8080"
step "1. ./run.sh --isolated --headless: the stack is up ($(stack_processes | wc -l) processes)"

# 2. vcu check with the vehicle's folder as a positional path, as a user types it
check_out=$("$vcu" check config/hhea 2>&1)
check_status=$?
[ $check_status -eq 0 ] || fail "vcu check config/hhea exited $check_status: $check_out"
step "2. vcu check config/hhea: exit 0 ($(echo "$check_out" | tail -1))"

# 3. the web page's live updates at rest: the state is Standby and no update lists a fault
curl -sN --max-time 2 http://127.0.0.1:8080/api/live > "$work/live.txt" 2>/dev/null
rest=$(/usr/bin/python3 - "$work/live.txt" <<'PY'
import json, sys
updates = [json.loads(line[len('data: '):]) for line in open(sys.argv[1]) if line.startswith('data: ')]
if not updates:
    print('no update event from /api/live within 2 s'); sys.exit(1)
faults = sorted({f"{f['name']} ({f['severity']}: {f['text']})" for u in updates for f in u['faults']})
states = sorted({u['header']['state'] for u in updates})
if faults:
    print(f"{len(faults)} active fault(s) at rest: " + '; '.join(faults)); sys.exit(1)
if states != ['Standby']:
    print(f'states {states}, not Standby alone'); sys.exit(1)
print(f'{len(updates)} updates, Standby, no active fault')
PY
) || fail "vcu-web at rest: $rest"
step "3. vcu-web /api/live at rest: $rest"

# 4. the Record page's recording. With record_page_driver (vcu-hmi built): the page's own
# RecordController in a process set up as vcu-hmi (SIGTERM and SIGINT blocked), Recording
# once vcu record said "recording ", Stop on a line to its stdin, then the Statistics tab's
# model on what it recorded. Without it: the argv the page builds, its readiness line, its
# SIGTERM, run here.
page=${OPENVCU_RECORD_PAGE:-}
folder=""
if [ -n "$page" ]; then
  mkfifo "$work/stop-button"
  exec {stop_button}<> "$work/stop-button"
  mkdir -m 700 "$work/xdg"
  XDG_RUNTIME_DIR=$work/xdg "$page" --config "$config" --data-folder "$work/data" --vcu "$vcu" <&"$stop_button" \
    > "$work/record.out" 2> "$work/record.err" &
  recorder=$!
  ready="$work/record.out"
else
  folder=$work/data/recordings/$(date +%Y%m%d-%H%M%S)
  "$vcu" record "$folder" --config "$config" < /dev/null > "$work/record.out" 2> "$work/record.err" &
  recorder=$!
  ready="$work/record.err"
fi
began=0
for _ in $(seq 1 150); do
  if grep -q '^recording ' "$ready"; then began=1; break; fi
  kill -0 "$recorder" 2>/dev/null || break
  sleep 0.1
done
[ $began -eq 1 ] || fail "the recording never began: $(cat "$work/record.out" "$work/record.err")"
if [ -n "$page" ]; then
  folder=$(sed -n 's/^recording //p' "$work/record.out" | head -1)
  case "$folder" in "$work/data/recordings/"?*) ;; *) fail "the page records into '$folder', not a folder of $work/data/recordings" ;; esac
fi
"$vcu" signal set internal.operator.StartStop Start --config "$config" > /dev/null ||
  fail "the operator's Start was refused"
# the battery fault of the simulated VIC: the FSM goes to Battery Fault and the VCU's DM1
# (PGN 65226, 0xFECA) raises its DTC; on until a DM1 with a lamp on is in the recording
# (vcu record writes lines in time order, so it shows up within a moment)
sleep 1
fault_on=$(date +%s.%N)
"$vcu" sim fault battery on --config "$config" > "$work/fault.txt" || fail "vcu sim fault battery on: $(cat "$work/fault.txt")"
raised=""
for _ in $(seq 1 $((DTC_WAIT_SECONDS * 10))); do
  raised=$(awk -v since="$fault_on" -v id="$VCU_DM1" '
    $2 == "vehicle" && substr($3, 1, 9) == id "#" && substr($3, 10, 2) != "00" {
      t = substr($1, 2, length($1) - 2); if (t + 0 > since + 0) { print t; exit } }' "$folder/vehicle.log" 2>/dev/null)
  [ -n "$raised" ] && break
  sleep 0.1
done
[ -n "$raised" ] || fail "no DM1 of the VCU with a lamp on in the recording within ${DTC_WAIT_SECONDS} s of the battery fault"
"$vcu" sim fault battery off --config "$config" >> "$work/fault.txt" || fail "vcu sim fault battery off failed"
sleep 1
if [ -n "$page" ]; then echo stop >&"$stop_button"; else kill -TERM "$recorder"; fi
stopped=0
for _ in $(seq 1 $((RECORD_STOP_SECONDS * 10 + 50))); do
  kill -0 "$recorder" 2>/dev/null || { stopped=1; break; }
  sleep 0.1
done
[ $stopped -eq 1 ] || fail "the recording did not end within ${RECORD_STOP_SECONDS} s of Stop (the page kills vcu record then)"
wait "$recorder"
record_status=$?
recorder=""
[ $record_status -eq 0 ] ||
  fail "the recording ended badly (exit $record_status; the page's text in red): $(cat "$work/record.out" "$work/record.err")"
[ -s "$folder/vehicle.log" ] && [ -s "$folder/events.lcmlog" ] || fail "the recording lacks vehicle.log or events.lcmlog: $(ls -l "$folder")"
if [ -n "$page" ]; then
  step "4. the Record page: $(grep '^result: ' "$work/record.out" | head -1)"
  step "   the Statistics tab: $(grep '^statistics: ' "$work/record.out" | head -1)"
else
  step "4. the Record page's vcu record: exit 0 after SIGTERM ($(head -1 "$work/record.out"))"
fi
"$vcu" trace stats --config "$config" --format json "$folder" > "$work/stats.json" 2> "$work/stats.err"
stats_status=$?
[ $stats_status -eq 0 ] || fail "vcu trace stats exited $stats_status: $(cat "$work/stats.err")"
[ ! -s "$work/stats.err" ] || fail "vcu trace stats reported: $(cat "$work/stats.err")"
stats=$(/usr/bin/python3 -c '
import json, sys
s = json.load(open(sys.argv[1]))
print(s["frames"], s["backward_steps"], s["skipped_frames"], round(s["duration_s"], 1))' "$work/stats.json") ||
  fail "vcu trace stats wrote no JSON: $(head -c 300 "$work/stats.json")"
read -r frames backward skipped duration <<< "$stats"
[ "$backward" = 0 ] || fail "vcu trace stats: time went backwards $backward time(s)"
[ "$skipped" = 0 ] || fail "vcu trace stats: $skipped frame(s) skipped"
step "   vcu trace stats: $frames frames over $duration s, no malformed line, no backward step"

# 5. the DTC raised by the battery fault, at the log's own time, which grep finds as the DM1
"$vcu" trace check --config "$config" "$folder" > "$work/check.txt" 2>&1
finding=$(awk -v on="$fault_on" '$1 ~ /^[0-9]+\.[0-9]+$/ && $3 == "dtc" && $1 + 0 >= on + 0 { print; exit }' "$work/check.txt")
[ -n "$finding" ] || fail "vcu trace check named no DTC after the battery fault ($fault_on): $(cat "$work/check.txt")"
time=${finding%% *}
grep -qF "($time) vehicle $VCU_DM1#" "$folder/vehicle.log" ||
  fail "the finding's time $time is not the time stamp of a DM1 of the VCU in vehicle.log: $finding; the lines stamped ($time): $(grep -F "($time)" "$folder/vehicle.log")"
step "5. vcu trace check: '$finding'; grep finds ($time) $VCU_DM1 in vehicle.log"

# 6. Ctrl-C: run.sh's orderly stop, nothing left
kill -INT -- "-$group"
gone=0
for _ in $(seq 1 $((STOP_SECONDS * 10))); do
  if [ -z "$(pgrep -f 'run\.sh' || true)" ] && [ -z "$(stack_processes)" ]; then gone=1; break; fi
  sleep 0.1
done
wait "$group" 2>/dev/null
group=""
[ $gone -eq 1 ] || fail "${STOP_SECONDS} s after Ctrl-C still running: $(pgrep -a -f 'run\.sh' || true) $(stack_processes)"
status=$(cat "$work/status" 2>/dev/null)
[ "$status" = 130 ] || fail "run.sh ended with status '$status', not 130 (its orderly stop after SIGINT)"
left=$(shared_memory)
[ -z "$left" ] || fail "shared memory left behind: $left"
step "6. Ctrl-C: run.sh stopped (130), no process and no shared memory left"
echo "first_hour_test: PASS in $(elapsed)"
