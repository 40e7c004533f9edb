#!/usr/bin/env bash
# Builds the libFuzzer targets with clang (build-fuzz/, the `fuzz` preset) and runs them.
#   scripts/fuzz.sh [TARGET] [SECONDS]     one target (default: fuzz_dbc 600)
#   scripts/fuzz.sh all [SECONDS]          every target of fuzz/targets.txt in turn, SECONDS each
#   scripts/fuzz.sh list                   the targets
# Seeds: fuzz/targets.txt (files and folders of the tree), tests/data/fuzz/TARGET/ (kept
# corpus and regression inputs), and the team kit's DBC corpus for fuzz_dbc when present.
# The growing corpus is build-fuzz/corpus-TARGET/; crashes, timeouts, leaks and OOMs land in
# build-fuzz/findings-TARGET/ and each run's log in build-fuzz/logs/TARGET-DATE.log (its
# last lines: executions, time, corpus and coverage). Runs under `nice -n 19`, one at a
# time. A finding: minimise it (build-fuzz/fuzz/TARGET -minimize_crash=1 FILE), keep it as
# tests/data/fuzz/TARGET/regressions/<issue>_<what> and note it in docs/testing.md.
# Env: MAX_LEN (default 65536), JOBS (build jobs, default 2), FUZZ_ARGS (more libFuzzer flags),
# NO_BUILD=1 (run what build-fuzz/ holds).
set -euo pipefail
cd "$(dirname "$(readlink -f "$0")")/.."

targets() { grep -E '^fuzz_' fuzz/targets.txt | awk '{print $1}'; }
seedsOf() { grep -E "^$1([[:space:]]|\$)" fuzz/targets.txt | awk '{for (i = 2; i <= NF; ++i) print $i}'; }

target=${1:-fuzz_dbc}
seconds=${2:-600}
case "$target" in
  list) targets; exit 0 ;;
  -h|--help) sed -n '2,14p' "$0"; exit 0 ;;
esac
case "$seconds" in ''|*[!0-9]*) echo "fuzz.sh: SECONDS must be a whole number, not '$seconds'" >&2; exit 2 ;; esac

if [ "$target" = all ]; then
  selected=$(targets)
else
  if ! targets | grep -qx "$target"; then
    echo "fuzz.sh: unknown target '$target' (scripts/fuzz.sh list)" >&2
    exit 2
  fi
  selected=$target
fi

if [ -z "${NO_BUILD:-}" ]; then
  nice -n 19 cmake --preset fuzz >/dev/null
  # shellcheck disable=SC2086
  nice -n 19 cmake --build build-fuzz -j "${JOBS:-2}" --target $selected
fi

run_one() {
  local name=$1
  local work=build-fuzz/corpus-$name findings=build-fuzz/findings-$name
  local log
  log=build-fuzz/logs/$name-$(date +%Y%m%d-%H%M%S).log
  mkdir -p "$work" "$findings" build-fuzz/logs
  # libFuzzer takes folders only: seed files are copied into the work corpus.
  local seed
  for seed in $(seedsOf "$name"); do
    if [ -d "$seed" ]; then cp -rn "$seed"/. "$work"/ 2>/dev/null || true
    else cp -n "$seed" "$work/seed_$(echo "$seed" | tr / _)" 2>/dev/null || true; fi  # same names in two folders
  done
  local extra=()
  [ -d "tests/data/fuzz/$name" ] && extra+=("tests/data/fuzz/$name/corpus" "tests/data/fuzz/$name/regressions")
  [ "$name" = fuzz_dbc ] && [ -d ../shared/corpus/dbc ] && extra+=(../shared/corpus/dbc/cantools ../shared/corpus/dbc/dbcppp)
  local existing=()
  for dir in "${extra[@]}"; do [ -d "$dir" ] && existing+=("$dir"); done
  echo "== $name: ${seconds}s, corpus $work, findings $findings, log $log"
  local status=0
  # UBSan reports are findings too (the build does not make them fatal by itself).
  # shellcheck disable=SC2086
  UBSAN_OPTIONS=${UBSAN_OPTIONS:-halt_on_error=1:print_stacktrace=1} \
    nice -n 19 "build-fuzz/fuzz/$name" "$work" "${existing[@]}" -max_total_time="$seconds" \
    -artifact_prefix="$findings/" -max_len="${MAX_LEN:-65536}" -timeout=10 -rss_limit_mb=2048 \
    -print_final_stats=1 ${FUZZ_ARGS:-} >"$log" 2>&1 || status=$?
  grep -E '^#[0-9]+' "$log" | tail -n 1 || true  # executions, coverage, corpus
  grep -E '^(Done |stat::(number_of_executed_units|average_exec_per_sec|peak_rss_mb))' "$log" || true
  if [ $status -ne 0 ]; then
    echo "fuzz.sh: $name stopped with a finding (exit $status): $(ls "$findings" | tail -n 3 | tr '\n' ' ')" >&2
    grep -m1 -E 'ERROR: |SUMMARY: |deadly signal' "$log" >&2 || true
  fi
  return $status
}

overall=0
for name in $selected; do
  run_one "$name" || overall=1
done
exit $overall
