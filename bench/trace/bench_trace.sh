#!/usr/bin/env bash
# Trace analysis benchmark (docs/benchmarks.md, "Trace analysis"): on the 1,000,000-frame
# synthetic J1939 log, times `vcu dbc decode` (JSON lines to /dev/null), `vcu trace stats`
# and `vcu trace check` side by side in the same run, best of 3 wall times each with
# /usr/bin/time -v (max RSS: the largest of the 3 runs); then `vcu trace stats` on a
# 100,000-frame log to show that its memory does not grow with the log.
# Builds nothing: ninja -C build vcu first.
#
# usage: bench/trace/bench_trace.sh [BUILD_DIR]      (default <repo>/build)
# environment:
#   OPENVCU_GEN_J1939    the generator, default <repo>/../shared/tools/gen-j1939-log.py
#   OPENVCU_BENCH_CACHE  where generated logs are kept, default /tmp/openvcu-bench
#   RUNS                 runs per command, default 3
# The last line is:
#   RESULT decode_s=.. stats_s=.. check_s=.. stats_ratio=.. check_ratio=.. decode_rss_mb=..
#          stats_rss_mb=.. check_rss_mb=.. stats_rss_100k_mb=..
# (check_*=na when the binary has no `trace check`; a line "check: not built" says so.)
set -euo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
build="${1:-$repo/build}"
vcu="$build/bin/vcu"
generator="${OPENVCU_GEN_J1939:-$repo/../shared/tools/gen-j1939-log.py}"
cacheRoot="${OPENVCU_BENCH_CACHE:-/tmp/openvcu-bench}"
runs="${RUNS:-3}"

if [[ ! -x "$vcu" ]]; then
  echo "error: $vcu not built (ninja -C $build vcu)" >&2
  exit 1
fi
if [[ ! -x /usr/bin/time ]]; then
  echo "error: /usr/bin/time not found (apt-get install time)" >&2
  exit 1
fi

# generate FRAMES: the folder holding synthetic_j1939.{dbc,log} for that many frames (seed 1939).
generate() {
  local frames="$1" dir="$cacheRoot/trace-f$1-s1939"
  if [[ ! -s "$dir/synthetic_j1939.log" || ! -s "$dir/synthetic_j1939.dbc" ]]; then
    if [[ ! -f "$generator" ]]; then
      echo "error: $generator not found (set OPENVCU_GEN_J1939)" >&2
      exit 1
    fi
    mkdir -p "$dir"
    echo "generating $frames frames into $dir" >&2
    /usr/bin/python3 "$generator" --frames "$frames" --seed 1939 --out-dir "$dir" >/dev/null
  fi
  echo "$dir"
}

# measure NAME COMMAND...: runs COMMAND $runs times (stdout to /dev/null); sets
# best_s (lowest wall time, s) and rss_mb (highest max RSS, MiB); prints each run.
measure() {
  local name="$1" i report wall kb seconds status
  shift
  best_s="" rss_mb=0
  local rssKb=0
  for (( i = 1; i <= runs; i++ )); do
    report="$(mktemp)"
    /usr/bin/time -v -o "$report" "$@" >/dev/null 2>"$report.err" || true
    wall="$(sed -n 's/.*Elapsed (wall clock) time (h:mm:ss or m:ss): //p' "$report")"
    kb="$(sed -n 's/.*Maximum resident set size (kbytes): //p' "$report")"
    status="$(sed -n 's/.*Exit status: //p' "$report")"
    seconds="$(awk -v t="$wall" 'BEGIN { n = split(t, p, ":"); s = 0; for (i = 1; i <= n; i++) s = s * 60 + p[i]; printf "%.3f", s }')"
    echo "  $name run $i: ${seconds} s, max RSS ${kb} kB, exit ${status}$(grep -q . "$report.err" && echo "; stderr: $(head -c 200 "$report.err" | tr '\n' ' ')")"
    if [[ -z "$best_s" ]] || awk -v a="$seconds" -v b="$best_s" 'BEGIN { exit !(a < b) }'; then best_s="$seconds"; fi
    (( kb > rssKb )) && rssKb="$kb"
    rm -f "$report" "$report.err"
  done
  rss_mb="$(awk -v k="$rssKb" 'BEGIN { printf "%.1f", k / 1024 }')"
}

ratio() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.2f", a / b }'; }

big="$(generate 1000000)"
small="$(generate 100000)"

echo "== machine"
echo "nproc $(nproc); $(lscpu | grep 'Model name' | sed 's/  */ /g'); $(date -u '+%Y-%m-%d %H:%M UTC')"
echo "load $(cut -d' ' -f1-3 /proc/loadavg); commit $(git -C "$repo" rev-parse --short HEAD 2>/dev/null || echo '?')"
grep -E '^CMAKE_BUILD_TYPE:' "$build/CMakeCache.txt" 2>/dev/null || true
echo "== 1,000,000 frames: $big/synthetic_j1939.log ($(wc -c <"$big/synthetic_j1939.log") bytes)"

measure decode "$vcu" dbc decode "$big/synthetic_j1939.dbc" "$big/synthetic_j1939.log"
decode_s="$best_s" decode_rss="$rss_mb"
measure stats "$vcu" trace stats --dbc "$big/synthetic_j1939.dbc" "$big/synthetic_j1939.log"
stats_s="$best_s" stats_rss="$rss_mb"
# `vcu trace check --help` would print the group's help when check is missing: look for it in the list.
if "$vcu" trace --help 2>&1 | grep -qE '^ +check( |$)'; then
  measure check "$vcu" trace check --dbc "$big/synthetic_j1939.dbc" "$big/synthetic_j1939.log"
  check_s="$best_s" check_rss="$rss_mb" check_ratio="$(ratio "$best_s" "$decode_s")"
else
  echo "check: not built"
  check_s=na check_rss=na check_ratio=na
fi
echo "== 100,000 frames: $small/synthetic_j1939.log"
measure stats-100k "$vcu" trace stats --dbc "$small/synthetic_j1939.dbc" "$small/synthetic_j1939.log"
stats_rss_100k="$rss_mb"

echo "RESULT decode_s=$decode_s stats_s=$stats_s check_s=$check_s stats_ratio=$(ratio "$stats_s" "$decode_s")" \
  "check_ratio=$check_ratio decode_rss_mb=$decode_rss stats_rss_mb=$stats_rss check_rss_mb=$check_rss" \
  "stats_rss_100k_mb=$stats_rss_100k"
