#!/usr/bin/env bash
# The second command: installs what is missing, builds, runs every test.
#   ./test.sh            Release build + all tests, then an ASan+UBSan build of the unit tests + them
#   ./test.sh --fast     Release build + all tests only
# Exits non-zero if anything fails; prints ctest's summary.
set -euo pipefail
cd "$(dirname "$(readlink -f "$0")")"

fast=0
for arg in "$@"; do
  case "$arg" in
    --fast) fast=1 ;;
    -h|--help) sed -n '2,5p' "$0"; exit 0 ;;
    *) echo "test.sh: unknown option '$arg'" >&2; exit 2 ;;
  esac
done

jobs=$(nproc 2>/dev/null || echo 2)
scripts/install-deps.sh

echo "== Release build (build/)"
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j "$jobs"
echo "== Tests (Release)"
status=0
rm -f build/ctest.log build-asan/ctest.log
# ctest's own list of failures scrolls away under the ASan run: each run is also logged,
# and the lists are printed again at the end
ctest --test-dir build --output-on-failure -j "$jobs" 2>&1 | tee build/ctest.log || status=1

if [ $fast -eq 0 ]; then
  echo "== ASan+UBSan build (build-asan/)"
  cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=Asan -DOPENVCU_BUILD_BENCH=OFF >/dev/null
  # only what `ctest -L unit` runs; a unit test whose executable is missing from the target
  # would vanish from the list without an error, so the two lists must be equally long
  cmake --build build-asan -j "$jobs" --target unit-tests
  release_units=$(ctest --test-dir build -N -L unit | sed -n 's/^Total Tests: //p')
  asan_units=$(ctest --test-dir build-asan -N -L unit | sed -n 's/^Total Tests: //p')
  if [ "$release_units" != "$asan_units" ]; then
    echo "test.sh: build-asan lists $asan_units unit tests, build lists $release_units:" \
         "an executable is missing from the unit-tests target (openvcu_unit_test_target)" >&2
    status=1
  fi
  echo "== Unit tests under ASan+UBSan ($asan_units)"
  ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
    ctest --test-dir build-asan -L unit --output-on-failure -j "$jobs" 2>&1 | tee build-asan/ctest.log || status=1
fi

if [ $status -ne 0 ]; then
  for log in build/ctest.log build-asan/ctest.log; do
    if [ -f "$log" ]; then
      sed -n '/^The following tests FAILED/,/^Errors while running/p' "$log" | sed "s|^|${log%/*}: |" >&2
    fi
  done
  echo "test.sh: FAILED" >&2
else echo "test.sh: all tests passed"; fi
exit $status
