#!/usr/bin/env bash
# Builds CMake targets of a configured Ninja build folder and shows how far the build is,
# instead of ninja's wall of lines (./run.sh builds openvcu-runtime through it).
#   scripts/build-progress.sh BUILD_DIR TARGET...
# Before building: the number of steps to run (ninja's dry run; when CMake first checks
# build.ninja, ninja's own count once that check is done), or that nothing is to do.
# On a terminal: one line, rewritten in place, "building [n/m] <what was just built>".
# Otherwise (a pipe, a CI log): a line at about every 10 % and the last one.
# Every line ninja and the compilers print goes to BUILD_DIR/build-progress.log. On failure
# the compilers' whole output (each FAILED step with its command and messages) is printed
# to stderr, and the exit status is the build's.
# BUILD_JOBS: parallel jobs (default: the number of CPUs).
set -euo pipefail

if [ $# -lt 2 ]; then
  echo "usage: scripts/build-progress.sh BUILD_DIR TARGET..." >&2; exit 2
fi
dir=$1; shift
if [ ! -f "$dir/build.ninja" ]; then
  echo "build-progress.sh: $dir/build.ninja: no such file (configure with -G Ninja first)" >&2; exit 2
fi
jobs=${BUILD_JOBS:-$(nproc 2>/dev/null || echo 2)}
log=$dir/build-progress.log

# ninja starts each status line with NINJA_STATUS: a marker no compiler prints, then n/m
export NINJA_STATUS='@@progress %f/%t@@ '
# CMake's check of build.ninja itself (a CONFIGURE_DEPENDS glob re-checked before every
# build, a re-run of CMake): not a build step. A dry run cannot know whether the check will
# change build.ninja, so it plans only the check and stops: the count then comes from the
# real build, once ninja has restarted on the checked file.
manifest='^@@progress [0-9]*/[0-9]*@@ (Re-checking globbed directories|Re-running CMake)'
header="== building $* in $dir"
note=${BUILD_PROGRESS_NOTE:+ ($BUILD_PROGRESS_NOTE)}
announce=0
if dry=$(cmake --build "$dir" --target "$@" -- -n 2>&1); then
  if grep -Eq "$manifest" <<<"$dry"; then
    announce=1
  else
    steps=$(grep -c '^@@progress ' <<<"$dry" || true)
    if [ "$steps" -eq 0 ]; then
      echo "$header: nothing to do"
      exit 0
    fi
    echo "$header: $steps steps$note"
  fi
else
  # the build below fails the same way and shows why
  echo "$header"
fi

tty=0; [ -t 1 ] && tty=1
cols=80
if [ $tty -eq 1 ]; then cols=$(tput cols 2>/dev/null || echo 80); fi
start=$(date +%s)
status=0
# awk reads everything ninja and the compilers print, writes it to the log and draws the
# progress from ninja's status lines.
cmake --build "$dir" -j "$jobs" --target "$@" 2>&1 |
  awk -v tty=$tty -v cols="$cols" -v logfile="$log" -v announce=$announce -v header="$header" -v note="$note" '
  function what(s) {
    # "Building CXX object services/web/CMakeFiles/openvcu_web_app.dir/src/web_app.cpp.o"
    # -> "services/web/src/web_app.cpp"
    if (match(s, /^Building (C|CXX) object /)) {
      s = substr(s, RLENGTH + 1)
      sub(/CMakeFiles\/[^\/]*\.dir\//, "", s)
      sub(/\.o$/, "", s)
    }
    return s
  }
  function show(n, m, s,   line) {
    line = "building [" n "/" m "] " what(s)
    if (tty) {
      if (length(line) > cols - 1) line = substr(line, 1, cols - 1)
      printf "\r\033[K%s", line
      fflush()
    } else {
      print line
      fflush()
    }
    shown = 1
  }
  BEGIN { printf "" > logfile; decile = -1 }
  {
    print > logfile
    if (substr($0, 1, 11) == "@@progress ") {
      rest = substr($0, 12)
      split(substr(rest, 1, index(rest, "@@") - 1), nm, "/")
      n = nm[1] + 0; m = nm[2] + 0; s = substr(rest, index(rest, "@@ ") + 3)
      if (s ~ /^(Re-checking globbed directories|Re-running CMake)/) next
      if (announce) { print header ": " m " steps" note; fflush(); announce = 0 }
      lastn = n; lastm = m; lasts = s
      if (tty) show(n, m, s)
      else if (m > 0 && int(10 * n / m) > decile) { decile = int(10 * n / m); show(n, m, s); printedn = n }
    }
  }
  END {
    if (announce) print header ": nothing to do"
    if (!tty && lastn && printedn != lastn) show(lastn, lastm, lasts)
    if (tty && shown) printf "\n"
  }' || status=$?
# the pipeline fails with cmake --build's status (pipefail)
if [ $status -ne 0 ]; then
  {
    # Every line that is not progress: each FAILED step with its command and the compiler's
    # messages (ninja prints them after the step), and ninja's reason for stopping.
    echo "build-progress.sh: the build of $* in $dir failed; the compilers' output:"
    grep -v '^@@progress ' "$log" || true
    echo "build-progress.sh: full log: $log"
  } >&2
  exit $status
fi
# after CMake's check alone nothing was built: the awk above said so
grep '^@@progress ' "$log" | grep -Evq "$manifest" || exit 0
echo "== built $* in $(( $(date +%s) - start )) s (log: $log)"
