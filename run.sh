#!/usr/bin/env bash
# The first command: installs what is missing, builds what it runs (target openvcu-runtime:
# the services, vcu, vcu-hmi; not the tests, which ./test.sh builds) with its progress shown,
# and runs the openvcu stack on the simulated HHEA vehicle under supervisord until Ctrl-C.
#   ./run.sh                      the stack + the simulated vehicle, a live status view, and
#                                 the Qt HMI when a display is available (DISPLAY/WAYLAND_DISPLAY)
#   ./run.sh --scenario drive     also drive it: Start -> Connect Driving -> AC charging -> Stop
#                                 (the HHEA loader only)
#   ./run.sh --headless           no HMI, no status view: a status line every 3 s
#   ./run.sh --for SECONDS        stop after SECONDS
#   ./run.sh --isolated           in private mount, network and PID namespaces (LCM multicast
#                                 stays on loopback); logs and --record land in folders of this
#                                 machine that outlive the sandbox (printed at start and end)
#   ./run.sh --record DIR         record the session: every bus as candump -L, the LCM events
#   ./run.sh --bus socketcan:can0 the vehicle bus on real hardware (no simulated vehicle)
#   ./run.sh --config FILE        another vehicle (default config/hhea/vehicle.json)
#   ./run.sh --web-port PORT      vcu-web, the VCU in a browser, on http://127.0.0.1:PORT
#                                 (default 8080; 0: not started); read-only until a user
#                                 exists (the command to add one is printed at start)
#   ./run.sh --dbc FILE --node NAME [--into DIR]
#                                 a new machine from its DBC in one command: `vcu init DIR`
#                                 (default ./<DBC name>) for the VCU node NAME, then runs it;
#                                 an existing DIR/vehicle.json is run as it is (docs/bring-up.md)
#   ./run.sh --check              only `vcu check` every file of the vehicle and exit with its
#                                 code (0 clean, 1 errors); installs and builds nothing
#   ./run.sh --fleet N            a fleet: a local mosquitto on 127.0.0.1:1883 and N simulated
#                                 vehicles (instances <instance>-01 ..., each a copy of the
#                                 vehicle's folder in the run folder) publishing to it through
#                                 vcu-telemetry, watched with `vcu fleet watch`; HHEA vehicles
#                                 are started (StartStop), the second also connects Driving
# Ctrl-C (or the end of --for) stops every process cleanly and removes the stack's shared
# memory, also when the output is piped (`./run.sh | tee run.log`). Logs: the folder printed
# at start (one file per service); it is kept. Recordings, exports, uploads and vcu-web's
# users file: build/data (the data folder of vcu-hmi and vcu-web; it outlives the run).
set -euo pipefail
# paths given on the command line are the caller's (relative to where run.sh was started);
# realpath -m: the folder of --record need not exist yet
root=$(dirname "$(readlink -f "$0")")

headless=0; scenario=""; seconds=""; isolated=0; fleet=0; bus=""; check=0; record=""; dbc=""; node=""; into=""; web_port=8080
config=$root/config/hhea/vehicle.json; config_given=0
while [ $# -gt 0 ]; do
  case "$1" in
    --headless) headless=1 ;;
    --scenario) scenario=${2:?--scenario needs a name}; shift ;;
    --for) seconds=${2:?--for needs seconds}; shift ;;
    --isolated) isolated=1 ;;
    --bus) bus=${2:?--bus needs socketcan:IFACE}; shift ;;
    --record) record=$(realpath -m -- "${2:?--record needs a folder}"); shift ;;
    --config) config=$(realpath -m -- "${2:?--config needs a file}"); config_given=1; shift ;;
    --check) check=1 ;;
    --dbc) dbc=$(realpath -m -- "${2:?--dbc needs a DBC file}"); shift ;;
    --node) node=${2:?--node needs the node name of the VCU}; shift ;;
    --into) into=$(realpath -m -- "${2:?--into needs a folder}"); shift ;;
    --web-port) web_port=${2:?--web-port needs a port (0: no vcu-web)}; shift ;;
    --fleet) fleet=${2:?--fleet needs a number of vehicles}; shift ;;
    -h|--help) sed -n '2,34p' "$0"; exit 0 ;;
    *) echo "run.sh: unknown option '$1' (./run.sh --help)" >&2; exit 2 ;;
  esac
  shift
done
case "$scenario" in ""|drive) ;; *) echo "run.sh: unknown scenario '$scenario' (known: drive)" >&2; exit 2 ;; esac
if [ -n "$dbc" ]; then
  [ -n "$node" ] || { echo "run.sh: --dbc needs --node NAME (the VCU's node in the DBC)" >&2; exit 2; }
  [ $config_given -eq 0 ] || { echo "run.sh: --dbc and --config exclude each other" >&2; exit 2; }
  [ $check -eq 0 ] || { echo "run.sh: --check takes --config (vcu init checks what it writes)" >&2; exit 2; }
  [ -f "$dbc" ] || { echo "run.sh: --dbc $dbc: no such file" >&2; exit 2; }
  [ -n "$into" ] || into=$(realpath -m -- "$(basename "$dbc" .dbc)")
  config=$into/vehicle.json
elif [ -n "$node" ] || [ -n "$into" ]; then
  echo "run.sh: --node and --into go with --dbc" >&2; exit 2
fi
# the drive scenario sets HHEA's operator switches: another vehicle is driven by its own tests
if [ -n "$scenario" ] && [ "$(realpath -m -- "$config")" != "$root/config/hhea/vehicle.json" ]; then
  echo "run.sh: --scenario $scenario drives the HHEA loader (config/hhea) only; drive $config with" \
    "'vcu signal set' (its README names the switches)" >&2
  exit 2
fi
case "$bus" in ""|socketcan:*) ;; *) echo "run.sh: --bus takes socketcan:IFACE" >&2; exit 2 ;; esac
if [ -n "$seconds" ] && ! [[ "$seconds" =~ ^[0-9]+$ ]]; then echo "run.sh: --for takes whole seconds" >&2; exit 2; fi
if ! [[ "$fleet" =~ ^[0-9]+$ ]] || [ "$fleet" -gt 20 ]; then echo "run.sh: --fleet takes a number of vehicles, 1-20" >&2; exit 2; fi
fleet=$((10#$fleet))
if [ "$fleet" -gt 0 ] && { [ -n "$bus" ] || [ -n "$record" ] || [ -n "$scenario" ] || [ -n "$dbc" ] || [ $check -eq 1 ]; }; then
  echo "run.sh: --fleet runs simulated vehicles only: not with --bus, --record, --scenario, --dbc or --check" >&2; exit 2
fi
if ! [[ "$web_port" =~ ^[0-9]{1,5}$ ]] || [ "$web_port" -gt 65535 ]; then
  echo "run.sh: --web-port takes a port 1-65535, or 0 for no vcu-web" >&2; exit 2
fi
web_port=$((10#$web_port))
cd "$root"

bin=${OPENVCU_BIN:-$root/build/bin}  # the tests point it at their build tree
vcu=$bin/vcu

# --check: the configuration alone, with the vcu that is built; nothing installed or built
if [ $check -eq 1 ]; then
  if [ ! -x "$vcu" ]; then
    echo "run.sh: $vcu is not built: ./run.sh builds it, or: cmake --build build --target vcu" >&2
    exit 2
  fi
  exec "$vcu" check --config "$config"
fi

if [ -n "$record" ] && ! mkdir -p "$record"; then
  echo "run.sh: cannot create the recording folder $record" >&2; exit 1
fi

if [ "${OPENVCU_ISOLATED:-0}" != 1 ]; then
  scripts/install-deps.sh --quiet
  echo "== configuring build/"
  cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
  # Only what this script runs: the services, vcu, vcu-hmi and the LCM types jar (the target
  # openvcu-runtime, cmake/OpenvcuRuntimeTarget.cmake). ./test.sh builds the tests in the same
  # build/, reusing these objects. The progress: scripts/build-progress.sh.
  note=""
  [ -x build/bin/vcu ] || note="the first build: minutes, 6 on a 2-core VM (README.md)"
  BUILD_PROGRESS_NOTE=$note scripts/build-progress.sh build openvcu-runtime ||
    { echo "run.sh: the build failed (the compilers' output above)" >&2; exit 1; }
fi

# --dbc: the vehicle folder from the DBC (vcu init checks every file before writing any)
if [ -n "$dbc" ]; then
  if [ -f "$config" ]; then
    echo "== $config exists: running it as it is (vcu init --force $into ... regenerates it)"
  else
    echo "== vcu init $into for node $node of $dbc"
    "$vcu" init "$into" --dbc "$dbc" --node "$node" || { echo "run.sh: vcu init failed (above)" >&2; exit 1; }
  fi
fi

if [ "${OPENVCU_ISOLATED:-0}" != 1 ]; then
  if [ $isolated -eq 1 ]; then
    # the same sandbox as the tests: fresh /dev/shm and /tmp, lo only, PID namespace
    keep=(--keep "$root" --keep "$(dirname "$config")")
    # The sandbox's /tmp is private and goes with it: the logs and the recording live in
    # folders of this machine, bound into the sandbox at the same paths, so they are there
    # to read afterwards.
    OPENVCU_LOG_DIR=$(mktemp -d "${TMPDIR:-/tmp}/openvcu-run.XXXXXX")
    export OPENVCU_LOG_DIR
    keep+=(--keep "$OPENVCU_LOG_DIR")
    [ -n "$record" ] && keep+=(--keep "$record")
    # the X server's socket folder, so that the HMI reaches the display from the sandbox
    [ -n "${DISPLAY:-}" ] && [ -d /tmp/.X11-unix ] && keep+=(--keep /tmp/.X11-unix)
    case "${XAUTHORITY:-}" in /tmp/*) keep+=(--keep "$(dirname "$XAUTHORITY")") ;; esac
    # the options as parsed here, with absolute paths
    inner=(--config "$config")
    [ $headless -eq 1 ] && inner+=(--headless)
    [ -n "$scenario" ] && inner+=(--scenario "$scenario")
    [ -n "$seconds" ] && inner+=(--for "$seconds")
    [ -n "$bus" ] && inner+=(--bus "$bus")
    [ -n "$record" ] && inner+=(--record "$record")
    inner+=(--web-port "$web_port")
    [ "$fleet" -gt 0 ] && inner+=(--fleet "$fleet")
    exec tests/harness/run_isolated.sh "${keep[@]}" -- "$root/run.sh" "${inner[@]}"
  fi
fi

if [ "$fleet" -gt 0 ]; then
  OPENVCU_BIN=$bin exec "$root/scripts/run-fleet.sh" "$fleet" "$config" "$headless" "$seconds"
fi

echo "== configuration $config"
# Every file checked before anything starts; errors (on stderr) refuse the run.
"$vcu" check -q --config "$config" >/dev/null || { echo "run.sh: the configuration has errors (above)" >&2; exit 1; }

run=${OPENVCU_LOG_DIR:-$(mktemp -d "${TMPDIR:-/tmp}/openvcu-run.XXXXXX")}
# vcu check passed: the file is valid JSON with a valid instance (this cannot raise)
instance=$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["instance"])' "$config")
if [ -n "$bus" ]; then
  # a copy of the configuration next to the original (relative paths keep working) with the
  # first bus on the real interface; the simulated vehicle is not started
  copy=$(dirname "$config")/.run-$(basename "$config" .json)-$$.json
  python3 - "$config" "$copy" "$bus" <<'PY'
import json, sys
vehicle = json.load(open(sys.argv[1]))
vehicle["buses"][0]["link"] = sys.argv[3]
json.dump(vehicle, open(sys.argv[2], "w"), indent=2)
PY
  config=$copy
fi
export OPENVCU_BIN=$bin OPENVCU_CONFIG=$config OPENVCU_RUN=$run OPENVCU_ROUDI=$root/config/iceoryx/iox-roudi.sh
sed -e "s/^;user=root.*/$( [ "$(id -u)" = 0 ] && echo 'user=root' || echo ';not root')/" \
  config/supervisor/openvcu.conf > "$run/openvcu.conf"
if [ -n "$bus" ]; then
  sed -i -e '/^\[program:ecu-sim\]/,/^$/s/^autorestart=true/autostart=false\nautorestart=true/' "$run/openvcu.conf"
fi
# the data folder of vcu-hmi and vcu-web, beside the binaries so that it outlives the run
# (openvcu.conf names $run/data)
data=$(dirname "$bin")/data
mkdir -p "$data" || { echo "run.sh: cannot create the data folder $data" >&2; exit 1; }
ln -sfn "$data" "$run/data"
web=0
if [ "$web_port" -ne 0 ] && [ -x "$bin/vcu-web" ]; then
  web=1
  sed -i -e '/^\[program:web\]/,/^$/{s/^autostart=false/autostart=true/;s/127\.0\.0\.1:8080/127.0.0.1:'"$web_port"'/}' \
    "$run/openvcu.conf"
fi
hmi=0
if [ $headless -eq 0 ] && [ -x "$bin/vcu-hmi" ] && { [ -n "${DISPLAY:-}" ] || [ -n "${WAYLAND_DISPLAY:-}" ]; }; then
  hmi=1
  sed -i -e '/^\[program:hmi\]/,/^$/s/^autostart=false/autostart=true/' "$run/openvcu.conf"
fi
echo "== starting the stack under supervisord (logs: $run)$( [ $hmi -eq 1 ] && echo ', with the HMI')$( [ $web -eq 1 ] && echo ', with vcu-web')"

# Stopping. Ctrl-C sends SIGINT to the whole foreground process group: this script, the
# command it waits for, and whatever its output is piped to (`| tee run.log`), which then
# dies. So: SIGPIPE is ignored here (a write to the dead pipe fails instead of killing this
# script before it has stopped anything), supervisord writes to its own file and never to
# that pipe, and the stop ignores further signals until supervisord has stopped every
# program and exited. Services whose supervisor dies anyway end by themselves (the service
# runtime's PR_SET_PDEATHSIG).
trap '' PIPE
say() { echo "$@" 2>/dev/null || true; }
supervisord -n -c "$run/openvcu.conf" >"$run/supervisord.out" 2>&1 &
supervisor=$!
recorder=""; driver=""; roudi=""; helper=""

stopped=0
stop() {
  [ $stopped -eq 1 ] && return
  stopped=1
  trap '' INT TERM
  set +e  # a wait on a process ended by a signal returns >128: the stop goes on regardless
  say "== stopping"
  if [ -n "$helper" ]; then kill -TERM "$helper" 2>/dev/null; wait "$helper" 2>/dev/null; fi
  if [ -n "$driver" ]; then pkill -TERM -P "$driver" 2>/dev/null; kill -TERM "$driver" 2>/dev/null; wait "$driver" 2>/dev/null; fi
  if [ -n "$recorder" ]; then kill -INT "$recorder" 2>/dev/null; wait "$recorder" 2>/dev/null; fi
  supervisorctl -c "$run/openvcu.conf" shutdown >/dev/null 2>&1 || kill -TERM "$supervisor" 2>/dev/null || true
  wait "$supervisor" 2>/dev/null || true
  # A supervisord that died (SIGKILL) stopped nothing: its services end by themselves,
  # iox-roudi (started through iox-roudi.sh, not the service runtime) is stopped here.
  if [ -n "$roudi" ] && kill -0 "$roudi" 2>/dev/null; then
    kill -TERM "$roudi" 2>/dev/null
    for _ in $(seq 1 50); do kill -0 "$roudi" 2>/dev/null || break; sleep 0.1; done
  fi
  # every service has ended: the signal table and its lock go (iox-roudi removed its own)
  rm -f "/dev/shm/openvcu-$instance" "/dev/shm/openvcu-$instance.lock"
  [ -n "$bus" ] && rm -f "$config"
  say "== stopped; logs in $run"
}
trap stop EXIT
trap 'exit 130' INT
trap 'exit 143' TERM

# Waits for a command run in the background. A SIGINT that arrives meanwhile ends the
# wait at once and runs the trap. A command in the foreground would get the SIGINT too,
# and when it handles it and exits 0 (vcu top and vcu status do) bash runs no trap at all:
# this script would carry on with its output going nowhere.
waitfor() {
  "$@" &
  helper=$!
  local status=0
  wait "$helper" || status=$?
  helper=""
  return $status
}

# up when every service beats (vcu status lists one line per service heard)
expected=5; [ -n "$bus" ] && expected=4
for _ in $(seq 1 30); do
  waitfor "$vcu" status --config "$config" --wait 1 >"$run/status.txt" 2>/dev/null || true
  beating=$(grep -c '^vcu-' "$run/status.txt" || true)
  [ "$beating" -ge "$expected" ] && break
done
waitfor "$vcu" top --once --config "$config" || true
if [ $web -eq 1 ]; then
  # supervisord calls it RUNNING once it has lived startsecs (3 s): a vcu-web that cannot
  # start (the port taken) is told here rather than announced
  for _ in $(seq 1 10); do
    web_state=$(supervisorctl -c "$run/openvcu.conf" status web 2>/dev/null | awk '{print $2}' || true)
    [ "$web_state" = RUNNING ] && break
    waitfor sleep 0.5 || true
  done
  users=$data/web-users.json
  if [ "$web_state" != RUNNING ]; then
    say "web: vcu-web is not running (${web_state:-no state}; its log: $run/web.log)"
  else
    if [ -s "$users" ]; then access="logins from $users"; else access="read-only until a user exists"; fi
    sandbox=""; [ "${OPENVCU_ISOLATED:-0}" = 1 ] && sandbox=" in the sandbox's own network"
    say "web: http://127.0.0.1:$web_port$sandbox ($access: $bin/vcu-web passwd --users $users NAME)"
  fi
elif [ "$web_port" -ne 0 ]; then
  say "web: not started: $bin/vcu-web is not built"
fi
roudi=$(supervisorctl -c "$run/openvcu.conf" pid roudi 2>/dev/null || true)
[[ "$roudi" =~ ^[1-9][0-9]*$ ]] || roudi=""

if [ -n "$record" ]; then
  "$vcu" record "$record" --force --config "$config" &
  recorder=$!
fi

drive() {
  local set=("$vcu" signal set --config "$config")
  echo "== scenario drive: Start"; "${set[@]}" internal.operator.StartStop Start; sleep 5
  echo "== scenario drive: Connect Driving"; "${set[@]}" internal.operator.ConnectDriving 1; sleep 6
  echo "== scenario drive: disconnect, AC charging"; "${set[@]}" internal.operator.ConnectDriving 0; sleep 3
  "${set[@]}" internal.operator.ACCharging 1; sleep 6
  echo "== scenario drive: stop charging, Stop"; "${set[@]}" internal.operator.ACCharging 0; sleep 3
  "${set[@]}" internal.operator.StartStop Stop
}
if [ "$scenario" = drive ]; then drive & driver=$!; fi

deadline=""
[ -n "$seconds" ] && deadline=$(( $(date +%s) + seconds ))
view="$vcu top --config $config"
"$vcu" top --help >/dev/null 2>&1 || view=""
while kill -0 "$supervisor" 2>/dev/null; do
  if [ -n "$deadline" ] && [ "$(date +%s)" -ge "$deadline" ]; then break; fi
  if [ $headless -eq 0 ] && [ -n "$view" ] && [ -t 1 ]; then
    left=""; [ -n "$deadline" ] && left="--for $(( deadline - $(date +%s) ))"
    $view $left || true
    break
  fi
  waitfor "$vcu" top --once --config "$config" >"$run/top.txt" 2>/dev/null || true
  say "$(date +%T) $(grep -E '^(FSM|BATTERY|STATUS) ' "$run/top.txt" | tr -s ' ' | paste -sd'|' -)"
  waitfor sleep 3 || true
done
