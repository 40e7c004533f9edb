#!/bin/bash
# The sandbox of run_isolated.sh and the team kit.
#   test_sandbox_kit.sh keep-ro     run_isolated.sh --keep-ro DIR on a folder under /tmp: the
#                                   folder's files are seen inside the fresh /tmp, and nothing
#                                   can be written there (the folder outside stays unchanged)
#   test_sandbox_kit.sh clone       a clone under /tmp with the team kit beside it (CI's layout:
#                                   /tmp/X/main and /tmp/X/shared, the kit configured as
#                                   main/../shared): the launcher of isolated tests, written by
#                                   isolated_launcher.cmake for that layout, shows the kit inside
#                                   the sandbox, read-only
# Runs outside the sandbox (it starts run_isolated.sh itself); exit 0 passed, 1 failed.
set -uo pipefail
here=$(cd "$(dirname "$0")" && pwd)
mode=${1:?keep-ro or clone}
NAME="test_sandbox_kit($mode)"
fail() { echo "$NAME: FAIL: $*"; exit 1; }

work=$(mktemp -d /tmp/openvcu-sandbox-kit.XXXXXX) || fail "mktemp"
trap 'rm -rf "$work"' EXIT

# What the command inside the sandbox checks: DIR/marker is readable and holds "kit", and
# neither a new file nor a change to the marker is possible.
probe='cat "$0/marker" | grep -qx kit || { echo "marker not visible in $0"; exit 10; }
       if touch "$0/written" 2>/dev/null; then echo "$0 is writable"; exit 11; fi
       if echo changed 2>/dev/null > "$0/marker"; then echo "$0/marker is writable"; exit 12; fi
       exit 0'

case "$mode" in
  keep-ro)
    mkdir -p "$work/kit"
    echo kit > "$work/kit/marker"
    out=$("$here/run_isolated.sh" --keep-ro "$work/kit" -- sh -c "$probe" "$work/kit" 2>&1)
    code=$?
    [ $code -eq 0 ] || fail "inside the sandbox (exit $code): $out"
    [ ! -e "$work/kit/written" ] || fail "a file appeared in the kept folder"
    grep -qx kit "$work/kit/marker" || fail "the marker changed"
    # A folder that does not exist is refused with its name, before any namespace is made.
    out=$("$here/run_isolated.sh" --keep-ro "$work/missing" -- true 2>&1)
    code=$?
    [ $code -eq 2 ] || fail "--keep-ro on a missing folder exited $code, not 2: $out"
    echo "$out" | grep -q "$work/missing: not a directory" || fail "no clear error for a missing folder: $out"
    ;;
  clone)
    mkdir -p "$work/main/build" "$work/shared"
    echo kit > "$work/shared/marker"
    kit="$work/main/../shared"
    cmake -DOUTPUT="$work/main/build/run_isolated" -DBINARY_DIR="$work/main/build" -DSOURCE_DIR="$work/main" \
      -DTEAM_KIT="$kit" -P "$here/isolated_launcher.cmake" || fail "isolated_launcher.cmake failed"
    out=$(cd "$work/main/build" && ./run_isolated sh -c "$probe" "$kit" 2>&1)
    code=$?
    [ $code -eq 0 ] || fail "inside the sandbox (exit $code): $out"
    [ ! -e "$work/shared/written" ] || fail "a file appeared in the team kit"
    # Without a kit beside the clone the launcher still runs the command (the kit's tests
    # then skip themselves).
    rm -rf "$work/shared"
    out=$(cd "$work/main/build" && ./run_isolated sh -c 'test "$OPENVCU_ISOLATED" = 1' 2>&1)
    code=$?
    [ $code -eq 0 ] || fail "without a kit the launcher failed (exit $code): $out"
    ;;
  *) fail "unknown mode" ;;
esac
echo "$NAME: passed"
