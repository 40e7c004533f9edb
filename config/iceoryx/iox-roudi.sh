#!/bin/sh
# Starts iox-roudi for the openvcu stack so that its shared memory and its socket are open to
# the stack only (issue 18). Arguments go to iox-roudi unchanged (e.g. -c roudi.toml).
#
# What iceoryx 2.0.3 does by itself (measured): /dev/shm/iceoryx_mgmt and /tmp/roudi get
# mode 0660 and RouDi's group; the data segment, named after its writer group (roudi.toml
# `[[segment]] writer`, by default RouDi's group), gets 0660 plus an ACL granting that
# group read/write. The umask changes none of it. RouDi started as root:root therefore
# opened every CAN frame to group 0.
#
#   group `openvcu` exists and this user is a member (scripts/install-deps.sh creates it
#   with root as member): RouDi runs with openvcu as its group (setpriv). iceoryx_mgmt,
#   /tmp/roudi and the data segment /dev/shm/openvcu are <user>:openvcu 0660; the segment's
#   ACL names no group but openvcu. RouDi gives a client the segment whose writer group is
#   among the client user's groups in /etc/group, hence the membership.
#
#   otherwise (owner-only): RouDi runs as it is and, once its socket exists (RouDi creates
#   both segments before it), the segments' ACL and group bits and the socket's group bits
#   are removed: 0600. Clients must then run as RouDi's user (the stack runs as one user).
#   Until then (RouDi's start-up) the files are 0660 for RouDi's group.
#
# The test: tests/demo/roudi_permissions_test.sh. Design: docs/design/signal-table.md, "iceoryx".
set -eu

GROUP=openvcu
SOCKET=/tmp/roudi
user=$(id -un)

if getent group "$GROUP" >/dev/null 2>&1 && id -Gn "$user" | tr ' ' '\n' | grep -qx "$GROUP"; then
  exec setpriv --regid "$GROUP" --clear-groups -- iox-roudi "$@"
fi

if getent group "$GROUP" >/dev/null 2>&1; then
  why="user $user is not a member of group $GROUP"
else
  why="no group $GROUP (scripts/install-deps.sh creates it)"
fi
echo "iox-roudi.sh: $why: iceoryx's shared memory and $SOCKET made owner-only (0600)" >&2
segment=/dev/shm/$(id -gn)
# A socket left by a killed RouDi is not the sign we wait for: RouDi replaces it.
stale=$(stat -c %i "$SOCKET" 2>/dev/null || echo none)
# A helper outside RouDi's process (the subshell returns at once, so nothing is left to
# reap): waits (at most 30 s) for RouDi's new socket, the sign that both segments exist,
# then closes them.
(
  (
    tries=0
    while [ "$(stat -c %i "$SOCKET" 2>/dev/null || echo none)" = "$stale" ] || [ ! -S "$SOCKET" ]; do
      [ $tries -lt 600 ] || exit 0
      sleep 0.05
      tries=$((tries + 1))
    done
    for file in /dev/shm/iceoryx_mgmt "$segment" "$SOCKET"; do
      [ -e "$file" ] || continue
      if command -v setfacl >/dev/null 2>&1; then setfacl -b "$file"; fi
      chmod 600 "$file"
    done
  ) </dev/null &
)
exec iox-roudi "$@"
