#!/bin/bash
# ctest package_lintian: lintian on the packages package_build wrote; every tag must be in
# packaging/lintian-explanations (packaging/lintian-check.sh; exit 77 without lintian).
#   check_lintian.sh PACKAGES_DIR VERSION ARCH
set -euo pipefail
dir=${1:?packages folder} version=${2:?version} arch=${3:?architecture}
root=$(cd "$(dirname "$0")/../.." && pwd)
debs=("$dir/openvcu_${version}_${arch}.deb")
[ -f "$dir/openvcu-hmi_${version}_${arch}.deb" ] && debs+=("$dir/openvcu-hmi_${version}_${arch}.deb")
for deb in "${debs[@]}"; do [ -f "$deb" ] || { echo "check_lintian: $deb missing (package_build)"; exit 1; }; done
exec "$root/packaging/lintian-check.sh" "${debs[@]}"
