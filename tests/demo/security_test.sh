#!/bin/bash
# Issue 18, tried as an attacker and a careless user would, on the supervised HHEA stack
# inside tests/harness/run_isolated.sh (docs/design/security.md):
#   1. user nobody: `vcu signal set`, a direct connect to the command sockets, a socket of its
#      own in the command folder, `vcu send` of a frame: all refused, the FSM stays in Standby;
#   2. a member of the command group (nobody with group openvcu) may command (skipped, and
#      said so, when the group does not exist: scripts/install-deps.sh creates it);
#   3. a flood of 3,000 requests on one connection: every one answered (most "rate limit"),
#      and an operator's Start from another connection meanwhile is accepted within its 2 s
#      and drives the vehicle to Ready (the flood does not flood the event bus);
#   4. a request that waits past its deadline (vcu-fsm stopped by SIGSTOP) is reported as not
#      applied and is never applied once vcu-fsm runs again;
#   5. a host on the LAN (a second network namespace joined by a veth pair, the stack's host
#      joined to the LCM group on that link): forged command datagrams and forged "accepted"
#      answers reach the host (seen by an LCM listener) and change nothing;
#   6. with no stack running, `vcu signal set` fails whatever forged answers fly around.
# Prints "security: PASS" or "security: FAIL: <why>" and exits 0/1.
set -uo pipefail
NAME=security
source "$(dirname "$0")/stack_lib.sh"
forge=${OPENVCU_FORGE:-$bin/../tests/demo/forge_command}
[ -x "$forge" ] || fail "no forge_command at $forge"
instance=hhea
start_key=internal.operator.StartStop

for _ in $(seq 1 30); do [ "$(beats | grep -c '^vcu-')" -ge 5 ] && break; done
[ "$(beats | grep -c '^vcu-')" -ge 5 ] || fail "the stack did not come up"
wait_state Standby || fail "not in Standby at start: $(state)"
sockets=$(ls /run/openvcu/$instance 2>/dev/null || ls "${OPENVCU_RUN_DIR:-/nonexistent}/$instance")
echo "$NAME: command sockets: $(echo $sockets)"
folder=${OPENVCU_RUN_DIR:-/run/openvcu}/$instance

# 1. nobody
out=$(runuser -u nobody -- "$vcu" signal set $start_key Start --config "$config" 2>&1)
[ $? -ne 0 ] || fail "nobody's vcu signal set succeeded: $out"
echo "$out" | grep -qi "permission denied" || fail "nobody's refusal does not say why: $out"
echo "$NAME: nobody, vcu: $out"
out=$(runuser -u nobody -- /usr/bin/python3 -c "
import socket, sys
s = socket.socket(socket.AF_UNIX, socket.SOCK_SEQPACKET)
try:
    s.connect('$folder/vcu-fsm.sock'); print('CONNECTED')
except OSError as e:
    print('REFUSED', e)
try:
    t = socket.socket(socket.AF_UNIX, socket.SOCK_SEQPACKET); t.bind('$folder/evil.sock'); print('BOUND')
except OSError as e:
    print('REFUSED', e)
" 2>&1)
echo "$NAME: nobody, raw sockets: $(echo $out)"
echo "$out" | grep -q "CONNECTED\|BOUND" && fail "nobody reached or planted a command socket: $out"
# frames to the bus go through iceoryx (RouDi's socket and memory: root and group openvcu only)
out=$(runuser -u nobody -- "$vcu" send vehicle 18EF2100#0102030405060708 --config "$config" 2>&1)
[ $? -ne 0 ] || fail "nobody's vcu send was sent: $out"
echo "$out" | grep -q "may not use it" || fail "nobody's vcu send refusal does not say why: $out"
echo "$NAME: nobody, vcu send: $out"
out=$(runuser -u nobody -- "$vcu" send --direct vehicle 18EF2100#0102030405060708 --config "$config" 2>&1)
[ $? -ne 0 ] || fail "nobody's vcu send --direct was sent: $out"
echo "$NAME: nobody, vcu send --direct: $out"

# 2. a member of the command group
if gid=$(getent group openvcu | cut -d: -f3) && [ -n "$gid" ]; then
  out=$(setpriv --reuid=65534 --regid=65534 --groups="$gid" -- "$vcu" signal set internal.operator.ConnectDriving 0 --config "$config" 2>&1)
  [ "$out" = "accepted" ] || fail "a member of group openvcu was not let in: $out"
  echo "$NAME: nobody in group openvcu: $out"
else
  echo "$NAME: SKIPPED (group openvcu does not exist): a member of the command group may command"
fi
[ "$(state)" = Standby ] || fail "the FSM left Standby: $(state)"

# 3. a flood on one connection does not starve an operator
"$forge" flood $instance vcu-fsm 3000 internal.fsm.state > "$run/flood.out" 2>&1 &
flooder=$!
sleep 0.2
t0=$(date +%s%N)
out=$("$vcu" signal set $start_key Start --config "$config" 2>&1) || fail "Start during a flood: $out"
t1=$(date +%s%N)
echo "$NAME: Start during a flood: $out in $(( (t1 - t0) / 1000000 )) ms"
wait $flooder || fail "the flood was not answered in full: $(cat "$run/flood.out")"
echo "$NAME: flood: $(cat "$run/flood.out")"
limited=$(beats | grep '^vcu-fsm' | grep -oE 'commands_limited[=: ]+[0-9]+' | grep -oE '[0-9]+$')
echo "$NAME: vcu-fsm refused by the rate limit: $limited"
[ "${limited:-0}" -gt 2000 ] || fail "the flood was not limited: $(beats | grep '^vcu-fsm')"
wait_state Ready || fail "not Ready after Start: $(state)"
out=$("$vcu" signal set $start_key Stop --config "$config" 2>&1) || fail "Stop: $out"
wait_state Standby || fail "not back in Standby after Stop: $(state)"

# 4. a request that waits past its deadline is never applied
fsm=$(ctl pid fsm)
kill -STOP "$fsm"
out=$("$vcu" signal set $start_key Start --timeout 0.5 --config "$config" 2>&1)
status=$?
kill -CONT "$fsm"
[ $status -ne 0 ] || fail "a command to a stopped vcu-fsm was reported as applied: $out"
echo "$NAME: to a stopped vcu-fsm: $out"
sleep 1.5
[ "$(state)" = Standby ] || fail "the expired Start was applied later: $(state)"
expired=$(beats | grep '^vcu-fsm' | grep -oE 'commands_expired[=: ]+[0-9]+' | grep -oE '[0-9]+$')
echo "$NAME: vcu-fsm counts commands_expired $expired"
[ "$expired" = "1" ] || fail "vcu-fsm did not count the expired request: $(beats | grep '^vcu-fsm')"

# 5. a host on the LAN
unshare --net sleep 120 &
lan=$!
sleep 0.2
ip link add vcu0 type veth peer name lan0 netns $lan || fail "cannot create the veth pair"
ip addr add 10.77.0.1/24 dev vcu0 && ip link set vcu0 up
nsenter -t $lan -n sh -c 'ip link set lo up; ip addr add 10.77.0.2/24 dev lan0; ip link set lan0 up; ip route add default via 10.77.0.1' ||
  fail "cannot set up the LAN namespace"
# The VCU's host joins the LCM group on the LAN link (as a VCU whose default route is its
# Ethernet does): the listener below joins through this route.
ip route add 239.255.76.67/32 dev vcu0
"$forge" listen "udpm://239.255.76.67:7667?ttl=0" $instance 8 > "$run/listen.out" 2>&1 &
listener=$!
for _ in $(seq 1 50); do grep -q LISTENING "$run/listen.out" && break; sleep 0.1; done
nsenter -t $lan -n "$forge" datagram 239.255.76.67 $instance $start_key 1 10 || fail "the LAN could not send"
nsenter -t $lan -n "$forge" datagram 10.77.0.1 $instance $start_key 1 10 || fail "the LAN could not send unicast"
sleep 1
kill $listener 2>/dev/null; wait $listener 2>/dev/null
seen=$(grep -c '^SEEN' "$run/listen.out")
echo "$NAME: forged datagrams from the LAN seen on the VCU's host: $seen"
[ "$seen" -gt 0 ] || fail "no forged datagram reached the host, so this case proves nothing"
[ "$(state)" = Standby ] || fail "the LAN commanded the FSM: $(state)"
kill $lan 2>/dev/null

# 6. no stack: forged answers cannot make vcu report success
ctl stop all > /dev/null
"$forge" datagram 127.0.0.1 $instance $start_key 1 100 > /dev/null &
forger=$!
out=$("$vcu" signal set $start_key Start --config "$config" 2>&1)
status=$?
kill $forger 2>/dev/null
[ $status -ne 0 ] || fail "with no stack, vcu reported: $out"
echo "$NAME: no stack, forged answers flying: $out"

echo "$NAME: PASS"
