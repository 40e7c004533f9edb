#!/usr/bin/env bash
# The first command: sets up and runs openvcu on the simulated HHEA vehicle.
#
# The services (can-rx, can-tx, fsm, gpio, hmi, ecu-sim) do not exist yet. Until they do,
# this installs what is missing, builds the `vcu` tool and checks the embedded HHEA
# configuration: the vehicle DBC is parsed, validated and summarised, and vehicle.json is
# loaded into its signal catalog.
#   ./run.sh                 check and summarise config/hhea
#   ./run.sh --info          also list every HHEA message and signal
set -euo pipefail
cd "$(dirname "$(readlink -f "$0")")"

info=0
for arg in "$@"; do
  case "$arg" in
    --info) info=1 ;;
    -h|--help) sed -n '2,9p' "$0"; exit 0 ;;
    *) echo "run.sh: unknown option '$arg'" >&2; exit 2 ;;
  esac
done

scripts/install-deps.sh --quiet
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build --target vcu -j "$(nproc 2>/dev/null || echo 2)" >/dev/null

vcu=build/bin/vcu
echo "== openvcu: HHEA compact track loader configuration (config/hhea)"
"$vcu" dbc check config/hhea/hhea.dbc
# Loading the signal catalog validates the whole vehicle.json (buses, DBC, internal signals).
echo "== The operator switches and internal signals of config/hhea/vehicle.json"
"$vcu" signal list --config config/hhea/vehicle.json 'internal.*'
echo "== The state machine config/hhea/fsm.json (docs/fsm.md)"
"$vcu" fsm check config/hhea/fsm.json --config config/hhea/vehicle.json
if [ $info -eq 1 ]; then
  "$vcu" dbc info config/hhea/hhea.dbc
else
  echo "(./run.sh --info lists every message and signal; build/bin/vcu --help shows the tool)"
fi
