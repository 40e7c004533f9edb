#!/bin/bash
# The whole HHEA safety campaign as a benchmark (docs/benchmarks.md "## Safety campaign"):
# reaction times of every hazard of config/hhea/safety.json against its FTTI, measured on
# the simulated stack N times each, optionally while stress-ng keeps every core busy.
#
#   bench/stack/safety_campaign.sh [--repeat N] [--stress] [--hazard ID ...] [--out DIR]
#
#   --repeat N    injections per hazard and fault (default 30; one repetition of all 14
#                 hazards, 16 injections, took 55-57 s on a 2-vCPU machine)
#   --stress      `stress-ng --cpu <nproc>` runs beside the stack for the campaign's duration
#                 (started after the stack is up, ended by its PID when the campaign ends)
#   --hazard ID   only these hazards (repeatable; several IDs may follow one --hazard)
#   --out DIR     where campaign.json, campaign.html, campaign.out, summary.tsv, stress-ng.out
#                 and the services' logs go (default build/safety-campaign/<UTC time>)
#
# Outside the test sandbox it re-runs itself inside tests/harness/run_isolated.sh (private
# /dev/shm, /tmp, network and PID namespaces: LCM multicast stays on loopback). Inside, the
# HHEA stack runs headless under supervisord on a copy of config/hhea (iox-roudi, can-rx,
# can-tx, fsm, gpio, vcu-watchdog, the simulated vehicle vcu-ecu-sim; no HMI, no web), then
#   vcu safety campaign --repeat N --json DIR/campaign.json --html DIR/campaign.html
# whose lines (one per repetition) are the progress. The binaries are build/bin's as they
# are (OPENVCU_BIN overrides); nothing is built.
#
# A repetition's reaction time is its latest item: the last safe-state item or detection of
# the hazard seen after the injection (time 0). Per hazard: min / median / max of those over
# the repetitions; a repetition in which an item was not seen within the campaign's window
# (2 x FTTI) or that could not run has no reaction time and is a miss.
# Ends with ONE line
#   RESULT hazards=N passed=N failed=N not_run=N repeat=N stress=0|1 worst_margin_ms=M
#          worst_hazard=ID <ID>_max_ms=.. (one per hazard)
# passed / failed / not_run: the campaign's verdicts (a hazard fails when any item of any
# repetition came later than its FTTI or not at all). <ID>_max_ms is the hazard's largest
# reaction time in ms, "miss" when a repetition missed an item, "notrun" when the campaign
# could not inject it. worst_margin_ms = min over the hazards with a max of (FTTI - max)
# (negative: the FTTI was exceeded), worst_hazard that hazard ("none" when no hazard has a
# max): hazards with "miss" or "notrun" are outside it and counted in failed / not_run.
# Exit: 0 the campaign ran (whatever its verdicts), 1 it could not run (the stack did not
# come up, the campaign ended without its JSON report), 2 usage error.
set -uo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
bin=${OPENVCU_BIN:-$root/build/bin}
NAME=safety-campaign

usage() { sed -n '5,14p' "$0" | sed 's/^# \{0,1\}//'; }
repeat=30; stress=0; hazards=(); out=""
while [ $# -gt 0 ]; do
  case "$1" in
    --repeat) repeat=${2:-}; shift ;;
    --stress) stress=1 ;;
    --hazard)
      if [ -z "${2:-}" ] || [[ "$2" == --* ]]; then echo "$NAME: --hazard needs a hazard ID" >&2; exit 2; fi
      while [ -n "${2:-}" ] && [[ "$2" != --* ]]; do hazards+=("$2"); shift; done ;;
    --out) out=${2:-}; [ -n "$out" ] || { echo "$NAME: --out needs a folder" >&2; exit 2; }; shift ;;
    -h|--help) usage; exit 0 ;;
    *) echo "$NAME: unknown argument '$1'" >&2; usage >&2; exit 2 ;;
  esac
  shift
done
if ! [[ "$repeat" =~ ^[0-9]+$ ]] || [ "$repeat" -lt 1 ] || [ "$repeat" -gt 1000 ]; then
  echo "$NAME: --repeat takes a whole number from 1 to 1000, not '$repeat'" >&2
  exit 2
fi

if [ "${OPENVCU_ISOLATED:-}" != 1 ]; then
  # outside the sandbox: check what runs inside, fix the output folder, re-run in the sandbox
  for binary in vcu vcu-can-rx vcu-can-tx vcu-fsm vcu-gpio vcu-watchdog vcu-ecu-sim; do
    [ -x "$bin/$binary" ] || { echo "$NAME: error: $bin/$binary not built (cmake --build build --target openvcu-runtime)" >&2; exit 1; }
  done
  for tool in supervisord supervisorctl jq; do
    command -v "$tool" >/dev/null || { echo "$NAME: error: $tool not found (scripts/install-deps.sh)" >&2; exit 1; }
  done
  if [ $stress -eq 1 ] && ! command -v stress-ng >/dev/null; then
    echo "$NAME: error: --stress needs stress-ng (scripts/install-deps.sh)" >&2
    exit 1
  fi
  [ -n "$out" ] || out=$root/build/safety-campaign/$(date -u +%Y%m%dT%H%M%SZ)
  mkdir -p "$out" || { echo "$NAME: error: cannot create the output folder $out" >&2; exit 1; }
  out=$(cd "$out" && pwd -P)
  keep=()
  case "$out" in /tmp|/tmp/*) keep=(--keep "$out") ;; esac
  case "$bin" in /tmp|/tmp/*) keep+=(--keep "$bin") ;; esac
  args=(--repeat "$repeat" --out "$out")
  [ $stress -eq 1 ] && args+=(--stress)
  [ ${#hazards[@]} -gt 0 ] && args+=(--hazard "${hazards[@]}")
  exec "$root/tests/harness/run_isolated.sh" "${keep[@]}" -- env OPENVCU_BIN="$bin" "$0" "${args[@]}"
fi

# ---- inside the sandbox ----
[ -n "$out" ] || { echo "$NAME: error: no --out folder inside the sandbox" >&2; exit 1; }
mkdir -p "$out/logs"
# The stack and the campaign run copies of the binaries, taken now, in the sandbox's /tmp: a
# rebuild of the build folder during a long campaign cannot mix two builds into one figure
# (supervisord restarts killed services from the binary's path). A copy is taken again when
# a binary changed while it was copied.
snapshot=/tmp/openvcu-bin
mkdir -p "$snapshot"
binaries() { stat -c '%n %s %Y' "$1"/vcu "$1"/vcu-* 2>/dev/null | sed 's|^.*/||'; }
for attempt in 1 2 3 0; do
  [ "$attempt" -gt 0 ] || { echo "$NAME: error: $bin kept changing while copied (a build running?)" >&2; exit 1; }
  before=$(binaries "$bin")
  cp -p "$bin"/vcu "$bin"/vcu-* "$snapshot"/ || exit 1
  [ "$before" = "$(binaries "$bin")" ] && [ "$before" = "$(binaries "$snapshot")" ] && break
  sleep 5
done
origin=$bin
export OPENVCU_BIN=$snapshot
export VEHICLE=hhea
export COPY_VEHICLE=1  # the stack and the campaign use a copy of config/hhea in the sandbox's run folder
# shellcheck source=../../tests/demo/supervised_stack.sh
source "$root/tests/demo/supervised_stack.sh"

stressPid=""
finish() {
  if [ -n "$stressPid" ]; then kill -TERM "$stressPid" 2>/dev/null; wait "$stressPid" 2>/dev/null; fi
  ctl shutdown >/dev/null 2>&1
  [ -n "${supervisor:-}" ] && wait "$supervisor" 2>/dev/null
  cp "$run"/*.log "$run/supervisord.out" "$out/logs/" 2>/dev/null
}
start_supervisor
trap finish EXIT
t0=$(date +%s)
say() { echo "$NAME: [$(( $(date +%s) - t0 )) s] $*"; }
fail() { echo "$NAME: error: $*" >&2; echo "RESULT hazards=0 passed=0 failed=0 not_run=0 repeat=$repeat stress=$stress worst_margin_ms=none worst_hazard=none"; exit 1; }

{
  echo "date $(date -u '+%Y-%m-%d %H:%M:%S UTC'), main at $(git -C "$root" rev-parse --short HEAD 2>/dev/null)," \
        "binaries copied from $origin (newest built $(date -u -d "@$(stat -c %Y "$snapshot"/vcu "$snapshot"/vcu-* | sort -n | tail -n1)" '+%Y-%m-%d %H:%M:%S UTC'))"
  git -C "$root" status --porcelain --untracked-files=no 2>/dev/null | sed "s/^/uncommitted in the checkout: /"
  echo "$(nproc) CPUs ($(lscpu | sed -n 's/^Model name: *//p')), kernel $(uname -r), load $(cut -d' ' -f1-3 /proc/loadavg)"
} | tee "$out/machine.txt" | sed "s/^/$NAME: /"

# up when every service beats: can-rx, can-tx, fsm, gpio, watchdog and the simulated vehicle
services=0
for _ in $(seq 1 30); do
  services=$("$vcu" status --config "$config" --wait 1 2>/dev/null | grep -c '^vcu-')
  [ "$services" -ge 6 ] && break
  kill -0 "$supervisor" 2>/dev/null || break
done
[ "$services" -ge 6 ] || { tail -n 5 "$run/supervisord.out" >&2; fail "the stack did not come up ($services services beat; logs in $out/logs)"; }
say "stack up: $("$vcu" status --config "$config" --wait 1 2>/dev/null | grep '^vcu-' | awk '{print $1}' | tr '\n' ' ')"

campaign=("$vcu" safety campaign --config "$config" --repeat "$repeat" --json "$out/campaign.json" --html "$out/campaign.html")
for id in "${hazards[@]}"; do campaign+=(--hazard "$id"); done
if [ $stress -eq 1 ]; then
  # a bound in case this script dies without ending it: 3 minutes per hazard and repetition
  limit=$(( repeat * 14 * 180 ))
  stress-ng --cpu "$(nproc)" --timeout "${limit}s" --metrics-brief > "$out/stress-ng.out" 2>&1 &
  stressPid=$!
  sleep 1
  kill -0 "$stressPid" 2>/dev/null || fail "stress-ng did not start: $(tail -n 3 "$out/stress-ng.out")"
  say "stress-ng --cpu $(nproc) running (pid $stressPid)"
fi
say "running: ${campaign[*]#$bin/}"
rm -f "$out/campaign.json"
# the campaign's own lines are the progress, stamped with the seconds since the start
stdbuf -oL "${campaign[@]}" 2>&1 | tee "$out/campaign.out" | while IFS= read -r line; do say "$line"; done
code=${PIPESTATUS[0]}
if [ -n "$stressPid" ]; then
  kill -TERM "$stressPid" 2>/dev/null; wait "$stressPid" 2>/dev/null; stressPid=""
  say "stress-ng ended: $(awk '$4 == "cpu" && $5 ~ /^[0-9]+$/ {print $5 " bogo ops in " $6 " s"}' "$out/stress-ng.out")"
fi
say "campaign exit code $code, load $(cut -d' ' -f1-3 /proc/loadavg)"
case $code in 0|1) ;; *) fail "the campaign could not run (exit code $code; its output: $out/campaign.out)" ;; esac
jq -e '.hazards | type == "array"' "$out/campaign.json" >/dev/null 2>&1 ||
  fail "the campaign wrote no JSON report ($out/campaign.json; its output: $out/campaign.out)"

# per hazard: id, FTTI, verdict, repetitions, misses, min / median / max reaction (ms; "-": none)
jq -r '
  def fmt: if . == null then "-" else (. * 10 | round / 10 | tostring) end;
  .hazards[]
  | [.repetitions[]
     | if (.error == null) and (.items | length) > 0 and all(.items[]; .reachedMs != null)
       then [.items[].reachedMs] | max else null end] as $r
  | ([$r[] | select(. != null)] | sort) as $t
  | ($t | length) as $n
  | [.id, .fttiMs, .verdict, ($r | length), ([$r[] | select(. == null)] | length),
     ($t | first | fmt),
     (if $n == 0 then null elif $n % 2 == 1 then $t[($n - 1) / 2] else ($t[$n / 2 - 1] + $t[$n / 2]) / 2 end | fmt),
     ($t | last | fmt)]
  | @tsv' "$out/campaign.json" > "$out/summary.tsv"

printf '%-22s %6s %-8s %5s %6s %9s %9s %9s %9s\n' hazard FTTI verdict reps misses min_ms median_ms max_ms margin_ms
result=""; passed=0; failed=0; notRun=0; worst=""; worstHazard=none
while IFS=$'\t' read -r id ftti verdict reps misses min median max; do
  margin=-
  case "$verdict" in
    PASS) passed=$((passed + 1)) ;;
    FAIL) failed=$((failed + 1)) ;;
    *) notRun=$((notRun + 1)) ;;
  esac
  if [ "$verdict" = "NOT RUN" ]; then value=notrun
  elif [ "$misses" -gt 0 ] || [ "$max" = - ]; then value=miss
  else
    value=$(printf '%.0f' "$max")
    margin=$(awk -v f="$ftti" -v m="$max" 'BEGIN {printf "%.0f", f - m}')
    if [ -z "$worst" ] || [ "$margin" -lt "$worst" ]; then worst=$margin; worstHazard=$id; fi
  fi
  printf '%-22s %6s %-8s %5s %6s %9s %9s %9s %9s\n' "$id" "$ftti" "${verdict// /_}" "$reps" "$misses" "$min" "$median" "$max" "$margin"
  result+=" ${id}_max_ms=$value"
done < "$out/summary.tsv"
hazardCount=$(wc -l < "$out/summary.tsv")
say "reports: $out/campaign.json, $out/campaign.html, $out/summary.tsv"
echo "RESULT hazards=$hazardCount passed=$passed failed=$failed not_run=$notRun repeat=$repeat stress=$stress" \
  "worst_margin_ms=${worst:-none} worst_hazard=$worstHazard$result"
exit 0
