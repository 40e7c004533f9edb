#!/bin/bash
# Makes the Debian packages openvcu and openvcu-hmi from an already built tree with CPack
# (cmake/OpenvcuPackaging.cmake, docs/design/packaging.md), then checks them with lintian.
#
#   scripts/package.sh [--arch amd64|arm64] [--build-dir DIR] [--out DIR] [--no-lintian]
#
#   --arch       the packages' architecture (default: this machine's, dpkg --print-architecture)
#   --build-dir  the build tree (default: build for the native architecture, build-arm64 for
#                arm64). A missing native tree is configured (Release) and its target
#                openvcu-runtime built; a missing build-arm64 is made by scripts/cross-arm64.sh.
#                An existing tree is packaged as it is (its binaries are the tested ones):
#                only the generated packaging files are brought up to date.
#   --out        where the .deb files go (default: dist); written as
#                <out>/openvcu_<version>-1_<arch>.deb and <out>/openvcu-hmi_<version>-1_<arch>.deb
#                (openvcu-hmi only when the tree built vcu-hmi)
#   --no-lintian skip lintian
# lintian (when installed) runs on each package; every tag it prints must be explained in
# packaging/lintian-explanations, else the script fails (exit 1). Exit 2: bad arguments.
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
arch=""
build=""
out="$root/dist"
lintian_on=1

usage() { sed -n '2,/^set -euo/p' "${BASH_SOURCE[0]}" | sed -e '$d' -e 's/^# \{0,1\}//'; }
die() { echo "package.sh: $*" >&2; exit 1; }
step() { echo "package.sh: [$1] $2"; }

while [ $# -gt 0 ]; do
  case "$1" in
    --arch) arch=${2:?--arch needs amd64 or arm64}; shift 2 ;;
    --build-dir) build=${2:?--build-dir needs a folder}; shift 2 ;;
    --out) out=${2:?--out needs a folder}; shift 2 ;;
    --no-lintian) lintian_on=0; shift ;;
    -h|--help) usage; exit 0 ;;
    *) echo "package.sh: unknown argument '$1'" >&2; usage >&2; exit 2 ;;
  esac
done

native=$(dpkg --print-architecture 2>/dev/null || echo amd64)
arch=${arch:-$native}
case "$arch" in
  amd64|arm64) ;;
  *) echo "package.sh: --arch '$arch': expected amd64 or arm64" >&2; exit 2 ;;
esac
if [ -z "$build" ]; then
  if [ "$arch" = "$native" ]; then build="$root/build"; else build="$root/build-$arch"; fi
fi
mkdir -p "$out"
build=$(cd "$(dirname "$build")" && pwd)/$(basename "$build")
out=$(cd "$out" && pwd)

# 1. the build tree
if [ ! -f "$build/CMakeCache.txt" ]; then
  if [ "$arch" = "$native" ]; then
    step 1/4 "no build tree in $build: configuring (Release) and building openvcu-runtime"
    cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
    cmake --build "$build" --target openvcu-runtime
  elif [ "$arch" = arm64 ]; then
    [ -x "$root/scripts/cross-arm64.sh" ] || die "no build tree in $build and no scripts/cross-arm64.sh to make one"
    step 1/4 "no build tree in $build: scripts/cross-arm64.sh --build-dir $build"
    "$root/scripts/cross-arm64.sh" --build-dir "$build"
  fi
else
  step 1/4 "build tree $build"
fi
[ -f "$build/CPackConfig.cmake" ] || die "$build/CPackConfig.cmake missing: configure the tree with this repository's CMakeLists.txt"
tree_arch=$(sed -n 's/^set(CPACK_DEBIAN_PACKAGE_ARCHITECTURE "\(.*\)")$/\1/p' "$build/CPackConfig.cmake")
[ "$tree_arch" = "$arch" ] || die "$build was configured for architecture '${tree_arch:-?}', not $arch (--build-dir)"
components=$(sed -n 's/^set(CPACK_COMPONENTS_ALL "\(.*\)")$/\1/p' "$build/CPackConfig.cmake")
executables=(vcu vcu-can-rx vcu-can-tx vcu-fsm vcu-gpio vcu-ecu-sim vcu-web)
case ";$components;" in *";hmi;"*) executables+=(vcu-hmi) ;; esac
missing=()
for exe in "${executables[@]}"; do [ -x "$build/bin/$exe" ] || missing+=("$exe"); done
[ ${#missing[@]} -eq 0 ] ||
  die "$build/bin lacks ${missing[*]}: build them first (cmake --build $build --target openvcu-runtime)"

# 2. the generated files (/etc/openvcu from config/hhea, conffiles, changelog.Debian.gz)
step 2/4 "generated packaging files (/etc/openvcu, conffiles, changelog)"
cmake --build "$build" --target openvcu-packaging-files >/dev/null

# 3. CPack in a scratch folder, then the .deb files to --out
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
step 3/4 "cpack -G DEB ($arch; components: ${components//;/ })"
if ! (cd "$build" && cpack -G DEB --config "$build/CPackConfig.cmake" -B "$work") >"$work/cpack.log" 2>&1; then
  cat "$work/cpack.log" >&2
  die "cpack failed (log above)"
fi
shopt -s nullglob
debs=("$work"/*.deb)
[ ${#debs[@]} -gt 0 ] || { cat "$work/cpack.log" >&2; die "cpack wrote no .deb"; }
written=()
for deb in "${debs[@]}"; do
  name=$(basename "$deb")
  rm -f "$out/$name"
  mv "$deb" "$out/$name"
  written+=("$out/$name")
  echo "package.sh:   $out/$name ($(du -k "$out/$name" | cut -f1) KiB)"
done

# 4. lintian, each tag against packaging/lintian-explanations
if [ $lintian_on -eq 0 ]; then
  step 4/4 "lintian skipped (--no-lintian)"
  exit 0
fi
if ! command -v lintian >/dev/null 2>&1; then
  step 4/4 "lintian not installed (scripts/install-deps.sh): not checked"
  exit 0
fi
step 4/4 "lintian (packaging/lintian-check.sh)"
"$root/packaging/lintian-check.sh" "${written[@]}" | sed 's/^/package.sh:   /'
