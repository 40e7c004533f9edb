#!/bin/bash
# scripts/install-deps.sh on a machine where packages are missing, with dpkg-query, apt-get,
# id and getent faked on PATH (the OS edge: nothing is installed, no group is touched). The
# fake apt-get prints what apt prints on a first run (hundreds of "Setting up ..." lines).
#   - install-deps prints one line per phase and a last line, a few lines in all; apt's
#     output is in the log file it names (OPENVCU_DEPS_LOG), and the packages asked for are
#     the missing ones;
#   - when apt-get fails, install-deps exits non-zero and prints the phase that failed and
#     the log's tail (apt's error) on stderr.
set -uo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "install_deps_quiet_test: FAIL: $*"; echo "---- stdout"; cat "$work/out"; echo "---- stderr"; cat "$work/err"; exit 1; }
: >"$work/out"; : >"$work/err"

mkdir -p "$work/bin"
# every package installed except cmake and lintian
cat > "$work/bin/dpkg-query" <<'FAKE'
#!/bin/sh
pkg=$(eval echo "\${$#}")
case "$pkg" in cmake|lintian) printf 'unknown ok not-installed' ;; *) printf 'install ok installed' ;; esac
FAKE
cat > "$work/bin/apt-get" <<'FAKE'
#!/bin/sh
echo "apt-get $*" >> "$FAKE_CALLS"
echo "Reading package lists..."
case " $* " in
  *" update "*) for i in $(seq 1 40); do echo "Get:$i http://deb.debian.org/debian bookworm/main Packages"; done ;;
  *" --download-only "*) for i in $(seq 1 120); do echo "Get:$i http://deb.debian.org/debian bookworm/main lib$i"; done ;;
  *" install "*)
    for i in $(seq 1 300); do echo "Setting up lib$i (1.0-1) ..."; done
    if [ -n "${FAKE_APT_FAIL:-}" ]; then echo "E: Sub-process /usr/bin/dpkg returned an error code (1)"; exit 100; fi ;;
esac
exit 0
FAKE
printf '#!/bin/sh\ncase "$1" in -u) echo 0 ;; -nG) echo "root openvcu" ;; *) echo root ;; esac\n' > "$work/bin/id"
printf '#!/bin/sh\nexit 0\n' > "$work/bin/getent"
chmod +x "$work/bin/"*

run() { PATH="$work/bin:$PATH" FAKE_CALLS="$work/calls" OPENVCU_DEPS_LOG="$work/deps.log" \
          "$root/scripts/install-deps.sh" --quiet >"$work/out" 2>"$work/err"; }

run
status=$?
[ $status -eq 0 ] || fail "exit $status with apt succeeding"
lines=$(wc -l < "$work/out")
echo "install_deps_quiet_test: $lines lines:"; sed 's/^/  | /' "$work/out"
[ "$lines" -le 6 ] || fail "$lines lines of output (one per phase and a last line: at most 6)"
grep -q "Setting up\|Get:" "$work/out" "$work/err" && fail "apt's own lines on the terminal"
grep -q "$work/deps.log" "$work/out" || fail "the log file is not named"
grep -q "Setting up lib300" "$work/deps.log" || fail "apt's output is not in the log"
grep -q "^apt-get .*install .*cmake lintian" "$work/calls" || fail "not asked for the missing packages: $(cat "$work/calls")"
grep -q "^apt-get .*install .*build-essential" "$work/calls" && fail "asked for a package that is installed"

FAKE_APT_FAIL=1 run
status=$?
[ $status -ne 0 ] || fail "exit 0 although apt-get install failed"
grep -q "returned an error code" "$work/err" || fail "apt's error (the log's tail) is not on stderr"
grep -q "failed" "$work/err" || fail "no line says which phase failed"
[ "$(wc -l < "$work/out")" -le 6 ] || fail "a failed run printed more than the phase lines"
echo "install_deps_quiet_test: PASS"
