#!/bin/bash
# ctest package_maintainer_scripts (inside tests/harness/run_isolated.sh, as root): the
# package openvcu's postinst, prerm and postrm run against throw-away copies, never the
# machine's: a copy of /etc bind-mounted on /etc, tmpfs on /var/lib and /run, the package's
# units on a tmpfs over /usr/lib/systemd/system, all in the sandbox's mount namespace.
# Checks: postinst creates the system user and group openvcu and /var/lib/openvcu
# (openvcu:openvcu 0750) and enables openvcu.target and its five services through
# deb-systemd-helper without starting anything; a second configure (upgrade) keeps the user;
# postrm remove masks nothing it should not and keeps state; postrm purge removes
# /var/lib/openvcu, /etc/openvcu and the enable links, and keeps the user.
# Skips (77) when not root inside the sandbox.
#   maintainer_scripts.sh PACKAGES_DIR VERSION ARCH
set -uo pipefail
dir=${1:?packages folder} version=${2:?version} arch=${3:?architecture}
deb="$dir/openvcu_${version}_${arch}.deb"
[ -f "$deb" ] || { echo "maintainer_scripts: $deb missing (package_build)"; exit 1; }
[ "$(id -u)" -eq 0 ] && [ -n "${OPENVCU_ISOLATED:-}" ] ||
  { echo "maintainer_scripts: needs root inside tests/harness/run_isolated.sh: skipped"; exit 77; }
command -v deb-systemd-helper >/dev/null || { echo "maintainer_scripts: no deb-systemd-helper: skipped"; exit 77; }
failures=0
fail() { echo "maintainer_scripts: FAIL: $*"; failures=$((failures + 1)); }
work=$(mktemp -d /tmp/maintainer.XXXXXX)
dpkg-deb -e "$deb" "$work/control"
dpkg-deb -x "$deb" "$work/data"

# the copies (this mount namespace only)
cp -a /etc "$work/etc"
# a machine where the group or user exists already is another case: start without them
sed -i '/^openvcu:/d' "$work/etc/passwd" "$work/etc/group" "$work/etc/shadow" "$work/etc/gshadow" 2>/dev/null
mount --bind "$work/etc" /etc || { echo "maintainer_scripts: cannot bind-mount /etc"; exit 1; }
mount -t tmpfs tmpfs /var/lib && mount -t tmpfs tmpfs /run && mount -t tmpfs tmpfs /usr/lib/systemd/system ||
  { echo "maintainer_scripts: cannot mount the tmpfs copies"; exit 1; }
cp "$work"/data/lib/systemd/system/* /usr/lib/systemd/system/
cp -r "$work/data/etc/openvcu" /etc/openvcu

run() {  # SCRIPT ARGS...
  local script=$1; shift
  # the environment dpkg gives maintainer scripts (deb-systemd-helper refuses to run without it)
  if ! out=$(DPKG_MAINTSCRIPT_PACKAGE=openvcu DPKG_MAINTSCRIPT_NAME=$script DPKG_MAINTSCRIPT_ARCH=$arch \
             "$work/control/$script" "$@" 2>&1); then
    fail "$script $*: exit non-zero: $out"
  fi
  [ -z "$out" ] || echo "maintainer_scripts: $script $* said: $out"
}
wants=/etc/systemd/system/openvcu.target.wants
services=(openvcu-roudi openvcu-can-rx openvcu-can-tx openvcu-fsm openvcu-gpio)

run postinst configure ""
getent passwd openvcu >/dev/null || fail "postinst made no user openvcu"
uid=$(id -u openvcu 2>/dev/null || echo 0)
[ "$uid" -gt 0 ] && [ "$uid" -lt 1000 ] || fail "user openvcu is not a system user (uid $uid)"
[ "$(id -gn openvcu 2>/dev/null)" = openvcu ] || fail "user openvcu's group is not openvcu"
[ "$(getent passwd openvcu | cut -d: -f7)" != /bin/bash ] || fail "user openvcu has a login shell"
[ "$(stat -c '%U:%G %a' /var/lib/openvcu 2>/dev/null)" = "openvcu:openvcu 750" ] ||
  fail "/var/lib/openvcu is '$(stat -c '%U:%G %a' /var/lib/openvcu 2>&1)', not openvcu:openvcu 750"
[ -L /etc/systemd/system/multi-user.target.wants/openvcu.target ] || fail "openvcu.target not enabled"
for service in "${services[@]}"; do
  [ -L "$wants/$service.service" ] || fail "$service not enabled (no link in $wants)"
done
for service in openvcu-web openvcu-ecu-sim; do
  [ ! -e "$wants/$service.service" ] || fail "$service enabled by default"
done
echo "maintainer_scripts: after install: user $(id openvcu), enabled: $(ls "$wants" | tr '\n' ' ')"

# an upgrade: the same user, what the admin disabled stays disabled
rm "$wants/openvcu-gpio.service"
deb-systemd-helper update-state openvcu-gpio.service >/dev/null 2>&1 || true
echo "x" >/var/lib/openvcu/dtc_counts.json
run postinst configure "$version"
[ "$(id -u openvcu)" = "$uid" ] || fail "the upgrade changed the user's uid"
[ ! -e "$wants/openvcu-gpio.service" ] || fail "the upgrade re-enabled openvcu-gpio the admin disabled"
[ -f /var/lib/openvcu/dtc_counts.json ] || fail "the upgrade lost /var/lib/openvcu's files"

run prerm remove
run postrm remove
[ -f /var/lib/openvcu/dtc_counts.json ] || fail "remove deleted the state"
[ -d /etc/openvcu ] || fail "remove deleted /etc/openvcu"
run postrm purge
[ ! -e /var/lib/openvcu ] || fail "purge left /var/lib/openvcu"
[ ! -e /etc/openvcu ] || fail "purge left /etc/openvcu"
[ -z "$(ls "$wants" 2>/dev/null)" ] || fail "purge left enable links: $(ls "$wants")"
[ ! -e /etc/systemd/system/multi-user.target.wants/openvcu.target ] || fail "purge left openvcu.target enabled"
getent passwd openvcu >/dev/null || fail "purge removed the user (it stays, as Debian does)"

if [ $failures -gt 0 ]; then echo "maintainer_scripts: $failures failure(s)"; exit 1; fi
echo "maintainer_scripts: PASS"
