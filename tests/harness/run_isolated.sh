#!/bin/bash
# Runs one command in a throw-away sandbox: the launcher of every multi-process test
# (tests/integration, tests/shared/service, anything registered with openvcu_isolated_test).
#   - private mount namespace with fresh tmpfs on /dev/shm and /tmp: an iox-roudi or a
#     signal table created inside never meets the machine's (/tmp/roudi, /tmp/*.lock,
#     /dev/shm/iceoryx_mgmt, /dev/shm/openvcu-*), and /dev/shm of this machine is shared
#     with other users;
#   - private network namespace with only `lo` up and 224.0.0.0/4 routed on it: LCM's udpm
#     multicast works and cannot leave (network rule: loopback only);
#   - private PID namespace with the command's parent as PID 1: when the command exits, the
#     kernel ends every process it left behind (iox-roudi, services, java, Xvfb), and
#     --kill-child does the same when ctest kills us on a timeout.
# Directories under /tmp that the command needs (the build tree) are bound back into the
# fresh /tmp at the same path with --keep. --keep-ro binds a directory at the same path
# wherever it lives and makes that view read-only (the team kit beside the repository: its
# corpus and oracle are read by tests, never written). /run/openvcu (command sockets) is a
# private tmpfs too. Supervisor variables that would leak in from
# outside (NOTIFY_SOCKET, WATCHDOG_*, JOURNAL_STREAM, OPENVCU_CONFIG) are cleared, and
# OPENVCU_ISOLATED=1 tells the command it is inside.
#
#   run_isolated.sh [--keep DIR]... [--keep-ro DIR]... [--] COMMAND [ARG]...
#
# Needs root or unprivileged user namespaces (then it adds --user --map-root-user).
set -euo pipefail

keep=()
keepRo=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --keep|--keep-ro)
      if [[ $# -lt 2 || ! -d "$2" ]]; then
        echo "run_isolated.sh: $1 ${2:-}: not a directory" >&2
        exit 2
      fi
      if [[ "$1" == --keep ]]; then keep+=("$2"); else keepRo+=("$2"); fi
      shift 2 ;;
    --) shift; break ;;
    -h|--help) sed -n '2,25p' "$0"; exit 0 ;;
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
  for dir in "${keepRo[@]}"; do keepArgs+=(--keep-ro "$dir"); done
  OPENVCU_ISOLATION_STAGE=inside exec unshare "${userns[@]}" --mount --net --pid --fork --kill-child \
    --mount-proc --propagation private -- "$0" "${keepArgs[@]}" -- "$@"
fi

# ---- inside the namespaces (we are PID 1) ----
unset OPENVCU_ISOLATION_STAGE NOTIFY_SOCKET WATCHDOG_USEC WATCHDOG_PID JOURNAL_STREAM OPENVCU_CONFIG
fds=()
for dir in "${keep[@]}"; do
  dir="$(cd "$dir" && pwd -P)"
  exec {fd}<"$dir"  # hold the directory open across the /tmp mount
  fds+=("$fd:$dir")
done
roFds=()
for dir in "${keepRo[@]}"; do
  dir="$(cd "$dir" && pwd -P)"
  exec {fd}<"$dir"
  roFds+=("$fd:$dir")
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
for entry in "${roFds[@]}"; do
  fd="${entry%%:*}"; dir="${entry#*:}"
  mkdir -p "$dir"
  mount --no-canonicalize --bind "/proc/$$/fd/$fd" "$dir"
  mount -o remount,bind,ro "$dir"
done
cd "$workdir" 2>/dev/null || true

ipcmd="$(command -v ip || echo /usr/sbin/ip)"
"$ipcmd" link set lo up
"$ipcmd" route add 224.0.0.0/4 dev lo

# Command sockets (docs/design/security.md) live in /run/openvcu: a private tmpfs there, so
# stacks of parallel tests never meet; without the right to create the mount point, a
# folder in the private /tmp instead.
if mkdir -p /run/openvcu 2>/dev/null && mount -t tmpfs -o mode=0755,size=16m openvcu-run /run/openvcu 2>/dev/null; then
  unset OPENVCU_RUN_DIR
else
  export OPENVCU_RUN_DIR=/tmp/openvcu-run
fi

export OPENVCU_ISOLATED=1
# Not exec: PID 1 ignores default-action signals and must reap orphans; stay the parent.
set +e
"$@"
exit $?
