#!/bin/sh
# lcm-spy with the project's event types: shows every OPENVCU_* channel decoded.
#
#   shared/ipc/lcm-spy.sh [--types JAR] [--lcm-url URL]
#
# JAR defaults to $OPENVCU_LCM_TYPES_JAR, else the first openvcu-lcm-types.jar found under
# build*/shared/ipc/ of this checkout (built by the openvcu_lcm_jar target when a JDK is
# present). URL defaults to $LCM_DEFAULT_URL, else the stack's udpm://239.255.76.67:7667?ttl=0.
# Debian's own lcm-spy wrapper passes -Xincgc, which Java 17 refuses; this runs the same
# class directly. Needs a display (use `xvfb-run -a` when headless).
set -eu

here="$(cd "$(dirname "$0")" && pwd)"
repo="$(cd "$here/../.." && pwd)"
types="${OPENVCU_LCM_TYPES_JAR:-}"
url="${LCM_DEFAULT_URL:-udpm://239.255.76.67:7667?ttl=0}"
lcm_jar=/usr/share/java/lcm.jar
jchart_jar=/usr/share/java/jchart2d.jar

while [ $# -gt 0 ]; do
  case "$1" in
    --types) types="$2"; shift 2 ;;
    --types=*) types="${1#--types=}"; shift ;;
    --lcm-url) url="$2"; shift 2 ;;
    --lcm-url=*) url="${1#--lcm-url=}"; shift ;;
    -h|--help) sed -n '2,9p' "$0"; exit 0 ;;
    *) echo "lcm-spy.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done

if [ -z "$types" ]; then
  for candidate in "$repo"/build*/shared/ipc/openvcu-lcm-types.jar; do
    if [ -f "$candidate" ]; then types="$candidate"; break; fi
  done
fi
if [ -z "$types" ] || [ ! -f "$types" ]; then
  echo "lcm-spy.sh: no openvcu-lcm-types.jar: build the openvcu_lcm_jar target (needs a JDK) or pass --types JAR" >&2
  exit 1
fi
for jar in "$lcm_jar" "$jchart_jar"; do
  if [ ! -f "$jar" ]; then
    echo "lcm-spy.sh: $jar missing (install liblcm-java and libjchart2d-java)" >&2
    exit 1
  fi
done
if ! command -v java > /dev/null 2>&1; then
  echo "lcm-spy.sh: java not found (install default-jre)" >&2
  exit 1
fi

exec java -Djava.net.preferIPv4Stack=true -cp "$lcm_jar:$jchart_jar:$types" lcm.spy.Spy --lcm-url="$url"
