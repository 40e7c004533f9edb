#!/bin/bash
# Issue 26: scripts/build-progress.sh, the build ./run.sh shows. On a small CMake project of
# its own (40 C files, one executable): not on a terminal it tells the number of steps, then
# prints at most a line per 10 % plus the last one ("building [42/42] ..."), never ninja's
# own lines; a second run has nothing to do; a file that does not compile fails the build
# with the whole compiler message (file:line, the error, the FAILED step) on stderr and
# the build's non-zero status. Run directly: tests/demo/build_progress_test.sh
set -uo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "build_progress_test: FAIL: $*"; echo "---- stdout"; cat "$work/out"; echo "---- stderr"; cat "$work/err"; exit 1; }

mkdir -p "$work/src"
sources=""
for i in $(seq 1 40); do
  printf 'int f%d(void) { return %d; }\n' "$i" "$i" > "$work/src/f$i.c"
  sources="$sources f$i.c"
done
printf 'int f1(void);\nint main(void) { return f1() - 1; }\n' > "$work/src/main.c"
cat > "$work/src/CMakeLists.txt" <<CMAKE
cmake_minimum_required(VERSION 3.25)
project(progress C)
add_executable(progress main.c $sources)
CMAKE
cmake -S "$work/src" -B "$work/build" -G Ninja >/dev/null 2>&1 || { : >"$work/out"; : >"$work/err"; fail "cannot configure the test project"; }

BUILD_JOBS=2 "$root/scripts/build-progress.sh" "$work/build" progress >"$work/out" 2>"$work/err"
status=$?
[ $status -eq 0 ] || fail "the build: exit $status"
head -1 "$work/out" | grep -qx "== building progress in $work/build: 42 steps" || fail "no step count before the build"
lines=$(grep -c '^building \[' "$work/out")
[ "$lines" -ge 2 ] && [ "$lines" -le 12 ] || fail "$lines progress lines (a line per 10 % and the last: 2..12)"
grep '^building \[' "$work/out" | tail -1 | grep -q '^building \[42/42\] Linking C executable progress$' || fail "the last progress line is not the link"
grep -q '@@progress\|Building C object' "$work/out" && fail "ninja's own lines in the output"
[ -x "$work/build/progress" ] || fail "nothing built"

"$root/scripts/build-progress.sh" "$work/build" progress >"$work/out" 2>"$work/err" || fail "the second build failed"
grep -qx "== building progress in $work/build: nothing to do" "$work/out" || fail "the second build did not say that nothing was to do"

printf 'int f7(void) { return undeclared_name; }\n' > "$work/src/f7.c"
"$root/scripts/build-progress.sh" "$work/build" progress >"$work/out" 2>"$work/err"
status=$?
[ $status -ne 0 ] || fail "a file that does not compile: exit 0"
grep -q "f7.c:1:.*error: .undeclared_name. undeclared" "$work/err" || fail "the compiler's error is not on stderr"
grep -q '^FAILED: .*f7\.c\.o' "$work/err" || fail "the FAILED step is not on stderr"
grep -q '@@progress' "$work/err" && fail "progress lines in the error output"
echo "build_progress_test: PASS"
