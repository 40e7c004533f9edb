#!/bin/bash
# Runs one command in a throw-away sandbox for IPC tests and benchmarks:
#   - private mount namespace with fresh tmpfs on /dev/shm and /tmp, so an iox-roudi started
#     inside never meets the machine's RouDi (/tmp/roudi, /tmp/*.lock, /dev/shm/iceoryx_mgmt);
#   - private network namespace with only `lo` up and a multicast route on it, so LCM's
#     udpm traffic cannot leave the namespace (network rule: loopback only);
#   - private PID namespace: when the command exits, the kernel ends every process it left
#     behind (iox-roudi, peers, java, Xvfb): no stray processes, nothing to kill by name.
# Directories under /tmp that the command needs (the build tree) are bound back into the
# fresh /tmp at the same path with --keep. OPENVCU_ISOLATED=1 tells the command it is inside.
#
#   run_isolated.sh [--keep DIR]... [--] COMMAND [ARG]...
#
# Needs root or unprivileged user namespaces (then it adds --user --map-root-user).
# Minimal and self-contained on purpose: tests/harness/ may fold it in.
set -euo pipefail

keep=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --keep) keep+=("$2"); shift 2 ;;
    --) shift; break ;;
    -h|--help) sed -n '2,16p' "$0"; exit 0 ;;
    *) break ;;
  esac
done
if [[ $# -eq 0 ]]; then
  echo "run_isolated.sh: no command given (see --help)" >&2
  exit 2
fi

if [[ "${OPENVCU_ISOLATION_STAGE:-}" != "inside" ]]; then
  userns=()
  if [[ "$(id -u)" != 0 ]]; then userns=(--user --map-root-user); fi
  keepArgs=()
  for dir in "${keep[@]}"; do keepArgs+=(--keep "$dir"); done
  # --kill-child: if ctest kills us (timeout), PID 1 of the namespace dies and takes everything with it.
  OPENVCU_ISOLATION_STAGE=inside exec unshare "${userns[@]}" --mount --net --pid --fork --kill-child \
    --mount-proc --propagation private -- "$0" "${keepArgs[@]}" -- "$@"
fi

# ---- inside the namespaces (we are PID 1) ----
unset OPENVCU_ISOLATION_STAGE
fds=()
for dir in "${keep[@]}"; do
  dir="$(cd "$dir" && pwd -P)"
  exec {fd}<"$dir"  # hold the directory open across the /tmp mount
  fds+=("$fd:$dir")
done
workdir="$(pwd -P)"

mount -t tmpfs -o mode=1777,size=512m openvcu-shm /dev/shm
mount -t tmpfs -o mode=1777,size=512m openvcu-tmp /tmp
for entry in "${fds[@]}"; do
  fd="${entry%%:*}"; dir="${entry#*:}"
  case "$dir" in
    /tmp|/tmp/*|/dev/shm|/dev/shm/*)
      mkdir -p "$dir"
      # --no-canonicalize: resolve the fd link in the kernel, not to its (now hidden) path
      mount --no-canonicalize --bind "/proc/$$/fd/$fd" "$dir" ;;
  esac
done
# Our cwd survives the mounts even when hidden; prefer the re-bound path when there is one.
cd "$workdir" 2>/dev/null || true

ipcmd="$(command -v ip || echo /usr/sbin/ip)"
"$ipcmd" link set lo up
"$ipcmd" route add 224.0.0.0/4 dev lo

export OPENVCU_ISOLATED=1
# Not exec: PID 1 ignores default-action signals and must reap orphans; stay the parent.
set +e
"$@"
status=$?
exit "$status"
