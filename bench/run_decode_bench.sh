#!/usr/bin/env bash
# Decode benchmark (docs/benchmarks.md): generates the synthetic J1939 log once (or reuses
# it), runs bench_dbc_decode, then times `vcu dbc decode` on the same log if it was built.
# Builds nothing: configure and build a Release tree first, e.g.
#   cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release && ninja -C build bench_dbc_decode vcu
#
# usage: bench/run_decode_bench.sh [BUILD_DIR] [-- extra bench_dbc_decode options]
#   BUILD_DIR            default: <repo>/build
# environment:
#   OPENVCU_TEAM_KIT     default: <repo>/../shared (holds tools/gen-j1939-log.py)
#   OPENVCU_BENCH_CACHE  where generated logs are kept, default: /tmp/openvcu-bench
#   FRAMES, SEED, TRUTH  generator settings, default 1000000, 1939, 20000
set -euo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${1:-$repo/build}"
[[ $# -gt 0 ]] && shift
[[ "${1:-}" == "--" ]] && shift
kit="${OPENVCU_TEAM_KIT:-$repo/../shared}"
frames="${FRAMES:-1000000}"
seed="${SEED:-1939}"
truth="${TRUTH:-20000}"
cache="${OPENVCU_BENCH_CACHE:-/tmp/openvcu-bench}/j1939-f${frames}-s${seed}-t${truth}"
bench="$build/bench/bench_dbc_decode"
vcu="$build/bin/vcu"

if [[ ! -x "$bench" ]]; then
  echo "error: $bench not built (ninja -C $build bench_dbc_decode)" >&2
  exit 1
fi
generator="$kit/tools/gen-j1939-log.py"
dbc="$cache/synthetic_j1939.dbc"
log="$cache/synthetic_j1939.log"
truthFile="$cache/synthetic_j1939.truth.jsonl"
if [[ -s "$log" && -s "$dbc" && -s "$truthFile" ]]; then
  echo "reusing $cache"
else
  if [[ ! -f "$generator" ]]; then
    echo "error: $generator not found (set OPENVCU_TEAM_KIT)" >&2
    exit 1
  fi
  mkdir -p "$cache"
  echo "generating $frames frames (seed $seed) into $cache"
  /usr/bin/python3 "$generator" --frames "$frames" --seed "$seed" --out-dir "$cache" --truth "$truth" >/dev/null
fi

echo "== machine"
lscpu | grep -E '^(Model name|CPU family|Model|CPU\(s\)|Core\(s\) per socket|Thread\(s\) per core|L2 cache|L3 cache|Hypervisor vendor):' | sed 's/  */ /g'
echo "RAM $(free -h | awk '/^Mem:/ {print $2}'), kernel $(uname -r), load $(cut -d' ' -f1-3 /proc/loadavg)"
grep -E '^CMAKE_(BUILD_TYPE|CXX_COMPILER|CXX_FLAGS|CXX_FLAGS_RELEASE):' "$build/CMakeCache.txt" 2>/dev/null || true
compiler="$(sed -n 's/^CMAKE_CXX_COMPILER:FILEPATH=//p' "$build/CMakeCache.txt" 2>/dev/null)"
[[ -n "$compiler" ]] && "$compiler" --version | head -n 1

echo "== bench_dbc_decode"
benchOut="$(mktemp)"
trap 'rm -f "$benchOut"' EXIT
status=0
"$bench" --dbc "$dbc" --log "$log" --truth "$truthFile" "$@" >"$benchOut" || status=$?
grep -v '^RESULT ' "$benchOut" || true
result="$(grep '^RESULT ' "$benchOut" | tail -n 1 || true)"

echo "== vcu dbc decode (whole CLI: read log, match, decode, write JSON lines to /dev/null)"
vcuTimes=""
if [[ -x "$vcu" ]]; then
  TIMEFORMAT="real %3R s, user %3U s, sys %3S s"
  time "$vcu" dbc decode --stats "$dbc" "$log" >/dev/null
  TIMEFORMAT="%3R %3U"
  read -r vcuReal vcuUser < <({ time "$vcu" dbc decode --stats "$dbc" "$log" >/dev/null 2>&1; } 2>&1)
  echo "second run: real $vcuReal s, user $vcuUser s"
  vcuTimes=" vcu_real_s=$vcuReal vcu_user_s=$vcuUser"
else
  echo "skipped: $vcu not built yet"
fi

# The bench's RESULT line (CPU time; see the bench's header) is the last line of the script.
if [[ -z "$result" ]]; then
  echo "RESULT ns_per_frame=none bench_exit=$status"
else
  echo "$result bench_exit=$status$vcuTimes"
fi
exit "$status"
