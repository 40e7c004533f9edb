#!/usr/bin/env bash
# Builds the libFuzzer targets with clang and runs one for a while.
#   scripts/fuzz.sh [TARGET] [SECONDS]      default: fuzz_dbc 600
# Seeds: tests/data/dbc (and the team kit's corpus/dbc when it exists). Findings land in
# build-fuzz/findings-TARGET/; the run's last status line gives executions.
set -euo pipefail
cd "$(dirname "$(readlink -f "$0")")/.."
target=${1:-fuzz_dbc}
seconds=${2:-600}
cmake --preset fuzz >/dev/null
cmake --build --preset fuzz --target "$target"
work=build-fuzz/corpus-$target
findings=build-fuzz/findings-$target
mkdir -p "$work" "$findings"
seeds=()
case "$target" in
  fuzz_dbc)
    seeds+=(tests/data/dbc)
    [ -d ../shared/corpus/dbc ] && seeds+=(../shared/corpus/dbc/cantools ../shared/corpus/dbc/dbcppp)
    ;;
  fuzz_candump)
    seeds+=(tests/data/logs)
    ;;
esac
exec "build-fuzz/fuzz/$target" "$work" "${seeds[@]}" -max_total_time="$seconds" \
  -artifact_prefix="$findings/" -max_len="${MAX_LEN:-65536}" -timeout=10 -print_final_stats=1
