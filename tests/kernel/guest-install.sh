#!/bin/bash
# Runs INSIDE the QEMU VM (started by run-vm.sh, ctest kernel_vm_install): installs the amd64
# Debian packages openvcu (+ openvcu-hmi when built) with dpkg -i and an offline
# `apt-get install -f`, checks the installed layout (docs/design/packaging.md), points the
# installed vehicle bus at vcan0, starts the installed units' own ExecStart lines as their
# User=/Group= (tests/kernel/unit_exec.py; the VM's PID 1 is not systemd) plus the simulated
# vehicle, drives Start -> Ready, stops, purges and checks that nothing is left but what
# Debian policy allows. The VM's root is a tmpfs overlay of the host's:
# nothing of this reaches the host.
#
#   guest-install.sh OUTDIR     (OUTDIR/guest.env: DEB_DIR=folder of the .deb files, SRC=source tree)
#
# Prints one "CHECK <name> PASS|FAIL: detail" line per step and a RESULT line; exit 0 when
# every check passed, 1 otherwise. A step that the later ones need ends the run (they are
# reported as not run). Logs (dpkg, apt, every service, vcu status) stay in OUTDIR.
set -uo pipefail

OUT=$1
# shellcheck disable=SC1091
. "$OUT/guest.env"   # DEB_DIR SRC
export PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin
export DEBIAN_FRONTEND=noninteractive
HERE=$SRC/tests/kernel
PY=/usr/bin/python3
CFG=/etc/openvcu/vehicle.json
pass=0; fail=0; failed=()
pids=(); names=()

t() { echo "T+$(cut -d' ' -f1 /proc/uptime)s $*"; }
result() { # name PASS|FAIL detail
  echo "CHECK $1 $2: $3"
  if [[ $2 == PASS ]]; then pass=$((pass + 1)); else fail=$((fail + 1)); failed+=("$1"); fi
}
finish() {
  echo "RESULT: $pass passed, $fail failed${failed[*]:+ (${failed[*]})}"
  [[ $fail == 0 ]]; exit
}
abort() { result "$1" FAIL "$2; the later steps need it: not run"; stop_services; finish; }
wait_for() { # SECONDS COMMAND...: retry every 0.2 s until the command succeeds
  local deadline=$(( $(date +%s%N) + ${1%.*} * 1000000000 )); shift
  until "$@"; do (( $(date +%s%N) < deadline )) || return 1; sleep 0.2; done
}
stop_services() { # SIGTERM to what we started, newest first (RouDi last), by PID
  local i
  for ((i = ${#pids[@]} - 1; i >= 0; i--)); do kill "${pids[$i]}" 2>/dev/null; done
  for pid in "${pids[@]}"; do wait "$pid" 2>/dev/null; done
  pids=(); names=()
}
trap stop_services EXIT
# apt offline: no package source at all (an empty sources list), so apt can only configure and
# remove what is installed, never fetch (and it skips parsing the host's index files: ~25 s per
# run under emulation); --no-download on top where it installs. A missing dependency fails as
# "not installable". The VM has no network device either (-nic none).
APT=(apt-get -o Dir::Etc::SourceList=/dev/null -o Dir::Etc::SourceParts=/nonexistent
     -o APT::Get::List-Cleanup=false -o Acquire::Retries=0 -o DPkg::Lock::Timeout=10)
# What the VM changed in its root: run-vm.sh shows the overlay's layers read-only under
# /run/vm-root (lower = the host's root, upper = every write since the boot). One line per
# changed path: "new PATH", "newdir PATH", "modified PATH" (a host file whose content, owner
# or mode differ; a copy-up alone, e.g. of a lock file, is no change) or
# "deleted PATH" (a whiteout: a host file removed). Folders only copied up for a change
# inside them are left out. Cheap: the upper layer holds only the changes (listing the
# whole root over 9p took 206 s under emulation).
changes() {
  $PY - <<'PYEOF' | LC_ALL=C sort
import filecmp, os, stat
upper, lower = "/run/vm-root/upper", "/run/vm-root/lower"
# logs, dpkg's, apt's and debconf's state: reported as written, not compared (apt's caches are
# large and the host's copy is read over 9p)
STATE = ("/var/log/", "/var/cache/apt/", "/var/cache/debconf/", "/var/lib/apt/", "/var/lib/dpkg/")
for root, dirs, files in os.walk(upper):
    for name in dirs + files:
        full = os.path.join(root, name)
        rel = full[len(upper):]
        st = os.lstat(full)
        if stat.S_ISCHR(st.st_mode) and st.st_rdev == 0:
            print("deleted", rel)
        elif stat.S_ISDIR(st.st_mode):
            if not os.path.lexists(lower + rel):
                print("newdir", rel)
        elif not os.path.lexists(lower + rel):
            print("new", rel)
        elif rel.startswith(STATE):
            print("modified", rel)
        else:   # copied up: a change only if the content, owner or mode differ from the host's
            low = os.lstat(lower + rel)
            same = (st.st_mode, st.st_uid, st.st_gid) == (low.st_mode, low.st_uid, low.st_gid)
            if same and stat.S_ISLNK(st.st_mode):
                same = os.readlink(full) == os.readlink(lower + rel)
            elif same and stat.S_ISREG(st.st_mode):
                same = st.st_size == low.st_size and filecmp.cmp(full, lower + rel, shallow=False)
            if not same:
                print("modified", rel)
PYEOF
}

t "guest start, kernel $(uname -r)"
[[ -e /dev/fd ]] || ln -s /proc/self/fd /dev/fd
ip route add 224.0.0.0/4 dev lo   # LCM multicast stays on loopback

# ---------------------------------------------------------------- 1. the packages, the root before
shopt -s nullglob
debs=("$DEB_DIR"/openvcu_*_amd64.deb); hmi=("$DEB_DIR"/openvcu-hmi_*_amd64.deb)
shopt -u nullglob
[[ ${#debs[@]} == 1 ]] || abort packages_found "expected one openvcu_*_amd64.deb in $DEB_DIR, found ${#debs[@]} (ctest fixture openvcu_debs: test package_build)"
[[ ${#hmi[@]} -le 1 ]] || abort packages_found "more than one openvcu-hmi_*_amd64.deb in $DEB_DIR"
debs+=("${hmi[@]}")
gr_before=$(getent group openvcu | cut -d: -f3)   # scripts/install-deps.sh makes the group on development hosts
pkgs=(openvcu); [[ ${#hmi[@]} == 1 ]] && pkgs=(openvcu-hmi openvcu)
[[ -d /run/vm-root/upper && -d /run/vm-root/lower/usr ]] || abort root_before "/run/vm-root/{lower,upper} missing (run-vm.sh shows the overlay's layers there)"
changes > /tmp/root-before.txt
dpkg-query -W -f='${Package}:${Architecture}=${Version} ${db:Status-Abbrev}\n' | LC_ALL=C sort > /tmp/dpkg-before.txt
if getent passwd openvcu >/dev/null || [[ -e /etc/openvcu || -e /var/lib/openvcu ]] || dpkg -s openvcu >/dev/null 2>&1; then
  abort root_before "the VM's root already has openvcu (user, /etc/openvcu, /var/lib/openvcu or the package): the host is not clean"
fi
result root_before PASS "$(grep -c . /tmp/root-before.txt) path(s) of the root changed since the boot (the overlay's upper layer) ($(tr '\n' ' ' < /tmp/root-before.txt)); no openvcu user, package, /etc/openvcu or /var/lib/openvcu${gr_before:+; group openvcu exists already (gid $gr_before)}; packages: ${debs[*]##*/}"

# ---------------------------------------------------------------- 2. dpkg -i, apt-get install -f offline
t "dpkg -i"
if dpkg -i "${debs[@]}" > "$OUT/dpkg-install.log" 2>&1; then dpkg_rc=0; else dpkg_rc=$?; fi
if [[ $dpkg_rc == 0 ]]; then
  result dpkg_install PASS "dpkg -i ${debs[*]##*/}: status 0"
else
  # missing dependencies leave the packages unconfigured: apt-get install -f settles that below
  result dpkg_install FAIL "dpkg -i status $dpkg_rc: $(grep -E 'depends on|error|Errors' "$OUT/dpkg-install.log" | head -5 | tr '\n' '|')"
fi
# simulate first: apt must neither download (the VM has no network) nor remove anything
"${APT[@]}" -s install -f > "$OUT/apt-simulate.log" 2>&1
sim_rc=$?
wants=$(grep -E '^(Inst|Remv|Purg) ' "$OUT/apt-simulate.log" | awk '{print $1, $2}' | tr '\n' ' ')
if [[ $sim_rc != 0 || -n $wants ]]; then
  abort apt_install_f "apt-get install -f would install or remove packages (needs a download or removal, the VM is offline): ${wants:-status $sim_rc: $(tail -3 "$OUT/apt-simulate.log" | tr '\n' '|')}"
fi
"${APT[@]}" install -f -y --no-download > "$OUT/apt-install.log" 2>&1
apt_rc=$?
states=$(dpkg-query -W -f='${Package}=${db:Status-Abbrev} ' "${pkgs[@]}" 2>&1)
audit=$(dpkg --audit 2>&1)
if [[ $apt_rc == 0 && $(grep -o '=ii ' <<< "$states" | wc -l) == "${#pkgs[@]}" && -z $audit ]]; then
  result apt_install_f PASS "apt-get install -f --no-download (offline): nothing to fetch or remove, status 0; $states; dpkg --audit clean"
else
  abort apt_install_f "apt-get install -f status $apt_rc, $states, audit: $(head -3 <<< "$audit" | tr '\n' '|')"
fi

# ---------------------------------------------------------------- 3. the system user, the layout
t "layout"
pw=$(getent passwd openvcu); gr=$(getent group openvcu)
IFS=: read -r _ _ uid gid _ home shell <<< "$pw"
state_dir=$(stat -c '%U:%G %a' /var/lib/openvcu 2>&1)
if [[ -n $pw && -n $gr && $uid -lt 1000 && $gid == "$(cut -d: -f3 <<< "$gr")" && $home == /var/lib/openvcu \
      && $state_dir == "openvcu:openvcu 750" ]]; then
  result system_user PASS "openvcu uid $uid gid $gid (system range), home $home, shell $shell; /var/lib/openvcu $state_dir"
else
  result system_user FAIL "passwd '$pw', group '$gr', /var/lib/openvcu '$state_dir' (want a system user+group openvcu, home /var/lib/openvcu owned openvcu:openvcu 0750)"
fi

missing=()
expect_exec() { [[ -x $1 && -f $1 ]] || missing+=("$1 (executable)"); }
expect_file() { [[ -f $1 && -s $1 ]] || missing+=("$1"); }
for b in vcu vcu-can-rx vcu-can-tx vcu-fsm vcu-gpio vcu-ecu-sim vcu-web vcu-telemetry; do expect_exec "/usr/bin/$b"; done
for u in openvcu.target openvcu-roudi.service openvcu-can-rx.service openvcu-can-tx.service openvcu-fsm.service \
         openvcu-gpio.service openvcu-web.service openvcu-ecu-sim.service openvcu-telemetry.service; do expect_file "/lib/systemd/system/$u"; done
for f in /usr/share/openvcu/vehicles/hhea/vehicle.json /usr/share/openvcu/vehicles/tractor/vehicle.json \
         /usr/share/openvcu/iceoryx/iox-roudi.sh /usr/share/openvcu/iceoryx/roudi.toml \
         /usr/share/openvcu/supervisor/openvcu.conf /lib/udev/rules.d/60-openvcu.rules \
         /usr/share/doc/openvcu/copyright /usr/share/doc/openvcu/changelog.Debian.gz \
         /etc/openvcu/openvcu.env "$CFG"; do expect_file "$f"; done
[[ -n $(find /usr/share/openvcu/www -type f 2>/dev/null | head -1) ]] || missing+=("/usr/share/openvcu/www/ (vcu-web's pages)")
if [[ ${#hmi[@]} == 1 ]]; then expect_exec /usr/bin/vcu-hmi; expect_file /lib/systemd/system/openvcu-hmi.service; fi
# conffiles: openvcu.env, vehicle.json and every file vehicle.json names (+ the dashboard), all in /etc/openvcu
named=$($PY - "$CFG" <<'PYEOF' 2>&1
import json, os, sys
config = json.load(open(sys.argv[1]))
names = list(config.get("dbc", [])) + [config[k] for k in ("schedule", "fsm", "gpio", "simulation", "diagnostics", "web", "telemetry", "receive", "safety") if isinstance(config.get(k), str)]
print(" ".join(os.path.join(os.path.dirname(sys.argv[1]), n) for n in names + ["dashboard.json"]))
link = [b["link"] for b in config["buses"] if b["name"] == "vehicle"]
print("LINK", link[0] if link else "none")
PYEOF
)
conffiles=$(dpkg-query -W -f='${Conffiles}\n' openvcu | awk 'NF {print $1}')
installed_link=$(awk '$1 == "LINK" {print $2}' <<< "$named")
for f in /etc/openvcu/openvcu.env "$CFG" $(grep -v '^LINK' <<< "$named"); do
  expect_file "$f"
  grep -qx "$f" <<< "$conffiles" || missing+=("$f (not a conffile)")
done
env_line=$(grep -E '^OPENVCU_CONFIG=' /etc/openvcu/openvcu.env 2>/dev/null)
[[ $env_line == "OPENVCU_CONFIG=$CFG" ]] || missing+=("openvcu.env: '$env_line' (want OPENVCU_CONFIG=$CFG)")
[[ $installed_link == socketcan:can0 ]] || missing+=("vehicle.json's vehicle bus '$installed_link' (want socketcan:can0)")
if [[ ${#missing[@]} == 0 ]]; then
  result installed_layout PASS "8 binaries in /usr/bin, 9 units in /lib/systemd/system, udev rule, docs, examples, supervisor profile, www; $(wc -l <<< "$conffiles") conffiles incl. openvcu.env and every file vehicle.json names; bus vehicle on $installed_link${hmi:+; vcu-hmi + its unit}"
else
  result installed_layout FAIL "missing or wrong: ${missing[*]}"
fi

# ---------------------------------------------------------------- 4. the bus on vcan0, as an engineer would
ip link add dev vcan0 type vcan && ip link set vcan0 up
# an engineer edits the installed conffile /etc/openvcu/vehicle.json: the vehicle bus's link
$PY - "$CFG" <<'PYEOF' > "$OUT/bus-edit.txt" 2>&1
import json, sys
path = sys.argv[1]
config = json.load(open(path))
bus = next(b for b in config["buses"] if b["name"] == "vehicle")
print("vehicle bus:", bus["link"], "-> socketcan:vcan0")
bus["link"] = "socketcan:vcan0"
with open(path, "w") as out:
    json.dump(config, out, indent=2)
    out.write("\n")
PYEOF
check_out=$(vcu check --config "$CFG" 2>&1); check_rc=$?
echo "$check_out" > "$OUT/vcu-check.txt"
if [[ $check_rc == 0 ]] && grep -q '"socketcan:vcan0"' "$CFG"; then
  result bus_on_vcan0 PASS "$(head -1 "$OUT/bus-edit.txt") in $CFG (python3 json); \`vcu check\` accepts it"
else
  abort bus_on_vcan0 "edit: $(tr '\n' '|' < "$OUT/bus-edit.txt"); vcu check status $check_rc: $(tail -3 <<< "$check_out" | tr '\n' '|')"
fi

# ---------------------------------------------------------------- 5. the services from the installed units
t "services"
# The units openvcu.target wants (its own Wants= line), RouDi first as its Before= says, then
# the simulated vehicle (openvcu-ecu-sim.service, installed but not enabled).
wanted=$(awk -F= '$1 == "Wants" {print $2}' /lib/systemd/system/openvcu.target)
units=(openvcu-roudi.service)
for u in $wanted; do [[ $u == openvcu-roudi.service ]] || units+=("$u"); done
units+=(openvcu-ecu-sim.service)
if ! $PY "$HERE/unit_exec.py" /tmp/units "${units[@]/#//lib/systemd/system/}" > "$OUT/units.txt" 2>&1; then
  abort services_started "unit_exec.py: $(tail -3 "$OUT/units.txt" | tr '\n' '|')"
fi
cp /tmp/units/*.sh "$OUT/" 2>/dev/null
start_unit() { # unit: its generated script in the background, its output in OUT/NAME.log
  local name=${1%.service}
  bash "/tmp/units/$name.sh" > "$OUT/$name.log" 2>&1 &
  pids+=($!); names+=("$name")
  [[ $name != openvcu-roudi ]] || wait_for 40 grep -q "RouDi is ready" "$OUT/$name.log"
}
t0=$(date +%s%N)
# RouDi first (the services' After=openvcu-roudi.service), then the others together, as systemd does
start_unit "${units[0]}" || abort services_started "${units[0]%.service} did not get ready ($(tail -3 "$OUT/${units[0]%.service}.log" | tr '\n' '|'))"
for u in "${units[@]:1}"; do start_unit "$u"; done
started=(); late=()
for u in "${units[@]}"; do
  name=${u%.service}; pattern=ready; [[ $name == openvcu-roudi ]] && pattern="RouDi is ready"
  if wait_for 60 grep -q "$pattern" "$OUT/$name.log"; then started+=("$name"); else late+=("$name: $(tail -3 "$OUT/$name.log" | tr '\n' '|')"); fi
done
[[ ${#late[@]} == 0 ]] || abort services_started "not ready within 60 s: ${late[*]}; ready: ${started[*]}"
ms=$(( ($(date +%s%N) - t0) / 1000000 ))
# each runs as its unit's User=/Group= (root when the unit names no user), from the installed
# binary; can-tx holds CAP_SYS_NICE (its unit's AmbientCapabilities)
who=(); bad=()
for i in "${!pids[@]}"; do
  # the generated script execs unshare, bash, env, setpriv, sh and the service: one PID
  pid=${pids[$i]}
  want=$(awk -v u="${names[$i]}:" '$1 == u {sub(",", "", $3); print $3}' "$OUT/units.txt")
  exe=$(tr '\0' '\n' < "/proc/$pid/cmdline" | head -1)
  user=$(ps -o user=,group= -p "$pid" | awk '{print $1 ":" $2}')
  capeff=$(awk '/^CapEff/ {print $2}' "/proc/$pid/status")
  who+=("${names[$i]#openvcu-}=$user:${exe##*/}:CapEff$capeff")
  # argv[0] an installed path, and the process image that very file
  [[ $user == "$want" && $exe == /usr/bin/* && /proc/$pid/exe -ef $exe ]] || bad+=("${names[$i]} runs '$exe' as '$user' (unit: '$want')")
done
if [[ ${#bad[@]} == 0 ]]; then
  result services_started PASS "${started[*]} ready in $ms ms from the units' ExecStart lines ($(tr '\n' ';' < "$OUT/units.txt")); processes: ${who[*]}"
else
  abort services_started "${bad[*]}; processes: ${who[*]}"
fi

# ---------------------------------------------------------------- 6. Start -> Ready
t "Start"
# state indexes from the installed FSM file (the one vehicle.json names), looked up
fsm_file=$($PY -c "import json,os,sys; c=json.load(open(sys.argv[1])); print(os.path.join(os.path.dirname(sys.argv[1]), c['fsm']))" "$CFG")
declare -A STATE
while IFS='=' read -r name index; do STATE[$name]=$index; done < <($PY -c "import json,sys
for i, x in enumerate(json.load(open(sys.argv[1]))['states']): print('%s=%d' % (x['name'], i))" "$fsm_file")
state() { vcu signal get internal.fsm.state --config "$CFG" 2>&1 | awk '$1 == "bus" {print $2; exit}'; }
state_is() { [[ "$(state)" == "${STATE[$1]}" ]]; }
if ! wait_for 15 state_is Standby; then
  abort start_ready "the FSM is not in Standby (${STATE[Standby]:-?}) after the start: state $(state)"
fi
t0=$(date +%s%N)
set_out=$(vcu signal set internal.operator.StartStop Start --config "$CFG" 2>&1); set_rc=$?
if [[ $set_rc == 0 ]] && wait_for 40 state_is Ready; then
  result start_ready PASS "as root: vcu signal set internal.operator.StartStop Start -> internal.fsm.state ${STATE[Ready]} (Ready, index from $fsm_file) after $(( ($(date +%s%N) - t0) / 1000000 )) ms"
else
  result start_ready FAIL "set status $set_rc ($set_out); state $(state), want ${STATE[Ready]} (Ready)"
fi

# ---------------------------------------------------------------- 7. vcu status names the services
vcu status --config "$CFG" > "$OUT/status.txt" 2>&1; status_rc=$?
# every service we started is listed with the very PID we started (the status text is free:
# vcu-gpio shows its back end), RouDi is no openvcu service
absent=(); listed=()
for i in "${!pids[@]}"; do
  [[ ${names[$i]} == openvcu-roudi ]] && continue
  svc=vcu-${names[$i]#openvcu-}
  shown=$(awk -v s="$svc" '$1 == s {print $2; exit}' "$OUT/status.txt")
  if [[ $shown == "${pids[$i]}" ]]; then listed+=("$svc=$shown"); else absent+=("$svc (pid ${pids[$i]}, shown '${shown}')"); fi
done
if [[ $status_rc == 0 && ${#absent[@]} == 0 ]]; then
  result vcu_status PASS "vcu status (status 0) lists each started service with its PID: ${listed[*]}"
else
  result vcu_status FAIL "status $status_rc, missing or another PID: ${absent[*]}; $(head -8 "$OUT/status.txt" | cut -c1-60 | tr '\n' '|')"
fi

# ---------------------------------------------------------------- 8. a member of group openvcu commands Stop
# an operator account in group openvcu (not root): the group is what lets people use the stack
adduser --system --no-create-home --group operator1 > "$OUT/operator.log" 2>&1
adduser operator1 openvcu >> "$OUT/operator.log" 2>&1
op_out=$(setpriv --reuid=operator1 --regid=operator1 --init-groups -- env -i PATH="$PATH" HOME=/ \
           vcu signal set internal.operator.StartStop Stop --config "$CFG" 2>&1); op_rc=$?
if [[ $op_rc == 0 ]] && wait_for 40 state_is Standby; then
  result group_member_stop PASS "user operator1 (groups: $(id -Gn operator1)): vcu signal set internal.operator.StartStop Stop -> Standby (${STATE[Standby]})"
else
  result group_member_stop FAIL "user operator1 (groups: $(id -Gn operator1)): status $op_rc ($(tr '\n' '|' <<< "$op_out")); state $(state), want ${STATE[Standby]} (Standby)"
fi
deluser --system operator1 >> "$OUT/operator.log" 2>&1; delgroup --system operator1 >> "$OUT/operator.log" 2>&1

# ---------------------------------------------------------------- 9. stop
t "stop"
t0=$(date +%s%N)
still=(); codes=()
for ((i = ${#pids[@]} - 1; i >= 0; i--)); do kill "${pids[$i]}" 2>/dev/null; wait "${pids[$i]}"; codes+=("${names[$i]#openvcu-}=$?"); done
pids=(); names=()
# every started process was waited for; a process of the user outside them (a child that
# outlived its service) gets 3 s to end before it counts as left behind
no_stack_process() { ! pgrep -u openvcu >/dev/null; }
wait_for 3 no_stack_process || true
mapfile -t still < <(pgrep -u openvcu -a)
if [[ ${#still[@]} == 0 ]]; then
  result services_stopped PASS "SIGTERM, newest first: exit codes ${codes[*]} in $(( ($(date +%s%N) - t0) / 1000000 )) ms; no process of user openvcu left"
else
  result services_stopped FAIL "still running as openvcu: ${still[*]}; exit codes ${codes[*]}"
  kill -KILL $(pgrep -u openvcu)   # by PID: the VM's processes of that user, before the purge
fi

# ---------------------------------------------------------------- 10. apt-get purge
t "purge"
for p in "${pkgs[@]}"; do dpkg -L "$p"; done | LC_ALL=C sort -u > "$OUT/package-files.txt"
"${APT[@]}" purge -y "${pkgs[@]}" > "$OUT/apt-purge.log" 2>&1; purge_rc=$?
removed=$(grep -E '^(Removing|Purging) ' "$OUT/apt-purge.log" | tr '\n' '|')
left=$(dpkg-query -W -f='${Package}=${db:Status-Abbrev} ' "${pkgs[@]}" 2>/dev/null)
# apt must remove these packages and nothing else
others=$(grep -E '^(Removing|Purging configuration files for) ' "$OUT/apt-purge.log" | grep -vE "^(Removing|Purging configuration files for) ($(IFS='|'; echo "${pkgs[*]}")) " | tr '\n' '|')
if [[ $purge_rc == 0 && ! $left =~ =(ii|rc|iU|iF|iH) && -z $others ]]; then
  result apt_purge PASS "apt-get purge -y ${pkgs[*]}: status 0, $removed; dpkg: ${left:-no record}"
else
  result apt_purge FAIL "status $purge_rc; $removed; other packages: ${others:-none}; dpkg: $left; $(tail -3 "$OUT/apt-purge.log" | tr '\n' '|')"
fi

# ---------------------------------------------------------------- 11. nothing of the packages left
# a path of dpkg -L may stay only when the host has it too (a shared folder such as /usr/bin)
leftover=()
while read -r f; do
  [[ -e $f || -L $f ]] || continue
  [[ -d $f && -d /run/vm-root/lower$f ]] && continue   # -d follows /lib -> usr/lib (merged /usr)
  leftover+=("$f")
done < "$OUT/package-files.txt"
gone=()
for d in /etc/openvcu /var/lib/openvcu; do [[ -e $d ]] && gone+=("$d still there"); done
if [[ ${#leftover[@]} == 0 && ${#gone[@]} == 0 ]]; then
  result package_files_gone PASS "none of the $(wc -l < "$OUT/package-files.txt") paths of dpkg -L remains (shared folders that were there before stay); /etc/openvcu and /var/lib/openvcu gone"
else
  result package_files_gone FAIL "${gone[*]} ${leftover[*]:0:15}"
fi

# ---------------------------------------------------------------- 12. the root after = before, but for policy
t "root comparison"
changes > /tmp/root-after.txt
comm -13 /tmp/root-before.txt /tmp/root-after.txt > "$OUT/root-changes.txt"
# What policy allows to stay changed: the system user and group openvcu (the account files and
# adduser's backups of them); the logs, dpkg's database and apt's and debconf's state and caches.
# Everything else (a new or modified file, a new folder, a deleted host file) is a leftover.
allowed='^(modified|new) /etc/(passwd|group|shadow|gshadow)-?$|^[a-z]+ /var/(log|cache/apt|cache/debconf|lib/apt|lib/dpkg)/'
extra=$(grep -Ev "$allowed" "$OUT/root-changes.txt")
# dpkg's own records of the packages must be gone too
records=$(grep -E "^new /var/lib/dpkg/info/($(IFS='|'; echo "${pkgs[*]}"))[.:]" "$OUT/root-changes.txt")
# dpkg's database lists the same packages, versions and states as before the install
dpkg-query -W -f='${Package}:${Architecture}=${Version} ${db:Status-Abbrev}\n' | LC_ALL=C sort > /tmp/dpkg-after.txt
dpkg_diff=$(diff /tmp/dpkg-before.txt /tmp/dpkg-after.txt | grep '^[<>]' | sed 's/^/dpkg database: /')
user_left=$(getent passwd openvcu)
accounts=$(grep -E '^(modified|new) /etc/' "$OUT/root-changes.txt" | awk '{print $2}' | tr '\n' ' ')
if [[ -z $extra && -z $records && -z $dpkg_diff ]]; then
  result root_after_purge PASS "changed since the boot, beyond what was before the install: $(grep -c . "$OUT/root-changes.txt") path(s), all allowed: account files ${accounts:-none} (the system user stays, Debian practice: ${user_left:-none}), plus $(grep -cE ' /var/' "$OUT/root-changes.txt") in logs and dpkg/apt/debconf state; no package record left in /var/lib/dpkg/info; dpkg's package list ($(wc -l < /tmp/dpkg-after.txt) packages) as before"
else
  result root_after_purge FAIL "left behind: $(printf '%s\n' "$extra" "$records" "$dpkg_diff" | grep . | head -15 | tr '\n' ' ') (all: root-changes.txt)"
fi

t "checks done"
finish
