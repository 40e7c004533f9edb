#!/bin/bash
# Starts iox-roudi for the openvcu stack so that its shared memory and its socket are open to
# the stack only (issue 18). Configuration: roudi.toml beside this script, or the file given
# with -c/--config-file; every other argument goes to iox-roudi unchanged (e.g. -l warning).
#
# What iceoryx 2.0.3 does by itself (measured): /dev/shm/iceoryx_mgmt and /tmp/roudi get
# mode 0660 and RouDi's group; the data segment, named after its writer group (roudi.toml
# `[[segment]] writer`, by default RouDi's group), gets 0660 plus an ACL granting its writer
# (and reader) group read/write. The umask changes none of it. RouDi gives a client the
# segment whose writer group is among the client user's groups in /etc/group (a client
# without one aborts). Started as root:root, all of it was open to group 0.
#
#   A. group `openvcu` exists and this user is a member: RouDi runs with group openvcu
#      (setpriv). iceoryx_mgmt, /tmp/roudi and the data segment /dev/shm/openvcu are
#      <user>:openvcu 0660; the segment's ACL names no group but openvcu.
#   B. group `openvcu` exists, this user is not a member (scripts/install-deps.sh creates it
#      without members): RouDi runs with group openvcu, so iceoryx_mgmt and /tmp/roudi are
#      <user>:openvcu 0660; the segment keeps the user's own group as reader and writer (its
#      clients need it) and is named after it (/dev/shm/root); its ACL and group bits are
#      removed as soon as RouDi's socket exists: <user>:openvcu 0600.
#   C. no group `openvcu`: owner-only. RouDi runs as it is; once its socket exists, the
#      ACL and group bits of both segments and of the socket are removed: 0600. The chmod
#      moves the socket's change time: a service that registered before it takes RouDi for
#      replaced (ipc::Runtime::roudiReplaced compares it) and exits 75 once.
# In every case RouDi gets SIGTERM when its parent (supervisord, run.sh's sandbox, a test)
# dies (setpriv --pdeathsig), like the services (PR_SET_PDEATHSIG in their runtime).
# In B and C the files are 0660 for a few milliseconds during RouDi's start-up.
# The test: tests/demo/roudi_permissions_test.sh. Design: docs/design/signal-table.md.
set -euo pipefail

GROUP=openvcu
SOCKET=/tmp/roudi
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
config=$here/roudi.toml
args=()
while [ $# -gt 0 ]; do
  case "$1" in
    -c|--config-file) config=${2:?$1 needs a file}; shift 2 ;;
    --config-file=*) config=${1#*=}; shift ;;
    *) args+=("$1"); shift ;;
  esac
done
user=$(id -un)
own_group=$(id -gn)

# close_later FILE...: a helper outside RouDi's process (the subshell returns at once, so
# nothing is left to reap) waits for RouDi's new socket, the sign that both segments exist
# (at most 30 s, looking every 10 ms), then removes the files' ACL and group bits.
close_later() {
  local stale
  stale=$(stat -c %i "$SOCKET" 2>/dev/null || echo none)  # a killed RouDi's socket is replaced
  (
    (
      tries=0
      while [ "$(stat -c %i "$SOCKET" 2>/dev/null || echo none)" = "$stale" ] || [ ! -S "$SOCKET" ]; do
        [ $tries -lt 3000 ] || exit 0
        sleep 0.01
        tries=$((tries + 1))
      done
      for file in "$@"; do
        [ -e "$file" ] || continue
        if command -v setfacl >/dev/null 2>&1; then setfacl -b "$file"; fi
        chmod 600 "$file"
      done
    ) </dev/null &
  )
}

if getent group "$GROUP" >/dev/null 2>&1; then
  if id -Gn "$user" | tr ' ' '\n' | grep -qx "$GROUP"; then
    exec setpriv --pdeathsig TERM --regid "$GROUP" --clear-groups -- iox-roudi -c "$config" "${args[@]}"
  fi
  echo "iox-roudi.sh: user $user is not a member of group $GROUP: RouDi runs with group $GROUP," \
    "its data segment /dev/shm/$own_group is made owner-only (0600)" >&2
  close_later "/dev/shm/$own_group"
  # the configuration with the user's group as the segment's reader and writer, on stdin
  exec setpriv --pdeathsig TERM --regid "$GROUP" --clear-groups -- iox-roudi -c /dev/stdin "${args[@]}" <<EOF
$(sed -e '/^[[:space:]]*\(reader\|writer\)[[:space:]]*=/d' \
      -e "s/^\[\[segment\]\][[:space:]]*\$/[[segment]]\nreader = \"$own_group\"\nwriter = \"$own_group\"/" "$config")
EOF
fi

echo "iox-roudi.sh: no group $GROUP (scripts/install-deps.sh creates it): iceoryx's shared memory" \
  "and $SOCKET are made owner-only (0600)" >&2
close_later /dev/shm/iceoryx_mgmt "/dev/shm/$own_group" "$SOCKET"
exec setpriv --pdeathsig TERM -- iox-roudi -c "$config" "${args[@]}"
