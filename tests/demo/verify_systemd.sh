#!/bin/bash
# config/systemd checked with `systemd-analyze verify` (skipped, exit 77, where the tool is
# missing). The units name the installed package's paths (/usr/bin/vcu*, /etc/openvcu;
# docs/design/packaging.md); the copy checked here points them at this build so that verify
# can find every executable (iox-roudi stays /usr/bin/iox-roudi, Debian's iceoryx).
set -euo pipefail
command -v systemd-analyze >/dev/null || { echo "verify_systemd: systemd-analyze not installed: skipped"; exit 77; }
root=$(cd "$(dirname "$0")/../.." && pwd)
bin=${OPENVCU_BIN:?set OPENVCU_BIN to the bin folder of the build}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cp "$root"/config/systemd/*.service "$root"/config/systemd/*.target "$work"/
cp "$root/config/systemd/openvcu.env" "$work/openvcu.env"
sed -i -e "s#/usr/bin/vcu#$bin/vcu#g" -e "s#/etc/openvcu/openvcu.env#$work/openvcu.env#g" "$work"/*.service
cd "$work"
output=$(systemd-analyze verify --man=no ./*.service ./*.target 2>&1) || { echo "$output"; echo "verify_systemd: FAIL"; exit 1; }
# verify also reports problems as warnings without failing: none allowed for our units
if echo "$output" | grep -i "openvcu"; then echo "verify_systemd: FAIL (warnings above)"; exit 1; fi
echo "$output"
echo "verify_systemd: PASS ($(ls ./*.service ./*.target | wc -l) units)"
