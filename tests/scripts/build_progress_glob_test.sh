#!/bin/bash
# scripts/build-progress.sh (the build ./run.sh shows) on a project whose sources are a
# CONFIGURE_DEPENDS glob, as openvcu's own build is: ninja re-checks the glob before every
# build, so its dry run plans only "Re-checking globbed directories" and "Re-running CMake"
# (2 steps) and never the build itself. The announced step count must be the number the
# progress then counts to ("== building progress in DIR: N steps", last line
# "building [N/N] ..."); a second run has nothing to do and says so. Runs anywhere (no
# stack, no sandbox needed).
set -uo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "build_progress_glob_test: FAIL: $*"; echo "---- stdout"; cat "$work/out"; echo "---- stderr"; cat "$work/err"; exit 1; }

mkdir -p "$work/src"
for i in $(seq 1 12); do printf 'int f%d(void) { return %d; }\n' "$i" "$i" > "$work/src/f$i.c"; done
printf 'int f1(void);\nint main(void) { return f1() - 1; }\n' > "$work/src/main.c"
cat > "$work/src/CMakeLists.txt" <<'CMAKE'
cmake_minimum_required(VERSION 3.25)
project(progress C)
file(GLOB sources CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/*.c)
add_executable(progress ${sources})
CMAKE
: >"$work/out"; : >"$work/err"
cmake -S "$work/src" -B "$work/build" -G Ninja >/dev/null 2>&1 || fail "cannot configure the test project"

BUILD_JOBS=2 "$root/scripts/build-progress.sh" "$work/build" progress >"$work/out" 2>"$work/err" || fail "the build failed"
announced=$(sed -n "s|^== building progress in $work/build: \([0-9]*\) steps.*|\1|p" "$work/out" | head -1)
[ -n "$announced" ] || fail "no step count before the build"
last=$(grep '^building \[' "$work/out" | tail -1)
echo "$last" | grep -q "^building \[$announced/$announced\] Linking C executable progress$" ||
  fail "announced $announced steps, the progress ended with: $last"
grep -q 'Re-checking globbed\|Re-running CMake' "$work/out" && fail "CMake's glob check shown as a build step"
[ -x "$work/build/progress" ] || fail "nothing built"

"$root/scripts/build-progress.sh" "$work/build" progress >"$work/out" 2>"$work/err" || fail "the second build failed"
grep -qx "== building progress in $work/build: nothing to do" "$work/out" || fail "the second build did not say that nothing was to do"
echo "build_progress_glob_test: PASS"
