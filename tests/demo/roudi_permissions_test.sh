#!/bin/bash
# Issue 18: iox-roudi as the stack starts it (the [program:roudi] command of
# config/supervisor/openvcu.conf, i.e. config/iceoryx/iox-roudi.sh) leaves its shared memory
# (/dev/shm/iceoryx_mgmt, the data segment that carries every CAN frame) and its socket
# /tmp/roudi to the stack only: owned by group openvcu with no ACL entry for another group,
# or owner-only (0600, no ACL) where that group cannot be used (the three cases A, B, C of
# config/iceoryx/iox-roudi.sh). Before,
# all three were 0660 root:root and the data segment's ACL granted group 0 read/write.
# Each case runs against its own /etc/group (bind-mounted in this private mount namespace,
# so the machine's is never touched), starts RouDi, checks modes, owners and ACLs with
# stat and getfacl, and checks that a client of the stack's user still publishes and
# receives a frame (vcu send --direct / vcu dump).
#   run_isolated.sh -- tests/demo/roudi_permissions_test.sh      (ctest: label integration)
set -euo pipefail
NAME=roudi_permissions_test
root=$(cd "$(dirname "$0")/../.." && pwd)
bin=${OPENVCU_BIN:-$root/build/bin}
config=$root/config/hhea/vehicle.json

if [ "${OPENVCU_ISOLATED:-0}" != 1 ]; then echo "$NAME: SKIP: run inside tests/harness/run_isolated.sh"; exit 77; fi
if ! awk '$1 == 0 && $2 == 0 && $3 == 4294967295 { found = 1 } END { exit !found }' /proc/self/gid_map; then
  echo "$NAME: SKIP: needs real root (a user namespace maps no group openvcu could run as)"; exit 77
fi
command -v getfacl >/dev/null || { echo "$NAME: FAIL: getfacl missing (package acl, scripts/install-deps.sh)"; exit 1; }

# The command supervisord runs for RouDi, with its variable filled as run.sh fills it.
roudi_command=$(sed -n '/^\[program:roudi\]/,/^$/s/^command=//p' "$root/config/supervisor/openvcu.conf")
roudi_command=${roudi_command//%(ENV_OPENVCU_ROUDI)s/$root/config/iceoryx/iox-roudi.sh}
[ -n "$roudi_command" ] || { echo "$NAME: FAIL: no [program:roudi] command in openvcu.conf"; exit 1; }
user=$(id -un)
work=$(mktemp -d)
failures=0
fail() { echo "$NAME: FAIL: $*"; failures=$((failures + 1)); }

# group_file NAME LINE: /etc/group without any openvcu line, plus LINE when given
group_file() {
  grep -v '^openvcu:' /etc/group > "$work/group.$1" || true
  [ -z "$2" ] || echo "$2" >> "$work/group.$1"
  echo "$work/group.$1"
}

free_gid() {
  local gid=990
  while getent group "$gid" >/dev/null; do gid=$((gid - 1)); done
  echo "$gid"
}

# acl_of FILE: the ACL as one line, e.g. "user::rw- group::rw- group:openvcu:rw- mask::rw- other::---"
acl_of() { getfacl -c -p "$1" 2>/dev/null | grep -v '^$' | tr '\n' ' ' | sed 's/ $//'; }

wait_for_socket() {
  for _ in $(seq 1 250); do
    [ -S /tmp/roudi ] && return 0
    kill -0 "$roudi" 2>/dev/null || return 1
    sleep 0.02
  done
  return 1
}

# A client as the stack runs them: a frame sent on the simulated bus reaches `vcu dump`
# (sent 20 times over 1 s: a subscriber may need a moment to be connected).
client_works() {
  timeout 10 "$bin/vcu" dump vehicle -s wire -n 1 --timeout 5 --config "$config" > "$work/dump" 2>&1 &
  local dump=$!
  for _ in $(seq 1 100); do grep -q '^listening' "$work/dump" && break; sleep 0.05; done
  timeout 10 "$bin/vcu" send vehicle 123#DEADBEEF --direct --repeat 20 --interval 50 --config "$config" > "$work/send" 2>&1 || true
  wait "$dump" || true
  grep -q '123#DEADBEEF' "$work/dump"
}

# run_case NAME GROUP_LINE EXPECT [IOX-ROUDI ARGS...]
#   EXPECT member:    all three <user>:openvcu 0660, the segment /dev/shm/openvcu with an ACL for openvcu only
#          nonmember: iceoryx_mgmt and /tmp/roudi <user>:openvcu 0660, /dev/shm/<user's group> 0600 without ACL
#          nogroup:   all three 0600 without ACL
run_case() {
  local name=$1 line=$2 expect=$3
  shift 3
  local file
  file=$(group_file "$name" "$line")
  mount --bind "$file" /etc/group
  rm -f /tmp/roudi
  $roudi_command "$@" > "$work/roudi.$name.log" 2>&1 &
  roudi=$!
  if ! wait_for_socket; then
    fail "$name: iox-roudi did not open its socket: $(tail -3 "$work/roudi.$name.log")"
  else
    local socket_changed segment path mode named
    socket_changed=$(stat -c %z /tmp/roudi)
    declare -A want
    case "$expect" in
      member) segment=/dev/shm/openvcu
        want=([/dev/shm/iceoryx_mgmt]="660 $user:openvcu" [$segment]="660 $user:openvcu" [/tmp/roudi]="660 $user:openvcu") ;;
      nonmember) segment=/dev/shm/$(id -gn)
        want=([/dev/shm/iceoryx_mgmt]="660 $user:openvcu" [$segment]="600 $user:openvcu" [/tmp/roudi]="660 $user:openvcu") ;;
      nogroup) segment=/dev/shm/$(id -gn)
        want=([/dev/shm/iceoryx_mgmt]="600 $user:$(id -gn)" [$segment]="600 $user:$(id -gn)" [/tmp/roudi]="600 $user:$(id -gn)") ;;
    esac
    # the launcher's helper closes files right after RouDi's socket appears: wait for it
    [ "$expect" = member ] || for _ in $(seq 1 250); do [ "$(stat -c %a "$segment" 2>/dev/null)" = 600 ] && break; sleep 0.02; done
    for path in /dev/shm/iceoryx_mgmt "$segment" /tmp/roudi; do
      if [ ! -e "$path" ]; then fail "$name: $path missing ($(ls /dev/shm | tr '\n' ' '))"; continue; fi
      mode=$(stat -c '%a %U:%G' "$path")
      echo "$NAME: $name: $path: $mode; ACL: $(acl_of "$path")"
      [ "$mode" = "${want[$path]}" ] || fail "$name: $path is '$mode', expected '${want[$path]}'"
      # no named ACL entry for any group but openvcu (iceoryx adds group:<writer group>)
      named=$(getfacl -c -p "$path" 2>/dev/null | grep -E '^group:[^:]+:' | grep -v '^group:openvcu:' || true)
      [ -z "$named" ] || fail "$name: $path grants a group beyond openvcu: $named"
      if [ "$path" != "$segment" ] || [ "$expect" != member ]; then
        [ -z "$(getfacl -c -p -s "$path" 2>/dev/null)" ] || fail "$name: $path has an ACL: $(acl_of "$path")"
      fi
    done
    if [ "$expect" = member ]; then
      [ "$(acl_of "$segment")" = "user::rw- group::rw- group:openvcu:rw- mask::rw- other::---" ] ||
        fail "$name: $segment ACL is '$(acl_of "$segment")'"
    fi
    # services take a socket whose change time moved for a new RouDi (and restart): only the
    # owner-only start may touch it
    if [ "$expect" != nogroup ] && [ "$(stat -c %z /tmp/roudi)" != "$socket_changed" ]; then
      fail "$name: /tmp/roudi was changed after RouDi created it (services would restart)"
    fi
    client_works || fail "$name: a client of user $user could not send and receive a frame: $(cat "$work/send" "$work/dump" | tail -4)"
  fi
  kill -TERM "$roudi" 2>/dev/null || true
  wait "$roudi" 2>/dev/null || true
  umount /etc/group
  rm -f /tmp/roudi /dev/shm/iceoryx_mgmt /dev/shm/openvcu "/dev/shm/$(id -gn)"
}

gid=$(getent group openvcu | cut -d: -f3 || true)
[ -n "$gid" ] || gid=$(free_gid)
run_case "group openvcu with $user as member" "openvcu:x:$gid:$user" member
run_case "group openvcu with $user as member, the test harness's arguments" "openvcu:x:$gid:$user" member \
  -c "$root/config/iceoryx/roudi.toml" -l warning
run_case "group openvcu without $user" "openvcu:x:$gid:" nonmember
run_case "no group openvcu" "" nogroup

# A RouDi SIGKILLed and started again (supervisord's autorestart, the soak test) leaves its
# socket and segments behind: the launcher must close the new segment, not the old one.
restart_name="group openvcu without $user, RouDi SIGKILLed and started again"
mount --bind "$(group_file restart "openvcu:x:$gid:")" /etc/group
$roudi_command > "$work/roudi.first.log" 2>&1 &
roudi=$!
if wait_for_socket; then
  old_socket=$(stat -c %i /tmp/roudi)
  kill -KILL "$roudi"; wait "$roudi" 2>/dev/null || true
  $roudi_command > "$work/roudi.second.log" 2>&1 &
  roudi=$!
  for _ in $(seq 1 250); do [ "$(stat -c %i /tmp/roudi 2>/dev/null)" != "$old_socket" ] && break; sleep 0.02; done
  segment=/dev/shm/$(id -gn)
  for _ in $(seq 1 250); do [ "$(stat -c %a "$segment" 2>/dev/null)" = 600 ] && break; sleep 0.02; done
  echo "$NAME: $restart_name: $segment: $(stat -c '%a %U:%G' "$segment"); ACL: $(acl_of "$segment")"
  [ "$(stat -c %a "$segment")" = 600 ] || fail "$restart_name: $segment is $(stat -c %a "$segment")"
  [ -z "$(getfacl -c -p -s "$segment" 2>/dev/null)" ] || fail "$restart_name: $segment has an ACL: $(acl_of "$segment")"
  kill -TERM "$roudi" 2>/dev/null || true
  wait "$roudi" 2>/dev/null || true
else
  fail "$restart_name: iox-roudi did not open its socket: $(tail -3 "$work/roudi.first.log")"
fi
umount /etc/group
rm -rf "$work"
if [ $failures -ne 0 ]; then echo "$NAME: $failures failure(s)"; exit 1; fi
echo "$NAME: PASS"
