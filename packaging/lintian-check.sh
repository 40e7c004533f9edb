#!/bin/bash
# Runs lintian on Debian packages and checks every tag it prints against
# packaging/lintian-explanations (lines `<package> <tag>: why`). Prints each tag as
# "explained" or "NOT EXPLAINED"; exit 1 when a tag is not explained, 77 when lintian is not
# installed (a skip for ctest). Used by scripts/package.sh and tests/packaging.
#   packaging/lintian-check.sh [--explanations FILE] DEB...
set -euo pipefail

explanations="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)/lintian-explanations"
if [ "${1:-}" = "--explanations" ]; then explanations=${2:?--explanations needs a file}; shift 2; fi
[ $# -gt 0 ] || { echo "usage: lintian-check.sh [--explanations FILE] DEB..." >&2; exit 2; }
[ -f "$explanations" ] || { echo "lintian-check.sh: $explanations: no such file" >&2; exit 2; }
command -v lintian >/dev/null 2>&1 || { echo "lintian-check.sh: lintian not installed (scripts/install-deps.sh)"; exit 77; }

unexplained=0
tags=0
for deb in "$@"; do
  [ -f "$deb" ] || { echo "lintian-check.sh: $deb: no such file" >&2; exit 2; }
done
# one lintian for all packages (its start-up is most of the time). Exit 2 means it found an
# error tag (the tags decide below); anything else but 0 means lintian itself failed.
status=0
report=$(lintian --tag-display-limit 0 "$@" 2>&1) || status=$?
if [ $status -ne 0 ] && [ $status -ne 2 ]; then
  echo "$report"
  echo "lintian-check.sh: FAIL: lintian itself failed (exit $status)"
  exit 1
fi
while IFS= read -r line; do
  [ -n "$line" ] || continue
  # "E: openvcu: tag-name context" or "W: openvcu-hmi binary: tag-name context"
  if [[ "$line" =~ ^[EWIPXC]:\ ([a-z0-9.+-]+)(\ [a-z]+)?:\ ([A-Za-z0-9.+_-]+) ]]; then
    tags=$((tags + 1))
    if grep -Eq "^${BASH_REMATCH[1]}[[:space:]]+${BASH_REMATCH[3]}:" "$explanations"; then
      echo "lintian: explained: $line"
    else
      echo "lintian: NOT EXPLAINED: $line"
      unexplained=$((unexplained + 1))
    fi
  elif [ "$line" != "running with root privileges is not recommended!" ]; then
    echo "lintian: $line"
  fi
done <<<"$report"
if [ $unexplained -gt 0 ]; then
  echo "lintian-check.sh: FAIL: $unexplained of $tags tag(s) not in $explanations: fix them or explain them there"
  exit 1
fi
echo "lintian-check.sh: $# package(s), $tags tag(s), every one explained"
