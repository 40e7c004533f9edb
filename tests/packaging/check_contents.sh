#!/bin/bash
# ctest package_contents: the packages package_build wrote hold what docs/design/packaging.md
# (the agreed layout) lists, with the control fields it names.
#   check_contents.sh PACKAGES_DIR VERSION ARCH
# Checks: every file of the layout; the examples byte for byte as in config/; conffiles =
# the files under /etc/openvcu; control scripts 0755; files root-owned; ELF files stripped;
# every ExecStart of a unit names a file of the packages (or Debian's iox-roudi) and every
# service but RouDi runs as user openvcu (RouDi: root, group openvcu, CAP_DAC_OVERRIDE only); Depends has no -dev package, names the iceoryx and LCM
# libraries, iceoryx and adduser; openvcu-hmi depends on openvcu (= VERSION); no file in both.
set -euo pipefail
dir=${1:?packages folder} version=${2:?version} arch=${3:?architecture}
root=$(cd "$(dirname "$0")/../.." && pwd)
main="$dir/openvcu_${version}_${arch}.deb"
hmi="$dir/openvcu-hmi_${version}_${arch}.deb"
[ -f "$main" ] || { echo "check_contents: $main missing (package_build)"; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
failures=0
fail() { echo "check_contents: FAIL: $*"; failures=$((failures + 1)); }

# list DEB: the package's paths, one a line, without the leading "."
list() { dpkg-deb -c "$1" | awk '{print $6}' | sed -e 's#^\./#/#' -e 's#/$##' | grep -v '^/\?$' | sort; }
field() { dpkg-deb -f "$1" "$2"; }
files_only() { dpkg-deb -c "$1" | awk '$1 !~ /^d/ {print $6}' | sort; }

check_package() {  # DEB NAME FILE...
  local deb=$1 name=$2; shift 2
  list "$deb" >"$work/$name.files"
  for file in "$@"; do
    grep -qx -- "$file" "$work/$name.files" || fail "$name: $file missing"
  done
  [ "$(field "$deb" Package)" = "$name" ] || fail "$name: Package is '$(field "$deb" Package)'"
  [ "$(field "$deb" Version)" = "$version" ] || fail "$name: Version is '$(field "$deb" Version)', not $version"
  [ "$(field "$deb" Architecture)" = "$arch" ] || fail "$name: Architecture is '$(field "$deb" Architecture)'"
  [ -n "$(field "$deb" Maintainer)" ] || fail "$name: no Maintainer"
  [ -n "$(field "$deb" Section)" ] || fail "$name: no Section"
  [ "$(field "$deb" Description | wc -l)" -ge 2 ] || fail "$name: no long Description"
  local depends
  depends=$(field "$deb" Depends)
  echo "check_contents: $name Depends: $depends"
  # no development package (-dev) among the dependencies
  if tr ',|' '\n\n' <<<"$depends" | sed 's/(.*//; s/ //g' | grep -E -- '-dev(:[a-z0-9]+)?$'; then
    fail "$name: Depends names a -dev package"
  fi
  # every file root-owned; control scripts executable
  if dpkg-deb -c "$deb" | awk '$2 != "root/root"' | grep -q .; then
    fail "$name: files not owned by root/root: $(dpkg-deb -c "$deb" | awk '$2 != "root/root" {print $6}' | head -3)"
  fi
  mkdir -p "$work/$name/control" "$work/$name/data"
  dpkg-deb -e "$deb" "$work/$name/control"
  dpkg-deb -x "$deb" "$work/$name/data"
  for script in postinst prerm postrm; do
    [ -x "$work/$name/control/$script" ] || fail "$name: maintainer script $script missing or not executable"
  done
  # ELF files stripped: no symbol table left
  while IFS= read -r -d '' file; do
    if head -c 4 "$file" | grep -q 'ELF' && readelf -S "$file" 2>/dev/null | grep -q '\.symtab'; then
      fail "$name: ${file#"$work/$name/data"} is not stripped"
    fi
  done < <(find "$work/$name/data" -type f -print0)
}

has_dependency() {  # NAME DEPENDS REGEX
  tr ',' '\n' <<<"$2" | sed 's/^ *//' | grep -Eq -- "$3" || fail "$1: Depends has nothing matching '$3'"
}

# --- openvcu ---
etc=(openvcu.env vehicle.json hhea.dbc fsm.json schedule.json diagnostics.json gpio.json dashboard.json
     simulation.json web.json telemetry.json safety.json receive.json)
units=(openvcu.target openvcu-roudi.service openvcu-can-rx.service openvcu-can-tx.service openvcu-fsm.service
       openvcu-gpio.service openvcu-web.service openvcu-ecu-sim.service
       openvcu-telemetry.service openvcu-watchdog.service)
expected=(/usr/bin/vcu /usr/bin/vcu-can-rx /usr/bin/vcu-can-tx /usr/bin/vcu-fsm /usr/bin/vcu-gpio
          /usr/bin/vcu-ecu-sim /usr/bin/vcu-web /usr/bin/vcu-telemetry /usr/share/openvcu/www/index.html
          /usr/share/openvcu/iceoryx/iox-roudi.sh /usr/share/openvcu/iceoryx/roudi.toml
          /usr/share/openvcu/supervisor/openvcu.conf /lib/udev/rules.d/60-openvcu.rules
          /usr/share/doc/openvcu/copyright /usr/share/doc/openvcu/changelog.Debian.gz
          /usr/share/doc/openvcu/examples/telemetry/acl /usr/share/doc/openvcu/examples/telemetry/mosquitto.conf
          /usr/share/doc/openvcu/examples/telemetry/README.md)
for file in "${etc[@]}"; do expected+=("/etc/openvcu/$file"); done
for unit in "${units[@]}"; do expected+=("/lib/systemd/system/$unit"); done
for example in hhea tractor; do
  for file in "$root/config/$example"/*; do expected+=("/usr/share/openvcu/vehicles/$example/$(basename "$file")"); done
done
check_package "$main" openvcu "${expected[@]}"
data="$work/openvcu/data"

# the examples exactly as in the repository, iox-roudi.sh executable
for example in hhea tractor; do
  diff -r "$root/config/$example" "$data/usr/share/openvcu/vehicles/$example" >/dev/null ||
    fail "openvcu: /usr/share/openvcu/vehicles/$example differs from config/$example"
done
[ -x "$data/usr/share/openvcu/iceoryx/iox-roudi.sh" ] || fail "openvcu: iox-roudi.sh not executable"
# /etc/openvcu holds nothing else than the layout's files, and conffiles lists exactly them
(cd "$data" && find etc -type f | sed 's#^#/#' | sort) >"$work/etc.files"
printf '/etc/openvcu/%s\n' "${etc[@]}" | sort >"$work/etc.expected"
diff "$work/etc.expected" "$work/etc.files" >/dev/null ||
  fail "openvcu: /etc holds $(tr '\n' ' ' <"$work/etc.files"), expected $(tr '\n' ' ' <"$work/etc.expected")"
if [ -f "$work/openvcu/control/conffiles" ]; then
  sort "$work/openvcu/control/conffiles" | diff "$work/etc.files" - >/dev/null ||
    fail "openvcu: conffiles ($(tr '\n' ' ' <"$work/openvcu/control/conffiles")) is not the list of /etc files"
else
  fail "openvcu: no conffiles"
fi

depends=$(field "$main" Depends)
has_dependency openvcu "$depends" '^libiceoryx'
has_dependency openvcu "$depends" '^liblcm'
has_dependency openvcu "$depends" '^libc6'
has_dependency openvcu "$depends" '^iceoryx( |$)'
has_dependency openvcu "$depends" '^adduser( |$)'
field "$main" Recommends | grep -qw can-utils || fail "openvcu: Recommends lacks can-utils"
field "$main" Suggests | grep -qw supervisor || fail "openvcu: Suggests lacks supervisor"

# the units: ExecStart names a packaged binary (or iox-roudi), services run as openvcu,
# can-tx alone holds a capability
for unit in "$data"/lib/systemd/system/*.service; do
  name=$(basename "$unit")
  exec=$(sed -n 's/^ExecStart=\([^ ]*\).*/\1/p' "$unit")
  if [ "$exec" != /usr/bin/iox-roudi ] && [ ! -x "$data$exec" ]; then
    fail "openvcu: $name: ExecStart=$exec is not in the package"
  fi
  if [ "$name" = openvcu-roudi.service ]; then
    # RouDi: root with group openvcu and CAP_DAC_OVERRIDE alone (docs/design/packaging.md)
    grep -qx 'Group=openvcu' "$unit" || fail "openvcu: $name does not run with Group=openvcu"
    grep -qx 'CapabilityBoundingSet=CAP_DAC_OVERRIDE' "$unit" || fail "openvcu: $name is not limited to CAP_DAC_OVERRIDE"
  else
    grep -qx 'User=openvcu' "$unit" || fail "openvcu: $name does not run as User=openvcu"
  fi
  grep -q '/etc/openvcu' <(grep '^ReadWritePaths' "$unit") && fail "openvcu: $name may write /etc/openvcu"
  if [ "$name" = openvcu-can-tx.service ]; then
    grep -qx 'AmbientCapabilities=CAP_SYS_NICE' "$unit" || fail "openvcu: can-tx lacks CAP_SYS_NICE"
  elif grep -q '^AmbientCapabilities' "$unit"; then
    fail "openvcu: $name holds a capability"
  fi
done
grep -q 'openvcu-web.service\|openvcu-ecu-sim.service' "$data/lib/systemd/system/openvcu.target" &&
  fail "openvcu: openvcu.target pulls in web or ecu-sim (not enabled by default)"

# --- openvcu-hmi (when the tree built vcu-hmi) ---
if [ -f "$hmi" ]; then
  check_package "$hmi" openvcu-hmi /usr/bin/vcu-hmi /lib/systemd/system/openvcu-hmi.service \
    /usr/share/doc/openvcu-hmi/copyright /usr/share/doc/openvcu-hmi/changelog.Debian.gz
  hdepends=$(field "$hmi" Depends)
  has_dependency openvcu-hmi "$hdepends" "^openvcu \(= ${version//./\\.}\)$"
  has_dependency openvcu-hmi "$hdepends" '^libqt6quick6'
  has_dependency openvcu-hmi "$hdepends" '^qml6-module-qtquick-controls'
  has_dependency openvcu-hmi "$hdepends" '^libqt6opengl6'   # eglfs, the unit's platform
  # a file (not a folder) in both packages would make dpkg refuse the second
  both=$(comm -12 <(files_only "$main") <(files_only "$hmi"))
  [ -z "$both" ] || fail "in both packages: $both"
else
  echo "check_contents: no $hmi (the tree did not build vcu-hmi): openvcu-hmi not checked"
fi

if [ $failures -gt 0 ]; then
  echo "check_contents: $failures failure(s)"
  exit 1
fi
echo "check_contents: PASS ($(wc -l <"$work/openvcu.files") paths in openvcu$([ -f "$hmi" ] && echo ", $(wc -l <"$work/openvcu-hmi.files") in openvcu-hmi"))"
