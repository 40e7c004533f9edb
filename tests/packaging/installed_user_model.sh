#!/bin/bash
# ctest package_user_model (inside tests/harness/run_isolated.sh, as root): the extracted
# package's stack under the installed user model, without installing anything. A copy of
# /etc/passwd and /etc/group with the system user openvcu and a member `alice` is bind-mounted
# in the sandbox's private mount namespace only. RouDi runs as the unit says (root, group
# openvcu, CAP_DAC_OVERRIDE alone), can-rx and fsm as user openvcu, can-tx as openvcu with the
# unit's ambient CAP_SYS_NICE. Checks: root and alice command the stack (vcu trusts the
# folder owned by openvcu), nobody is refused, alice's `vcu send` goes out, can-tx's transmit
# thread gets SCHED_FIFO. Skips (77) when not root (setpriv needs real uids).
#   installed_user_model.sh PACKAGES_DIR VERSION ARCH
set -uo pipefail
dir=${1:?packages folder} version=${2:?version} arch=${3:?architecture}
deb="$dir/openvcu_${version}_${arch}.deb"
[ -f "$deb" ] || { echo "user_model: $deb missing (package_build)"; exit 1; }
[ "$(id -u)" -eq 0 ] && [ -n "${OPENVCU_ISOLATED:-}" ] ||
  { echo "user_model: needs root inside tests/harness/run_isolated.sh: skipped"; exit 77; }
[ "$arch" = "$(dpkg --print-architecture)" ] || { echo "user_model: $arch binaries do not run here: skipped"; exit 77; }
failures=0
fail() { echo "user_model: FAIL: $*"; failures=$((failures + 1)); }
work=$(mktemp -d /tmp/user_model.XXXXXX)
x=$work/x
dpkg-deb -x "$deb" "$x"

# the users, in this mount namespace only
cp /etc/passwd "$work/passwd"; cp /etc/group "$work/group"
sed -i '/^openvcu:/d; /^alice:/d' "$work/passwd" "$work/group"
echo "openvcu:x:64100:64100:openvcu:/var/lib/openvcu:/usr/sbin/nologin" >>"$work/passwd"
echo "alice:x:64101:64101:alice:/tmp:/usr/sbin/nologin" >>"$work/passwd"
echo "openvcu:x:64100:alice" >>"$work/group"
echo "alice:x:64101:" >>"$work/group"
mount --bind "$work/passwd" /etc/passwd && mount --bind "$work/group" /etc/group || { echo "user_model: cannot bind-mount passwd/group"; exit 1; }

# the installed configuration on the simulated bus, state in the sandbox
cfg=$work/etc; cp -r "$x/etc/openvcu" "$cfg"
sed -i 's#"socketcan:can0"#"sim:vehicle"#' "$cfg/vehicle.json"
sed -i "s#/var/lib/openvcu#$work/state#" "$cfg/schedule.json" "$cfg/diagnostics.json" "$cfg/web.json"
install -d -o openvcu -g openvcu -m 0750 "$work/state"
install -d -o openvcu -g openvcu -m 0755 /run/openvcu
chmod 0755 "$work"
as_openvcu() { setpriv --reuid=openvcu --regid=openvcu --init-groups -- "$@"; }
as_alice() { setpriv --reuid=alice --regid=alice --init-groups -- "$@"; }
vcu=$x/usr/bin/vcu
config=(--config "$cfg/vehicle.json")

(umask 007; exec setpriv --regid=openvcu --clear-groups --bounding-set=-all,+dac_override -- \
  iox-roudi -c "$x/usr/share/openvcu/iceoryx/roudi.toml" >"$work/roudi.log" 2>&1) &
for _ in $(seq 50); do [ -S /tmp/roudi ] && break; sleep 0.1; done
as_openvcu "$x/usr/bin/vcu-can-rx" "${config[@]}" >"$work/can-rx.log" 2>&1 &
as_openvcu "$x/usr/bin/vcu-fsm" "${config[@]}" >"$work/fsm.log" 2>&1 &
setpriv --reuid=openvcu --regid=openvcu --init-groups --inh-caps=+sys_nice --ambient-caps=+sys_nice \
  --bounding-set=-all,+sys_nice --no-new-privs -- "$x/usr/bin/vcu-can-tx" "${config[@]}" >"$work/can-tx.log" 2>&1 &
for _ in $(seq 100); do
  [ -S /run/openvcu/hhea/vcu-fsm.sock ] && [ -S /run/openvcu/hhea/vcu-can-tx.sock ] && break
  sleep 0.1
done

out=$("$vcu" signal set internal.operator.StartStop Start "${config[@]}" 2>&1) || fail "root's vcu signal set: $out"
echo "user_model: root, vcu signal set: $out"
out=$(as_alice "$vcu" signal set internal.operator.StartStop Stop "${config[@]}" 2>&1) || fail "alice's vcu signal set: $out"
echo "user_model: alice (group openvcu), vcu signal set: $out"
if out=$(runuser -u nobody -- "$vcu" signal set internal.operator.StartStop Start "${config[@]}" 2>&1); then
  fail "nobody's vcu signal set succeeded: $out"
fi
echo "user_model: nobody, vcu signal set: $out"
out=$(timeout 10 setpriv --reuid=alice --regid=alice --init-groups -- "$vcu" send vehicle 18EF2100#0102030405060708 "${config[@]}" 2>&1) ||
  fail "alice's vcu send: $out"
echo "user_model: alice, vcu send: $out"
owner=$(stat -c %U /run/openvcu/hhea 2>/dev/null)
[ "$owner" = openvcu ] || fail "/run/openvcu/hhea belongs to '$owner', not openvcu"
fifo=$(ps -eLo user:10,comm,cls,rtprio | awk '$1 == "openvcu" && $2 == "vcu-can-tx" && $3 == "FF"' | head -1)
[ -n "$fifo" ] || fail "no SCHED_FIFO thread in vcu-can-tx: $(grep -h 'SCHED_FIFO' "$work/can-tx.log")"
echo "user_model: can-tx's transmit thread: ${fifo:-none}"

if [ $failures -gt 0 ]; then
  for log in "$work"/*.log; do echo "== $log"; tail -5 "$log"; done
  echo "user_model: $failures failure(s)"
  exit 1
fi
echo "user_model: PASS"
