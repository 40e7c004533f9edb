#!/bin/bash
# vcu-web on the simulated HHEA stack, inside tests/harness/run_isolated.sh (issue 23):
#   web_stack_test.sh api       every endpoint of docs/design/web.md (web_api_test.py), then
#                               vcu-web without its users file: read-only
#   web_stack_test.sh browser   the page in headless chromium, then vcu-web SIGKILLed and
#                               started again while the page is open, then a battery fault
#                               injected into the simulated vehicle (web_browser_test.py)
#   web_stack_test.sh cross-origin  a page of a second origin (another port of 127.0.0.1) tries
#                               to command the VCU through the logged-in browser; vcu-web's own
#                               page still commands (web_cross_origin_test.py)
# Starts the HHEA stack under supervisord (tests/demo/supervised_stack.sh; the HMI stays off),
# makes a users file with `vcu-web passwd`, a data folder with one 3 s `vcu record` and a
# symlink out of it (recordings/escape -> /etc: must never be served), starts vcu-web on
# 127.0.0.1:18080 (the sandbox's own loopback) and waits for GET /api/info.
# Screenshots of the browser part: $OPENVCU_WEB_SCREENSHOTS, else <build>/tests/web-screenshots.
# Prints "web_stack_test: PASS" or "web_stack_test: FAIL: <why>" and exits 0/1; 77 (skipped)
# when the browser part lacks chromium, chromium-driver or python3-selenium.
set -uo pipefail
mode=${1:-}
case "$mode" in api|browser|cross-origin) ;; *) echo "usage: web_stack_test.sh api|browser|cross-origin" >&2; exit 2 ;; esac
NAME=web_stack_test
here=$(cd "$(dirname "$0")" && pwd)
python=/usr/bin/python3
export PYTHONDONTWRITEBYTECODE=1  # nothing written into the source tree
[ -x "$python" ] || { echo "$NAME: FAIL: no $python"; exit 1; }
if [ "$mode" != api ]; then
  "$python" "$here/web_browser_test.py" --check-only
  status=$?
  [ $status -eq 0 ] || exit $status  # 77: skipped, said why
fi

VEHICLE=hhea
COPY_VEHICLE=1  # the schedule commands of the tests write schedule.overlay.json beside it
source "$here/../../demo/supervised_stack.sh"
fail() {
  echo "$NAME: FAIL: $*"
  [ -f "$run/web.log" ] && { echo "---- vcu-web's log (last 40 lines)"; tail -n 40 "$run/web.log"; }
  exit 1
}
[ -x "$bin/vcu-web" ] || fail "no vcu-web in $bin"
# the stack's own [program:web] (if the configuration has one) stays off: this test runs its own
if grep -q '^\[program:web\]' "$run/openvcu.conf"; then
  sed -i -e '/^\[program:web\]/,/^$/{/^autostart=/d}' -e 's/^\[program:web\]$/&\nautostart=false/' "$run/openvcu.conf"
fi
start_supervisor
cleanup() {
  [ -f "$run/web.pid" ] && kill -9 "$(cat "$run/web.pid")" 2>/dev/null
  ctl shutdown >/dev/null 2>&1
  wait "$supervisor" 2>/dev/null
}
trap cleanup EXIT

beats() { "$vcu" status --config "$config" --wait 1.2 2>/dev/null; }
for _ in $(seq 1 30); do [ "$(beats | grep -c '^vcu-')" -ge 5 ] && break; done
[ "$(beats | grep -c '^vcu-')" -ge 5 ] || fail "the stack did not come up: $(beats)"

# users, data folder, one recording
user=alice
password=$(head -c 18 /dev/urandom | base64 | tr -d '/+=')
export OPENVCU_WEB_PASSWORD=$password
users=$run/web-users.json
out=$(printf '%s\n' "$password" | "$bin/vcu-web" passwd --users "$users" "$user" 2>&1) || fail "vcu-web passwd: $out"
data=$run/data
mkdir -p "$data/recordings"
[ "$mode" = cross-origin ] || out=$("$vcu" record "$data/recordings/drive1" --for 3 --config "$config" 2>&1) || fail "vcu record: $out"
if [ "$mode" != cross-origin ]; then  # the cross-origin test needs no recording
  [ -s "$data/recordings/drive1/vehicle.log" ] || fail "vcu record wrote no vehicle.log: $out"
  ln -s /etc "$data/recordings/escape"
  echo "$NAME: recording drive1: $(ls -l "$data/recordings/drive1" | tail -n +2 | awk '{print $9, $5}' | tr '\n' ' ')"
fi

port=18080
url=http://127.0.0.1:$port/
# web-start.sh / web-kill.sh start and SIGKILL vcu-web (the browser test's --start-command and
# --kill-command too).
# vcu-web ends with its parent (PR_SET_PDEATHSIG): a subshell that waits for it is its parent,
# so it outlives web-start.sh. WEB_USERS overrides the users file.
cat > "$run/web-start.sh" <<EOF
#!/bin/bash
rm -f "$run/web.pid"
(
  "$bin/vcu-web" --config "$config" --listen 127.0.0.1:$port --data-folder "$data" --users "\${WEB_USERS:-$users}" \\
    --www "$root/services/web/www" >> "$run/web.log" 2>&1 &
  echo \$! > "$run/web.pid"
  wait
) &
for _ in \$(seq 1 50); do [ -s "$run/web.pid" ] && break; sleep 0.02; done
for _ in \$(seq 1 100); do
  curl -s -o /dev/null --max-time 1 "${url}api/info" && exit 0
  kill -0 \$(cat "$run/web.pid") 2>/dev/null || { echo "vcu-web exited" >&2; exit 1; }
  sleep 0.1
done
echo "vcu-web does not answer on $url after 10 s" >&2
exit 1
EOF
cat > "$run/web-kill.sh" <<EOF
#!/bin/bash
kill -9 \$(cat "$run/web.pid") || exit 1
for _ in \$(seq 1 50); do
  curl -s -o /dev/null --max-time 1 "${url}api/info" || exit 0
  sleep 0.1
done
echo "vcu-web still answers after SIGKILL" >&2
exit 1
EOF
chmod +x "$run/web-start.sh" "$run/web-kill.sh"
"$run/web-start.sh" || fail "vcu-web did not start"
echo "$NAME: vcu-web listens on $url (pid $(cat "$run/web.pid"))"

if [ "$mode" = api ]; then
  "$python" "$here/web_api_test.py" --url "$url" --user "$user" --recording drive1 \
    --log "$root/tests/data/logs/candump_l.log"
  status=$?
  # the same vcu-web with a users file that does not exist: read-only
  "$run/web-kill.sh" || fail "vcu-web did not die"
  WEB_USERS=$run/no-such-users.json "$run/web-start.sh" || fail "the read-only vcu-web did not start"
  "$python" "$here/web_api_test.py" --url "$url" --read-only "$run/no-such-users.json" || fail "web_api_test.py --read-only"
  [ $status -eq 0 ] || fail "web_api_test.py"
elif [ "$mode" = cross-origin ]; then
  "$python" "$here/web_cross_origin_test.py" --url "$url" --user "$user" --attacker-port $((port + 1)) \
    --command-log "$data/web-commands.log" --web-log "$run/web.log" \
    --screenshots "${OPENVCU_WEB_SCREENSHOTS:-$bin/../tests/web-screenshots}"
  status=$?
  [ $status -eq 77 ] && exit 77
  [ $status -eq 0 ] || fail "web_cross_origin_test.py"
else
  shots=${OPENVCU_WEB_SCREENSHOTS:-$bin/../tests/web-screenshots}
  mkdir -p "$shots" || fail "cannot create $shots"
  rm -f "$shots"/*.png  # only this run's
  "$python" "$here/web_browser_test.py" --url "$url" --user "$user" --log "$root/tests/data/logs/candump_l.log" \
    --screenshots "$shots" --kill-command "$run/web-kill.sh" --start-command "$run/web-start.sh" \
    --fault-on-command "$vcu sim fault battery on --config $config" \
    --fault-off-command "$vcu sim fault battery off --config $config"
  status=$?
  [ $status -eq 77 ] && exit 77
  [ $status -eq 0 ] || fail "web_browser_test.py"
fi
# vcu-web must still be the one started last (no crash during the test)
kill -0 "$(cat "$run/web.pid")" 2>/dev/null || fail "vcu-web died during the test"
echo "$NAME: PASS"
