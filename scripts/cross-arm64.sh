#!/usr/bin/env bash
# Cross-builds openvcu for arm64 on this amd64 Debian 12 machine, runs the arm64 unit tests
# and the vcu CLI tests under qemu-user, and makes the arm64 Debian packages
# (docs/cross-arm64.md). Not part of ./test.sh: a full arm64 build takes too long for CI.
#
#   scripts/cross-arm64.sh [--build-dir DIR] [--jobs N] [--no-tests] [--no-package] [--out DIR]
#
#   --build-dir  the arm64 build tree (default: build-arm64)
#   --jobs N     parallel build and test jobs (default: the number of cores)
#   --no-tests   build only, run no tests
#   --no-package do not call scripts/package.sh
#   --out DIR    where scripts/package.sh writes the .deb files (default: dist)
#
# What it changes on the machine (as root, or through sudo): `dpkg --add-architecture arm64`,
# apt-get update, and the packages of ARM64_PACKAGES below. Before installing it simulates
# the installation (apt-get -s) and stops if apt would remove any package. It mounts
# binfmt_misc and enables qemu-user-static's qemu-aarch64 entry when they are not, so that
# arm64 programs the tests start themselves (vcu, the services) run too.
# Debian's liblcm1/liblcm-dev are not Multi-Arch: same, so their arm64 versions would
# replace the amd64 ones: they are downloaded (apt-get download) and unpacked into
# <build>/arm64-extra-root instead, outside dpkg (the toolchain file's OPENVCU_ARM64_EXTRA_ROOT).
# Exit 0: everything passed; 1: a step failed; 2: bad arguments.
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build="$root/build-arm64"
out="$root/dist"
jobs=$(nproc)
run_tests=1
run_package=1

usage() { sed -n '2,/^set -euo/p' "${BASH_SOURCE[0]}" | sed -e '$d' -e 's/^# \{0,1\}//'; }
die() { echo "cross-arm64: $*" >&2; exit 1; }

while [ $# -gt 0 ]; do
  case "$1" in
    --build-dir) build=${2:?--build-dir needs a folder}; shift 2 ;;
    --jobs) jobs=${2:?--jobs needs a number}; shift 2 ;;
    --no-tests) run_tests=0; shift ;;
    --no-package) run_package=0; shift ;;
    --out) out=${2:?--out needs a folder}; shift 2 ;;
    -h|--help) usage; exit 0 ;;
    *) echo "cross-arm64: unknown argument '$1'" >&2; usage >&2; exit 2 ;;
  esac
done
case "$jobs" in ''|*[!0-9]*|0) echo "cross-arm64: --jobs '$jobs': expected a positive number" >&2; exit 2 ;; esac
mkdir -p "$build"
build=$(cd "$build" && pwd)

# The arm64 libraries the build links (scripts/install-deps.sh's library list, arm64 side).
# Header-only, Architecture: all packages (doctest-dev, nlohmann-json3-dev, libcli11-dev)
# and the host tools (cmake, ninja, lcm-gen, Qt's moc/rcc/qmlcachegen) are the amd64 ones
# scripts/install-deps.sh installs. Google Benchmark is not needed (bench is off).
ARM64_PACKAGES=(
  crossbuild-essential-arm64 qemu-user-static binfmt-support
  libc6-dev:arm64 libiceoryx-posh-dev:arm64 libiceoryx-hoofs-dev:arm64 libglib2.0-dev:arm64
  libgpiod-dev:arm64 libboost-dev:arm64 libcrypt-dev:arm64 libarchive-dev:arm64
  libmosquitto-dev:arm64 libssl-dev:arm64   # vcu-telemetry: libmosquitto, OpenSSL's SHA-256
  # the HMI (vcu-hmi) and, to run its tests under qemu, the QML modules and the offscreen plugin
  qt6-base-dev:arm64 qt6-declarative-dev:arm64 libgl-dev:arm64
  qml6-module-qtquick:arm64 qml6-module-qtqml:arm64 qml6-module-qtquick-controls:arm64
  qml6-module-qtquick-layouts:arm64 qml6-module-qtquick-window:arm64
  qml6-module-qtquick-templates:arm64 qml6-module-qtqml-workerscript:arm64
  qml6-module-qtqml-models:arm64 qml6-module-qttest:arm64 qml6-module-qtquick-shapes:arm64
  qt6-qpa-plugins:arm64
)
# Unpacked into <build>/arm64-extra-root (not Multi-Arch: same, see above).
EXTRA_ROOT_PACKAGES=(liblcm1:arm64 liblcm-dev:arm64)

# Tests not run under qemu-user, with the reason (ctest -E regex).
# processCpuTicks reads utime+stime from /proc/<own pid>/stat: qemu-user (7.2) answers that
# file itself and writes 0 in those fields, so the check that they grow cannot pass there.
# vcu-hmi's RecordController starts vcu through QProcess, whose forkfd calls
# clone(CLONE_VM|CLONE_VFORK|CLONE_PIDFD): qemu-user 7.2 refuses that with EINVAL (seen with
# qemu-aarch64-static -strace), so the program never starts there.
EXCLUDE_REGEX="^(processCpuTicks grows while this process computes|a recording that vcu record refuses ends in Error)"
EXCLUDE_REASON="qemu-user 7.2: /proc/self/stat has zero CPU times; clone with CLONE_PIDFD (QProcess) fails with EINVAL"

STEPS=7
started=$(date +%s)
declare -a summary=()
step() { echo; echo "=== cross-arm64: step $1 of $STEPS: $2 ($(( $(date +%s) - started )) s)"; }
note() { summary+=("$*"); }

SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null 2>&1 || die "not root and no sudo: cannot install the arm64 packages"
  SUDO="sudo"
fi
[ "$(dpkg --print-architecture)" = amd64 ] || die "this script cross-builds on amd64; this machine is $(dpkg --print-architecture)"
APT=($SUDO apt-get -o DPkg::Lock::Timeout=600)
export DEBIAN_FRONTEND=noninteractive

# --- 1. the arm64 architecture -------------------------------------------------------------
step 1 "dpkg architecture arm64"
if dpkg --print-foreign-architectures | grep -qx arm64; then
  echo "arm64 is already a foreign architecture"
else
  $SUDO dpkg --add-architecture arm64
  "${APT[@]}" update -q
  note "added the dpkg architecture arm64 and ran apt-get update"
fi

# --- 2. packages -------------------------------------------------------------------------------
step 2 "cross toolchain, qemu-user and the :arm64 libraries"
missing=()
for pkg in "${ARM64_PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed" || missing+=("$pkg")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "all ${#ARM64_PACKAGES[@]} packages present"
else
  echo "missing: ${missing[*]}"
  # the package lists may predate the arm64 architecture
  apt-cache policy "${missing[0]}" 2>/dev/null | grep -q "Candidate: [0-9]" || "${APT[@]}" update -q
  sim=$(mktemp)
  if ! "${APT[@]}" -s install --no-install-recommends "${missing[@]}" >"$sim" 2>&1; then
    cat "$sim" >&2; rm -f "$sim"
    die "apt-get cannot install the arm64 packages (simulation above); nothing was changed"
  fi
  if grep -q '^Remv ' "$sim"; then
    echo "apt-get would REMOVE these packages:" >&2
    grep '^Remv ' "$sim" >&2
    rm -f "$sim"
    die "refusing an installation that removes packages (multiarch conflict); nothing was changed"
  fi
  grep -E '^[0-9]+ upgraded' "$sim" || true
  if grep -q '^Inst .* \[' "$sim"; then
    echo "amd64 packages upgraded to the arm64 versions' level (Multi-Arch: same needs equal versions):"
    grep '^Inst ' "$sim" | grep -v ':arm64 ' | grep ' \[' | awk '{print "  " $2, $3, $4}'
  fi
  rm -f "$sim"
  "${APT[@]}" install -y -q --no-install-recommends "${missing[@]}"
  note "installed ${missing[*]}"
fi

# qemu-user-static registers qemu-aarch64 with binfmt_misc: the tests start arm64 programs.
if [ ! -e /proc/sys/fs/binfmt_misc/register ]; then
  $SUDO mount -t binfmt_misc binfmt_misc /proc/sys/fs/binfmt_misc ||
    die "cannot mount binfmt_misc: arm64 programs started by the tests could not run"
  note "mounted binfmt_misc"
fi
if [ "$(head -n1 /proc/sys/fs/binfmt_misc/qemu-aarch64 2>/dev/null)" != enabled ]; then
  $SUDO update-binfmts --enable qemu-aarch64 || die "update-binfmts --enable qemu-aarch64 failed"
  note "enabled binfmt qemu-aarch64"
fi

# liblcm for arm64, outside dpkg
extra="$build/arm64-extra-root"
if [ ! -e "$extra/usr/lib/aarch64-linux-gnu/liblcm.so.1" ]; then
  dl=$(mktemp -d)
  (cd "$dl" && "${APT[@]}" download "${EXTRA_ROOT_PACKAGES[@]}") ||
    { rm -rf "$dl"; die "apt-get download ${EXTRA_ROOT_PACKAGES[*]} failed"; }
  rm -rf "$extra"; mkdir -p "$extra"
  for deb in "$dl"/*.deb; do dpkg-deb -x "$deb" "$extra"; done
  rm -rf "$dl"
  # lcm.pc names prefix=/usr: point it at the extra root
  sed -i "s|^prefix=.*|prefix=$extra/usr|" "$extra/usr/lib/aarch64-linux-gnu/pkgconfig/lcm.pc"
  note "unpacked ${EXTRA_ROOT_PACKAGES[*]} into $extra"
fi
echo "liblcm (arm64): $extra"
qemu-aarch64-static --version | head -n1

# --- 3. configure --------------------------------------------------------------------------------
step 3 "configure $build (Release, cmake/toolchains/aarch64-linux-gnu.cmake)"
tests_on=ON
[ $run_tests -eq 1 ] || tests_on=OFF   # --no-tests: the test programs are not built either
cmake -S "$root" -B "$build" -G Ninja \
  -DCMAKE_TOOLCHAIN_FILE="$root/cmake/toolchains/aarch64-linux-gnu.cmake" \
  -DOPENVCU_ARM64_EXTRA_ROOT="$extra" \
  -DCMAKE_BUILD_TYPE=Release \
  -DOPENVCU_BUILD_TESTS=$tests_on -DOPENVCU_BUILD_BENCH=OFF -DOPENVCU_FUZZ=OFF >"$build/configure.log" 2>&1 ||
  { tail -n 40 "$build/configure.log" >&2; die "cmake configure failed ($build/configure.log)"; }
grep -E "skipped|vcu-hmi" "$build/configure.log" || true
hmi="no"; grep -q '^Qt6_DIR:PATH=/' "$build/CMakeCache.txt" && hmi="yes"

# --- 4. build ------------------------------------------------------------------------------------
step 4 "build (ninja -j$jobs; shared lock /tmp/openvcu-cpu.lock)"
t0=$(date +%s)
# the installed programs first (what the packages need), then the tests
runtime=(vcu vcu-can-rx vcu-can-tx vcu-fsm vcu-gpio vcu-ecu-sim vcu-web vcu-telemetry)
[ "$hmi" = yes ] && runtime+=(vcu-hmi)
flock -s /tmp/openvcu-cpu.lock cmake --build "$build" -j "$jobs" --target "${runtime[@]}" ||
  die "build of ${runtime[*]} failed"
note "programs (${runtime[*]}) built in $(( $(date +%s) - t0 )) s"
if [ $run_tests -eq 1 ]; then
  # the vcu CLI tests next, then everything else (the other unit tests, fuzz corpus replays...)
  flock -s /tmp/openvcu-cpu.lock cmake --build "$build" -j "$jobs" --target test_vcu ||
    die "build of test_vcu failed"
  flock -s /tmp/openvcu-cpu.lock cmake --build "$build" -j "$jobs" || die "build failed"
fi
build_s=$(( $(date +%s) - t0 ))
note "build: ${build_s} s"
file "$build/bin/vcu" | grep -q "ARM aarch64" || die "$build/bin/vcu is not an aarch64 program"

# --- 5./6. tests under qemu-user -------------------------------------------------------------------
# One list of the unit tests split in two by their executable: the vcu CLI's (test_vcu,
# tests/tools/vcu) and the rest; ctest -I runs each part by number.
ctest_part() { # <title> <vcu|other> : runs the part, records its counts
  local title=$1 which=$2 nums log
  nums=$(ctest --test-dir "$build" -N -L unit ${EXCLUDE_REGEX:+-E "$EXCLUDE_REGEX"} --show-only=json-v1 |
    /usr/bin/python3 -c '
import json, sys
which = sys.argv[1]
tests = json.load(sys.stdin)["tests"]
# ctest -I numbers are positions in the unfiltered list
every = [t["name"] for t in json.load(open(sys.argv[2]))["tests"]]
pick = [str(every.index(t["name"]) + 1) for t in tests
        if ("/test_vcu" in " ".join(t.get("command", []))) == (which == "vcu")]
print(",".join(pick))' "$which" <(ctest --test-dir "$build" -N --show-only=json-v1))
  if [ -z "$nums" ]; then note "$title: no tests found"; return 1; fi
  log="$build/ctest-$which.log"
  local rc=0
  flock -s /tmp/openvcu-cpu.lock ctest --test-dir "$build" -I "0,0,0,$nums" -j "$jobs" \
    --timeout 600 --output-on-failure --output-junit "ctest-$which.xml" 2>&1 | tee "$log" || rc=$?
  local counts
  counts=$(/usr/bin/python3 - "$build/ctest-$which.xml" <<'EOF'
import sys, xml.etree.ElementTree as ET
r = ET.parse(sys.argv[1]).getroot()
n = int(r.get("tests", 0)); f = int(r.get("failures", 0)); s = int(r.get("skipped", 0))
print(f"{n - f - s} passed, {f} failed, {s} skipped of {n}")
EOF
)
  note "$title under qemu-user: $counts"
  return $rc
}

failed=0
if [ $run_tests -eq 1 ]; then
  step 5 "vcu CLI tests under qemu-user (tests/tools/vcu: test_vcu)"
  ctest_part "vcu CLI tests" vcu || failed=1
  step 6 "the other arm64 unit tests under qemu-user (ctest -L unit, without tests/tools/vcu)"
  ctest_part "other unit tests" other || failed=1
  [ -z "$EXCLUDE_REGEX" ] || note "excluded: $EXCLUDE_REGEX ($EXCLUDE_REASON)"
else
  step 5 "tests skipped (--no-tests)"; step 6 "tests skipped (--no-tests)"
  note "tests not run (--no-tests)"
fi

# --- 7. packages ---------------------------------------------------------------------------------
step 7 "Debian packages (scripts/package.sh --arch arm64)"
if [ $run_package -eq 0 ]; then
  note "packages not made (--no-package)"
elif [ ! -x "$root/scripts/package.sh" ]; then
  note "packages not made: scripts/package.sh is missing"; failed=1
elif [ $failed -ne 0 ]; then
  note "packages not made: tests failed"
else
  if "$root/scripts/package.sh" --arch arm64 --build-dir "$build" --out "$out"; then
    for deb in "$out"/*_arm64.deb; do [ -e "$deb" ] && note "package: $deb"; done
  else
    note "scripts/package.sh failed"; failed=1
  fi
fi

echo
echo "=== cross-arm64: summary ($(( $(date +%s) - started )) s in all; HMI built: $hmi)"
for line in "${summary[@]}"; do echo "  $line"; done
[ $failed -eq 0 ] || { echo "cross-arm64: FAILED" >&2; exit 1; }
echo "cross-arm64: OK"
