#!/usr/bin/env bash
# ./run.sh --fleet N, once run.sh has built the programs and (with --isolated) entered the
# sandbox: a local mosquitto on 127.0.0.1:1883 and N simulated vehicles of one configuration
# under one supervisord (one iox-roudi). Vehicle NN is a copy of the configuration's folder in
# the run folder (vehicle-NN/) with the instance <instance>-NN, and its telemetry.json sending
# to that broker as vehicle id <instance>-NN, its queue in vehicle-NN/queue; each runs the whole
# stack (can-rx, can-tx, fsm, gpio, ecu-sim) and vcu-telemetry. HHEA vehicles are started
# (operator StartStop), the second also connects Driving, so that the states differ. Then
# `vcu fleet watch --broker mqtt://127.0.0.1:1883` until Ctrl-C or the end of SECONDS, and
# everything stops, shared memory removed.
#   scripts/run-fleet.sh N VEHICLE_JSON HEADLESS(0|1) [SECONDS]
# Called by run.sh (which passes OPENVCU_BIN, and OPENVCU_LOG_DIR under --isolated); not meant
# to be called alone (it neither installs nor builds).
set -euo pipefail
root=$(dirname "$(dirname "$(readlink -f "$0")")")
count=${1:?vehicles}; config=${2:?vehicle.json}; headless=${3:?0 or 1}; seconds=${4:-}
bin=${OPENVCU_BIN:-$root/build/bin}
vcu=$bin/vcu
broker=mqtt://127.0.0.1:1883
cd "$root"

[ -x /usr/sbin/mosquitto ] || { echo "run.sh: --fleet needs mosquitto (Debian's mosquitto; scripts/install-deps.sh)" >&2; exit 1; }
[ -x "$bin/vcu-telemetry" ] || { echo "run.sh: --fleet needs $bin/vcu-telemetry (cmake --build build --target vcu-telemetry)" >&2; exit 1; }
echo "== configuration $config (a fleet of $count)"
"$vcu" check -q --config "$config" >/dev/null || { echo "run.sh: the configuration has errors (above)" >&2; exit 1; }
if (exec 3<>/dev/tcp/127.0.0.1/1883) 2>/dev/null; then
  echo "run.sh: 127.0.0.1:1883 is taken (a broker of this machine?): stop it, or run with --isolated" >&2; exit 1
fi

run=${OPENVCU_LOG_DIR:-$(mktemp -d "${TMPDIR:-/tmp}/openvcu-run.XXXXXX")}
is_root=0; [ "$(id -u)" = 0 ] && is_root=1
# The vehicles' folders, mosquitto.conf and the supervisord profile (from config/supervisor/
# openvcu.conf: roudi once, the vehicle programs once per vehicle, telemetry on, hmi and web
# off). Prints the instances, one a line.
mapfile -t instances < <(python3 - "$config" "$run" "$count" "$is_root" "$bin" <<'PY'
import configparser, json, os, shutil, sys
config, run, count, is_root, binary = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4] == "1", sys.argv[5]
source = os.path.dirname(config)
base = json.load(open(config))
with open(os.path.join(run, "mosquitto.conf"), "w") as out:
    out.write("# the fleet's broker (run.sh --fleet): loopback only, anonymous, nothing kept on disk\n"
              "listener 1883 127.0.0.1\nallow_anonymous true\npersistence false\nlog_dest stdout\n"
              + ("user root\n" if is_root else ""))
profile = configparser.RawConfigParser()
profile.optionxform = str
profile.read(os.path.join("config", "supervisor", "openvcu.conf"))
fleet = configparser.RawConfigParser()
fleet.optionxform = str
for section in ("supervisord", "unix_http_server", "rpcinterface:supervisor", "supervisorctl", "program:roudi"):
    fleet[section] = dict(profile[section])
if is_root:
    fleet["supervisord"]["user"] = "root"
fleet["program:mosquitto"] = {
    "command": "/usr/sbin/mosquitto -c " + os.path.join(run, "mosquitto.conf"), "priority": "2", "autorestart": "true",
    "startsecs": "1", "stopsignal": "TERM", "stopwaitsecs": "5",
    "stdout_logfile": "%(ENV_OPENVCU_RUN)s/mosquitto.log", "redirect_stderr": "true"}
for number in range(1, count + 1):
    name = "%s-%02d" % (base["instance"], number)
    folder = os.path.join(run, "vehicle-%02d" % number)
    shutil.copytree(source, folder, ignore=shutil.ignore_patterns(".run-*"))
    vehicle = json.load(open(config))
    vehicle["instance"] = name
    telemetry_name = vehicle.get("telemetry", "telemetry.json")
    telemetry_path = os.path.join(folder, telemetry_name)
    telemetry = json.load(open(telemetry_path)) if "telemetry" in vehicle else {"signals": []}
    vehicle["telemetry"] = telemetry_name
    queue = os.path.join(folder, "queue")
    telemetry.update({"broker": "mqtt://127.0.0.1:1883", "vehicleId": name, "queueFolder": queue})
    json.dump(telemetry, open(telemetry_path, "w"), indent=2)
    vehicle_path = os.path.join(folder, os.path.basename(config))
    json.dump(vehicle, open(vehicle_path, "w"), indent=2)
    for program in ("can-rx", "can-tx", "fsm", "gpio", "ecu-sim", "telemetry"):
        section = dict(profile["program:" + program])
        command = section["command"].replace("%(ENV_OPENVCU_CONFIG)s", vehicle_path)
        section["command"] = command.replace("%(ENV_OPENVCU_RUN)s/telemetry-queue", queue)
        section["autostart"] = "true"
        section["stdout_logfile"] = "%%(ENV_OPENVCU_RUN)s/%s-%02d.log" % (program, number)
        fleet["program:%s-%02d" % (program, number)] = section
    print(name)
with open(os.path.join(run, "openvcu.conf"), "w") as out:
    out.write("; generated by run.sh --fleet from config/supervisor/openvcu.conf\n")
    fleet.write(out)
PY
)
export OPENVCU_BIN=$bin OPENVCU_RUN=$run OPENVCU_ROUDI=$root/config/iceoryx/iox-roudi.sh OPENVCU_CONFIG=$config
echo "== starting mosquitto ($broker) and ${#instances[@]} vehicles under supervisord (logs: $run): ${instances[*]}"

# Stopping: as run.sh (SIGPIPE ignored, supervisord's output to its own file, further signals
# ignored while supervisord stops every program).
trap '' PIPE
say() { echo "$@" 2>/dev/null || true; }
supervisord -n -c "$run/openvcu.conf" >"$run/supervisord.out" 2>&1 &
supervisor=$!
driver=""; roudi=""; helper=""
stopped=0
stop() {
  [ $stopped -eq 1 ] && return
  stopped=1
  trap '' INT TERM
  set +e
  say "== stopping"
  if [ -n "$helper" ]; then kill -TERM "$helper" 2>/dev/null; wait "$helper" 2>/dev/null; fi
  if [ -n "$driver" ]; then pkill -TERM -P "$driver" 2>/dev/null; kill -TERM "$driver" 2>/dev/null; wait "$driver" 2>/dev/null; fi
  supervisorctl -c "$run/openvcu.conf" shutdown >/dev/null 2>&1 || kill -TERM "$supervisor" 2>/dev/null || true
  wait "$supervisor" 2>/dev/null || true
  if [ -n "$roudi" ] && kill -0 "$roudi" 2>/dev/null; then
    kill -TERM "$roudi" 2>/dev/null
    for _ in $(seq 1 50); do kill -0 "$roudi" 2>/dev/null || break; sleep 0.1; done
  fi
  for instance in "${instances[@]}"; do rm -f "/dev/shm/openvcu-$instance" "/dev/shm/openvcu-$instance.lock"; done
  say "== stopped; logs in $run"
}
trap stop EXIT
trap 'exit 130' INT
trap 'exit 143' TERM
# as run.sh: a command in the background, so that a SIGINT meanwhile runs the trap at once
waitfor() {
  "$@" &
  helper=$!
  local status=0
  wait "$helper" || status=$?
  helper=""
  return $status
}

# up when every vehicle's services beat (can-rx, can-tx, fsm, gpio, ecu-sim, telemetry)
for number in $(seq 1 "${#instances[@]}"); do
  vehicle=$run/vehicle-$(printf %02d "$number")/$(basename "$config")
  beating=0
  for _ in $(seq 1 30); do
    waitfor "$vcu" status --config "$vehicle" --wait 1 >"$run/status.txt" 2>/dev/null || true
    beating=$(grep -c '^vcu-' "$run/status.txt" || true)
    [ "$beating" -ge 6 ] && break
  done
  say "== ${instances[number - 1]}: $beating service(s) beating"
done
roudi=$(supervisorctl -c "$run/openvcu.conf" pid roudi 2>/dev/null || true)
[[ "$roudi" =~ ^[1-9][0-9]*$ ]] || roudi=""
deadline=""
[ -n "$seconds" ] && deadline=$(( $(date +%s) + seconds ))

# HHEA: the operator's Start on every vehicle, Connect Driving on the second, once the watch
# below has subscribed (the state messages are not retained: it sees the transitions as they go)
drive() {
  sleep 2
  local number vehicle
  for number in $(seq 1 "${#instances[@]}"); do
    vehicle=$run/vehicle-$(printf %02d "$number")/$(basename "$config")
    "$vcu" signal set --config "$vehicle" internal.operator.StartStop Start >/dev/null || true
  done
  [ "${#instances[@]}" -ge 2 ] || return 0
  sleep 5
  "$vcu" signal set --config "$run/vehicle-02/$(basename "$config")" internal.operator.ConnectDriving 1 >/dev/null || true
}
if [ "$(realpath -m -- "$config")" = "$root/config/hhea/vehicle.json" ]; then drive & driver=$!; fi

watch=("$vcu" fleet watch --broker "$broker")
left=""
if [ -n "$deadline" ]; then
  left=$(( deadline - $(date +%s) ))
  [ "$left" -ge 1 ] || left=1
  watch+=(--for "$left")
fi
if [ "$headless" -eq 0 ] && [ -t 1 ]; then
  "${watch[@]}" || true  # it handles Ctrl-C itself and returns
else
  waitfor "${watch[@]}" || true
fi
