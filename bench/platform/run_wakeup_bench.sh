#!/bin/bash
# The platform's own cost of a wake-up (docs/benchmarks.md "Platform: the cost of a
# wake-up"), to set beside the services' CPU and switches per second (bench/stack): how
# much of a service's CPU any program waking that often pays on this machine.
#   bench/platform/run_wakeup_bench.sh [BUILD] [RATE] [SECONDS]
# BUILD default build (needs bench/bench_wakeup: ninja -C BUILD bench_wakeup), RATE wake-ups a
# second (default 1000), SECONDS per phase (default 20). No network and no shared memory, so
# it needs no sandbox. Ends with bench_wakeup's line
#   RESULT timer_wakeup_us=.. relay_sender_us=.. relay_receiver_us=.. rate=.. seconds=.. late_p99_us=..
set -euo pipefail
repo="$(cd "$(dirname "$0")/../.." && pwd)"
build="${1:-$repo/build}"
rate="${2:-1000}"
seconds="${3:-20}"
# shellcheck source=../bench_lib.sh
source "$repo/bench/bench_lib.sh"
if [[ ! -x "$build/bench/bench_wakeup" ]]; then
  echo "error: $build/bench/bench_wakeup not built (ninja -C $build bench_wakeup)" >&2
  exit 1
fi
machine
echo "== bench_wakeup --rate $rate --seconds $seconds ($(date -u +%FT%TZ))"
"$build/bench/bench_wakeup" --rate "$rate" --seconds "$seconds"
