#!/bin/bash
# Events come from this host only (docs/design/ipc.md, "Events come from this host"), on the
# supervised HHEA stack inside tests/harness/run_isolated.sh:
#   - a host on the LAN (a second network namespace joined by a veth pair; the VCU's host
#     joins the LCM group on that link, as a VCU whose Ethernet carries the group does)
#     sends fault_event_t on OPENVCU_HHEA_FAULT by multicast with TTL 1 and by unicast to
#     the VCU's address; plain LCM on the VCU's host receives both (so the case proves
#     something), yet no consumer believes them: vcu-web's live state, `vcu top --once` and
#     an ipc::EventBus subscriber (what vcu-telemetry and the HMI use) show none (unicast:
#     the subscriber, see below);
#   - a fault published on the VCU's host is shown by all three, the stack's own events
#     (which now loop back through the LAN link's route) keep it running, and lcm-logger
#     (the LCM receive path of lcm-spy) still records the stack's heartbeats and that fault.
# Prints "event_trust: PASS" or "event_trust: FAIL: <why>" and exits 0/1.
set -uo pipefail
NAME=event_trust
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
forge=${OPENVCU_FORGE_EVENT:-${OPENVCU_BIN:-$root/build/bin}/../tests/demo/forge_event}
[ -x "$forge" ] || { echo "$NAME: FAIL: no forge_event at $forge"; exit 1; }
group=239.255.76.67
instance=hhea

# The LAN before the stack: the stack's LCM sockets join the group on the link it is routed to.
unshare --net sleep 300 &
lan=$!
sleep 0.2
ip link add vcu0 type veth peer name lan0 netns $lan || { echo "$NAME: FAIL: cannot create the veth pair"; exit 1; }
ip addr add 10.77.0.1/24 dev vcu0 && ip link set vcu0 up
nsenter -t $lan -n sh -c 'ip link set lo up; ip addr add 10.77.0.2/24 dev lan0; ip link set lan0 up; ip route add default via 10.77.0.1' ||
  { echo "$NAME: FAIL: cannot set up the LAN namespace"; exit 1; }
ip route add $group/32 dev vcu0

VEHICLE=hhea
source "$here/supervised_stack.sh"
fail() {
  echo "$NAME: FAIL: $*"
  [ -f "$run/web.log" ] && { echo "---- vcu-web's log (last 20 lines)"; tail -n 20 "$run/web.log"; }
  exit 1
}
start_supervisor
cleanup() {
  [ -n "${web:-}" ] && kill "$web" 2>/dev/null
  kill $lan 2>/dev/null
  ctl shutdown >/dev/null 2>&1
  wait "$supervisor" 2>/dev/null
}
trap cleanup EXIT
beats() { "$vcu" status --config "$config" --wait 1.2 2>/dev/null; }
for _ in $(seq 1 30); do [ "$(beats | grep -c '^vcu-')" -ge 5 ] && break; done
[ "$(beats | grep -c '^vcu-')" -ge 5 ] || fail "the stack did not come up: $(beats)"

# vcu-web, read-only (no users file)
port=18090
mkdir -p "$run/data"
"$bin/vcu-web" --config "$config" --listen 127.0.0.1:$port --data-folder "$run/data" --users "$run/no-users.json" \
  --www "$root/services/web/www" > "$run/web.log" 2>&1 &
web=$!
for _ in $(seq 1 100); do curl -s -o /dev/null --max-time 1 "http://127.0.0.1:$port/api/info" && break; sleep 0.1; done
curl -s -o /dev/null --max-time 1 "http://127.0.0.1:$port/api/info" || fail "vcu-web does not answer"

# the witnesses: plain LCM, an EventBus subscriber, lcm-logger, vcu top
"$forge" listen $instance 4 > "$run/listen.out" 2>&1 &
listener=$!
"$forge" events $instance 4 > "$run/events.out" 2>&1 &
subscriber=$!
for _ in $(seq 1 50); do
  [ "$(cat "$run/listen.out" "$run/events.out" | grep -c '^LISTENING')" -eq 2 ] && break
  grep -q '^ERROR' "$run/events.out" && fail "the EventBus subscriber did not open: $(cat "$run/events.out")"
  sleep 0.1
done
lcm-logger -f "$run/local.lcmlog" > "$run/logger.out" 2>&1 &
logger=$!
"$vcu" top --once --config "$config" > "$run/top.out" 2>&1 &
top=$!

# multicast: one forger on the LAN, one on the VCU's host; each 1.2 s long, over top's window
nsenter -t $lan -n "$forge" fault $group $instance BMS_Isolation_forged_multicast 60 > "$run/forge1.out" 2>&1 &
f1=$!
"$forge" fault $group $instance Local_test_fault 60 > "$run/forge2.out" 2>&1 &
f2=$!
wait $f1 || fail "the LAN could not send by multicast: $(cat "$run/forge1.out")"
wait $f2 || fail "the VCU's host could not send: $(cat "$run/forge2.out")"
wait $top
wait $listener $subscriber
kill -INT $logger; wait $logger
curl -sN --max-time 1.5 "http://127.0.0.1:$port/api/live" > "$run/live.out" 2>/dev/null

grep -q "^SEEN BMS_Isolation_forged_multicast" "$run/listen.out" ||
  fail "no forged multicast fault reached the VCU's LCM port, so this case proves nothing: $(sort -u "$run/listen.out" | tr '\n' ' ')"
echo "$NAME: plain LCM on the VCU's host saw: $(sort "$run/listen.out" | uniq -c | tr -s ' ' | tr '\n' ';')"
faults=$(grep -o '"faults":\[[^]]*\]' "$run/live.out" | tail -n 1)
echo "$NAME: vcu-web: $faults"
echo "$NAME: vcu top: $(sed -n '/^FAULTS/,$p' "$run/top.out" | tr -s ' ' | tr '\n' ' ')"
echo "$NAME: EventBus subscriber: $(sort "$run/events.out" | uniq -c | tr -s ' ' | tr '\n' ';')"
grep -q BMS_Isolation_forged <<< "$faults" && fail "vcu-web shows a fault forged on the LAN"
grep -q BMS_Isolation_forged "$run/top.out" && fail "vcu top shows a fault forged on the LAN"
grep -q BMS_Isolation_forged "$run/events.out" && fail "an EventBus subscriber received a fault forged on the LAN"
grep -q Local_test_fault <<< "$faults" || fail "vcu-web does not show the fault published on the VCU's host"
grep -q Local_test_fault "$run/top.out" || fail "vcu top does not show the fault published on the VCU's host: $(cat "$run/top.out")"
grep -q '^EVENT Local_test_fault' "$run/events.out" || fail "the EventBus subscriber missed the local fault"
# lcm-logger, LCM's own receiver, records the stack's events (heartbeats) and the local fault
grep -aq OPENVCU_HHEA_HEARTBEAT "$run/local.lcmlog" || fail "lcm-logger recorded no heartbeat of the stack: $(cat "$run/logger.out")"
grep -aq Local_test_fault "$run/local.lcmlog" || fail "lcm-logger did not record the local fault"
echo "$NAME: lcm-logger recorded $(stat -c %s "$run/local.lcmlog") bytes with the stack's heartbeats and the local fault"

# unicast to the VCU's address: with several sockets bound to 0.0.0.0:7667 (SO_REUSEADDR)
# the kernel hands a unicast datagram to one of them, the newest; so each witness is
# started alone as the newest socket: plain LCM first (proof that it arrives), then an
# EventBus subscriber, which must drop the LAN's and keep one sent by the VCU's host.
unicast() {  # WITNESS OUT SENDER... : the witness as the newest socket, then 20 datagrams
  local witness=$1 out=$2
  shift 2
  "$forge" $witness $instance 2 > "$out" 2>&1 &
  local pid=$!
  for _ in $(seq 1 50); do grep -q '^LISTENING\|^ERROR' "$out" && break; sleep 0.1; done
  "$@" > /dev/null || fail "could not send: $*"
  wait $pid
}
unicast listen "$run/unicast-listen.out" nsenter -t $lan -n "$forge" fault 10.77.0.1 $instance BMS_Isolation_forged_unicast 20
grep -q "^SEEN BMS_Isolation_forged_unicast" "$run/unicast-listen.out" ||
  fail "no forged unicast fault reached the VCU's LCM port, so this case proves nothing: $(sort -u "$run/unicast-listen.out" | tr '\n' ' ')"
unicast events "$run/unicast-lan.out" nsenter -t $lan -n "$forge" fault 10.77.0.1 $instance BMS_Isolation_forged_unicast 20
unicast events "$run/unicast-local.out" "$forge" fault 10.77.0.1 $instance Local_unicast_fault 20
echo "$NAME: unicast to 10.77.0.1:7667: plain LCM saw $(grep -c '^SEEN' "$run/unicast-listen.out") from the LAN;" \
  "an EventBus subscriber $(grep -c '^EVENT' "$run/unicast-lan.out") from the LAN, $(grep -c '^EVENT' "$run/unicast-local.out") from the VCU's host"
grep -q '^EVENT' "$run/unicast-lan.out" && fail "an EventBus subscriber received a fault forged on the LAN by unicast"
grep -q '^EVENT Local_unicast_fault' "$run/unicast-local.out" ||
  fail "an EventBus subscriber missed a unicast fault from the VCU's host: $(cat "$run/unicast-local.out")"
[ "$(beats | grep -c '^vcu-')" -ge 5 ] || fail "the stack's own events stopped: $(beats)"
kill -0 $web 2>/dev/null || fail "vcu-web died"
echo "$NAME: PASS"
