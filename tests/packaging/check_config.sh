#!/bin/bash
# ctest package_config_check: the /etc/openvcu configuration of the package openvcu, extracted
# with dpkg-deb -x, passes the built `vcu check` (its paths are relative to vehicle.json, so
# the extracted copy checks as it would installed), and differs from the HHEA example it
# ships in /usr/share/openvcu/vehicles/hhea by exactly the changes of the agreed layout.
#   check_config.sh PACKAGES_DIR VERSION ARCH VCU_BINARY
set -euo pipefail
dir=${1:?packages folder} version=${2:?version} arch=${3:?architecture} vcu=${4:?the built vcu}
deb="$dir/openvcu_${version}_${arch}.deb"
[ -f "$deb" ] || { echo "check_config: $deb missing (package_build)"; exit 1; }
[ -x "$vcu" ] || { echo "check_config: $vcu: not an executable"; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
dpkg-deb -x "$deb" "$work"

echo "check_config: vcu check -c /etc/openvcu/vehicle.json (extracted)"
if ! OPENVCU_RUN_DIR="$work/run" "$vcu" check -c "$work/etc/openvcu/vehicle.json"; then
  echo "check_config: FAIL: vcu check refused the installed configuration"
  exit 1
fi

/usr/bin/python3 - "$work/etc/openvcu" "$work/usr/share/openvcu/vehicles/hhea" <<'PY'
import json, pathlib, sys
etc, example = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
state = "/var/lib/openvcu"
expected_changes = {
    "vehicle.json": lambda d: [b.update(link="socketcan:can0") for b in d["buses"] if b["name"] == "vehicle"],
    "schedule.json": lambda d: d.update(overlay=f"{state}/schedule.overlay.json"),
    "diagnostics.json": lambda d: d.update(countsFile=f"{state}/dtc_counts.json"),
    "web.json": lambda d: d.update(dataFolder=f"{state}/web", usersFile="/etc/openvcu/web-users.json"),
}
failures = 0
names = sorted(p.name for p in etc.iterdir() if p.name != "openvcu.env")
for name in names:
    installed = etc / name
    if not (example / name).is_file():
        print(f"check_config: FAIL: /etc/openvcu/{name} is not in the HHEA example")
        failures += 1
        continue
    if name.endswith(".json"):
        want = json.loads((example / name).read_text())
        if name in expected_changes:
            expected_changes[name](want)
        if json.loads(installed.read_text()) != want:
            print(f"check_config: FAIL: /etc/openvcu/{name} is not the example with the layout's changes")
            failures += 1
    elif installed.read_bytes() != (example / name).read_bytes():
        print(f"check_config: FAIL: /etc/openvcu/{name} differs from the example")
        failures += 1
missing = set(expected_changes) - set(names)
if missing:
    print(f"check_config: FAIL: /etc/openvcu lacks {sorted(missing)}")
    failures += 1
env = (etc / "openvcu.env").read_text()
if "OPENVCU_CONFIG=/etc/openvcu/vehicle.json" not in env.splitlines():
    print("check_config: FAIL: openvcu.env does not set OPENVCU_CONFIG=/etc/openvcu/vehicle.json")
    failures += 1
sys.exit(1 if failures else 0)
PY
echo "check_config: PASS"
