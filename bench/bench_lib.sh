# Helpers the benchmark scripts share (sourced, not run): the machine description, polling,
# CPU pinning and sampling, and ending only the processes a script started.
#
#   source "$repo/bench/bench_lib.sh"
#   bench_isolate "$build" "vcu-can-tx bench_tx_listener" bin/vcu bin/vcu-can-tx bench/bench_tx_listener -- "$0" "$build"
#   started+=("$pid")   # ended, in reverse order, when the script exits

# bench_isolate BUILD TARGETS BINARY... -- COMMAND...: outside the sandbox, checks that every
# BINARY (relative to BUILD) is built, then re-runs COMMAND inside
# tests/harness/run_isolated.sh (private network, /dev/shm); inside, returns.
bench_isolate() {
  local build="$1" targets="$2" binary
  shift 2
  [[ "${OPENVCU_ISOLATED:-}" == 1 ]] && return 0
  while [[ $# -gt 0 && "$1" != "--" ]]; do
    binary="$1"
    shift
    if [[ ! -x "$build/$binary" ]]; then
      echo "error: $build/$binary not built (ninja -C $build $targets)" >&2
      exit 1
    fi
  done
  shift  # the --
  local keep=()
  case "$build" in /tmp/*) keep=(--keep "$build") ;; esac
  exec "$(dirname "${BASH_SOURCE[0]}")/../tests/harness/run_isolated.sh" "${keep[@]}" -- "$@"
}

started=()  # PIDs this script started and has not reaped yet, ended in reverse order

cleanup() {
  local i
  for (( i = ${#started[@]} - 1; i >= 0; i-- )); do
    kill -TERM "${started[$i]}" 2>/dev/null || true
    wait "${started[$i]}" 2>/dev/null || true
  done
}
trap cleanup EXIT

# forget PID: it has been reaped; cleanup must not signal that number again.
forget() {
  local pid kept=()
  for pid in "${started[@]}"; do [[ "$pid" == "$1" ]] || kept+=("$pid"); done
  started=("${kept[@]}")
}

alive() { kill -0 "$1" 2>/dev/null; }

# machine: CPU, memory, kernel, load and the compiler of $build (for docs/benchmarks.md).
machine() {
  echo "== machine"
  lscpu | grep -E '^(Model name|CPU family|Model|CPU\(s\)|Core\(s\) per socket|Thread\(s\) per core|Hypervisor vendor):' |
    sed 's/  */ /g'
  echo "RAM $(free -h | awk '/^Mem:/ {print $2}'), kernel $(uname -r), load $(cut -d' ' -f1-3 /proc/loadavg)"
  grep -E '^CMAKE_(BUILD_TYPE|CXX_COMPILER|CXX_FLAGS_RELEASE):' "$build/CMakeCache.txt" 2>/dev/null || true
  local compiler
  compiler="$(sed -n 's/^CMAKE_CXX_COMPILER:FILEPATH=//p' "$build/CMakeCache.txt" 2>/dev/null)"
  [[ -n "$compiler" ]] && "$compiler" --version | head -n 1
  return 0
}

# wait_until SECONDS COMMAND...: polls COMMAND every 50 ms for up to SECONDS; 1 on timeout.
wait_until() {
  local seconds="$1"; shift
  local deadline=$(( $(date +%s%N) + seconds * 1000000000 ))
  until "$@"; do
    (( $(date +%s%N) < deadline )) || return 1
    sleep 0.05
  done
}

# pinned CPU COMMAND...: COMMAND under `taskset -c CPU`, or as is when CPU is empty.
pinned() {
  local cpu="$1"; shift
  if [[ -n "$cpu" ]]; then exec taskset -c "$cpu" "$@"; else exec "$@"; fi
}
