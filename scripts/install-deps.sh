#!/usr/bin/env bash
# Installs the Debian 12 packages openvcu needs, and nothing else.
# Idempotent: packages already present are not touched and apt is not called at all
# when nothing is missing. Runs as root, or through sudo when it is available.
#
#   scripts/install-deps.sh            # build + test dependencies
#   scripts/install-deps.sh --quiet    # no output when nothing is missing
# When packages are missing it prints one line per phase (package lists, download,
# installation); apt's own output goes to build/install-deps.log (OPENVCU_DEPS_LOG), whose
# last 25 lines are printed on stderr when a phase fails (exit status: apt's).
set -euo pipefail

quiet=0
[ "${1:-}" = "--quiet" ] && quiet=1

PACKAGES=(
  # toolchain
  build-essential cmake ninja-build pkg-config git
  clang libclang-rt-14-dev            # libFuzzer and the sanitizer runtime
  # libraries
  doctest-dev nlohmann-json3-dev libcli11-dev libbenchmark-dev
  iceoryx libiceoryx-posh-dev libiceoryx-hoofs-dev
  liblcm-dev liblcm-bin liblcm-java libglib2.0-dev
  libgpiod-dev gpiod                  # vcu-gpio's libgpiod v1 back end; the gpiod tools
  # lcm-spy with the project's generated Java types (and its headless test)
  default-jdk-headless libjchart2d-java xvfb xauth
  # test peers: the canmatrix/python-can decoding oracle, namespaces for isolated tests
  python3 python3-canmatrix python3-can util-linux iproute2
  # kernel tests (tests/kernel): QEMU boots a Debian kernel with SocketCAN and gpio-sim;
  # busybox/cpio/kmod build its initramfs, make/gcc-12/bc/xz-utils the gpio-sim module,
  # can-utils are the peers inside the VM
  qemu-system-x86 busybox-static cpio kmod make gcc-12 bc xz-utils can-utils
  # ./run.sh runs the stack under supervisord
  supervisor
  # cyclictest: the platform's wake-up latency beside vcu-can-tx (bench/can-tx, issue 27)
  rt-tests
  # stress-ng: CPU load beside the safety campaign (bench/stack/safety_campaign.sh --stress)
  stress-ng
  # setfacl/getfacl: iox-roudi's shared memory without ACL (config/iceoryx/iox-roudi.sh) and its test
  acl
  # the Qt 6 HMI (services/hmi) and its offscreen / Xvfb tests and screenshots
  qt6-base-dev qt6-declarative-dev qt6-charts-dev qml6-module-qtquick qml6-module-qtqml
  qml6-module-qtquick-controls qml6-module-qtquick-layouts qml6-module-qtquick-window
  qml6-module-qtquick-templates qml6-module-qtqml-workerscript qml6-module-qtqml-models
  qml6-module-qtcharts qml6-module-qttest qml6-module-qtquick-shapes qt6-qpa-plugins
  libgl-dev fonts-dejavu-core x11-apps imagemagick
  # vcu trace report: opened in Debian's headless Chromium by its test, pixels read with PIL
  chromium python3-pil
  # the Debian packages (scripts/package.sh, tests/packaging): lintian checks them
  lintian
  # vcu-web (services/web): Boost.Beast/Asio, libxcrypt's crypt(3), libarchive for the archives;
  # its browser test drives Debian's chromium through chromium-driver and python3-selenium
  libboost-dev libcrypt-dev libarchive-dev chromium-driver python3-selenium
  mosquitto mosquitto-clients libmosquitto-dev libssl-dev  # vcu-telemetry (issue 25): libmosquitto, OpenSSL (SHA-256 of the configuration); the broker and its clients for tests and demo
)

missing=()
for pkg in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$pkg")
  fi
done

# The command group (docs/design/security.md): root and its members may command the stack.
ensure_group() {
  local sudo=""
  if [ "$(id -u)" -ne 0 ]; then
    if command -v sudo >/dev/null 2>&1; then sudo="sudo"; else
      getent group openvcu >/dev/null 2>&1 ||
        echo "install-deps: no group openvcu and not root: only root and the stack's user may command it" >&2
      return 0
    fi
  fi
  if ! getent group openvcu >/dev/null 2>&1; then
    $sudo groupadd --system openvcu && echo "install-deps: created the system group openvcu (who may command the stack)"
  fi
  # The services run as root: as a member, RouDi's shared memory is root:openvcu with no
  # other ACL (config/iceoryx/iox-roudi.sh, case A).
  if ! id -nG root | tr ' ' '\n' | grep -qx openvcu; then
    $sudo usermod -a -G openvcu root && echo "install-deps: root joined group openvcu"
  fi
}

if [ ${#missing[@]} -eq 0 ]; then
  [ $quiet -eq 1 ] || echo "install-deps: all ${#PACKAGES[@]} packages present"
  ensure_group
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null 2>&1; then SUDO="sudo"; else
    echo "install-deps: missing ${missing[*]} and not root (no sudo available)" >&2
    exit 1
  fi
fi

# apt's own output (hundreds of "Get:" and "Setting up ..." lines on a first run) goes to a
# log; the terminal gets one line per phase, and the log's tail when a phase fails.
root=$(cd "$(dirname "$0")/.." && pwd)
log=${OPENVCU_DEPS_LOG:-$root/build/install-deps.log}
mkdir -p "$(dirname "$log")"
echo "install-deps: ${#missing[@]} of ${#PACKAGES[@]} packages missing: ${missing[*]}" > "$log"
names=""
[ ${#missing[@]} -le 10 ] && names=": ${missing[*]}"
echo "install-deps: ${#missing[@]} of ${#PACKAGES[@]} packages missing$names (apt's output: $log)"
export DEBIAN_FRONTEND=noninteractive
start=$(date +%s)
# phase N TEXT COMMAND...: one line, the command's output into the log, or its tail on failure
phase() {
  local number=$1 text=$2
  shift 2
  echo "install-deps: [$number/3] $text"
  echo "== [$number/3] $text: $*" >> "$log"
  local status=0
  "$@" >> "$log" 2>&1 < /dev/null || status=$?
  if [ $status -ne 0 ]; then
    {
      echo "install-deps: $text failed (exit $status); the last 25 lines of $log:"
      tail -n 25 "$log"
    } >&2
    exit $status
  fi
}
apt=($SUDO apt-get -o DPkg::Lock::Timeout=600 -q)
phase 1 "updating the package lists" "${apt[@]}" update
phase 2 "downloading ${#missing[@]} packages and what they need" \
  "${apt[@]}" install -y --no-install-recommends --download-only "${missing[@]}"
phase 3 "installing ${#missing[@]} packages and what they need" \
  "${apt[@]}" install -y --no-install-recommends "${missing[@]}"
echo "install-deps: installed in $(( $(date +%s) - start )) s"
ensure_group
