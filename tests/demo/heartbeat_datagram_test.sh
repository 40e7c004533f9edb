#!/bin/bash
# Issue 19 (inside run_isolated.sh): every event of the supervised HHEA stack that must
# arrive whole arrives in one UDP datagram, and a restarted service is heard at once.
#   - lcm-logger records 4 s of the stack's LCM traffic; each HEARTBEAT, STATS and SCHEDULE
#     message must fit LCM's single-datagram size (8-byte header + channel + NUL + payload
#     <= 1400 bytes; larger ones are fragmented, and a lost fragment loses the message);
#   - the per-message statistics are there: can-rx's rx.<Msg>.*, can-tx's tx.<Msg>.* and the
#     live schedule (vcu status --stats);
#   - with both cores busy (two busy shells for the duration), vcu-can-rx is SIGKILLed three
#     times; printed each time: kill -> supervisord names the new pid, and new pid -> `vcu
#     status` lists it (the process's start, its first beats and vcu status's own start,
#     all under load), which must stay under RESTART_LIMIT_S (before #19: 2.5-24 s under load).
#   heartbeat_datagram_test.sh      (ctest: label integration)
set -uo pipefail
NAME=heartbeat_datagram
RESTART_LIMIT_S=5
# shellcheck source=stack_lib.sh
. "$(dirname "$0")/stack_lib.sh"
for _ in $(seq 1 30); do [ "$(beats | grep -c '^vcu-')" -ge 5 ] && break; done
[ "$(beats | grep -c '^vcu-')" -ge 5 ] || fail "the stack did not come up"

timeout -s INT 4 lcm-logger -f "$run/events.lcmlog" >/dev/null 2>&1
[ -s "$run/events.lcmlog" ] || fail "lcm-logger recorded nothing"
report=$(/usr/bin/python3 - "$run/events.lcmlog" <<'PY'
import struct, sys, collections
data = open(sys.argv[1], 'rb').read()
pos, largest, counts, too_big = 0, collections.defaultdict(int), collections.Counter(), []
while pos + 28 <= len(data):
    sync, _, _, channel_len, data_len = struct.unpack('>IqqII', data[pos:pos + 28])
    if sync != 0xEDA1DA01:
        sys.exit('bad log at byte %d' % pos)
    channel = data[pos + 28:pos + 28 + channel_len].decode()
    pos += 28 + channel_len + data_len
    kind = channel.rsplit('_', 1)[-1]
    datagram = 8 + channel_len + 1 + data_len
    counts[kind] += 1
    largest[kind] = max(largest[kind], datagram)
    if kind in ('HEARTBEAT', 'STATS', 'SCHEDULE') and datagram > 1400:
        too_big.append('%s %d bytes' % (channel, datagram))
for kind in sorted(counts):
    print('%s: %d messages, largest datagram %d bytes' % (kind, counts[kind], largest[kind]))
for line in too_big[:5]:
    print('TOO BIG: ' + line)
PY
)
echo "$report" | sed "s/^/$NAME: /"
failures=0
check() { echo "$NAME: FAIL: $*"; failures=$((failures + 1)); }
echo "$report" | grep -q '^TOO BIG' && check "messages larger than one datagram"
for kind in HEARTBEAT STATS SCHEDULE; do
  echo "$report" | grep -q "^$kind: " || check "no $kind message recorded"
done

stats=$("$vcu" status --config "$config" --wait 1.2 --stats 2>/dev/null)
echo "$stats" | grep '^vcu-can-rx' | grep -q ' rx\.VIC_[A-Za-z0-9_]*\.frames=[1-9]' ||
  echo "$stats" | grep '^vcu-can-rx' | grep -qE ' rx\.[A-Za-z0-9_]+\.frames=[1-9]' || check "no rx.<Msg>.frames in vcu status --stats"
echo "$stats" | grep '^vcu-can-tx' | grep -qE ' tx\.[A-Za-z0-9_]+\.frames=[1-9]' || check "no tx.<Msg>.frames in vcu status --stats"
plain=$(beats | grep '^vcu-can-rx')
echo "$plain" | grep -qE ' rx\.[A-Za-z0-9_]+\.' && check "vcu status without --stats shows per-message counters"

# both cores busy while can-rx is killed and comes back
load_pids=()
for _ in 1 2; do (while :; do :; done) & load_pids+=($!); done
trap 'kill "${load_pids[@]}" 2>/dev/null; ctl shutdown >/dev/null 2>&1; wait $supervisor 2>/dev/null' EXIT
times=()
for round in 1 2 3; do
  for _ in $(seq 1 50); do ctl status can-rx | grep -q RUNNING && break; sleep 0.2; done
  old=$(ctl pid can-rx)
  kill -KILL "$old"
  killed=$(date +%s%N)
  new=""
  while [ $(( ($(date +%s%N) - killed) / 1000000000 )) -lt 30 ]; do
    new=$(ctl pid can-rx 2>/dev/null)
    [ -n "$new" ] && [ "$new" != "$old" ] && [ "$new" -gt 0 ] 2>/dev/null && break
    new=""
    sleep 0.1
  done
  [ -n "$new" ] || { check "round $round: supervisord did not restart vcu-can-rx within 30 s"; continue; }
  started=$(date +%s%N)
  seen=""
  while [ $(( ($(date +%s%N) - started) / 1000000000 )) -lt 30 ]; do
    if "$vcu" status --config "$config" --wait 0.3 2>/dev/null | grep -q "^vcu-can-rx *$new "; then
      seen=$(( ($(date +%s%N) - started) / 1000000 ))
      break
    fi
  done
  [ -n "$seen" ] || { check "round $round: the restarted vcu-can-rx (pid $new) was not heard within 30 s"; continue; }
  times+=("$(( (started - killed) / 1000000 ))+$seen")
  [ "$seen" -le $((RESTART_LIMIT_S * 1000)) ] || check "round $round: the restarted vcu-can-rx was heard $seen ms after its start"
done
kill "${load_pids[@]}" 2>/dev/null
echo "$NAME: both cores busy, kill -> supervisord's new pid + new pid -> heard by vcu status: ${times[*]} ms"
if [ $failures -gt 0 ]; then
  ctl shutdown >/dev/null 2>&1
  exit 1
fi
echo "$NAME: PASS"
