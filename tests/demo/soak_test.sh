#!/bin/bash
# Fault injection by killing (inside run_isolated.sh): the HHEA stack under supervisord with
# the simulated vehicle, driven to Driving; then SIGKILL of a service at a random time, one
# after another (can-rx, fsm, gpio, ecu-sim, can-tx in a random order, then iox-roudi;
# ROUNDS times), and:
#   - every killed service is running again with a new pid and beating;
#   - after the death of vcu-fsm, the FSM is in the state it was in before;
#   - while vcu-can-tx lives, the keep-alive and safety messages miss no cycle because
#     another service died (can-tx's own per-message `missed` counters do not move across a
#     kill; a kill whose restart took over 3 s is reported as a machine stall instead);
#   - the restart time (kill -> heartbeat of the new process) per kill, p50 and max;
#   - iox-roudi: supervisord restarts it, every iceoryx client (can-rx, can-tx, ecu-sim)
#     sees the new RouDi within a heartbeat and exits with code 75, supervisord starts it
#     again; vcu-fsm and vcu-gpio keep running (same pid); the vehicle is back in Driving
#     (after a FaultReset when the sim bus outage put the FSM into a fault state).
#   - vcu-hmi joins the kills when it is built (offscreen under supervisord).
#   soak_test.sh [ROUNDS] [SEED]      (ctest: 1 round; the long run: e.g. 20 rounds)
set -uo pipefail
rounds=${1:-1}; seed=${2:-$RANDOM}
NAME=soak
# shellcheck source=stack_lib.sh
. "$(dirname "$0")/stack_lib.sh"
RANDOM=$seed
echo "soak: seed $seed, $rounds round(s); logs $run"
drive

# can-tx's per-message missed-cycle counters of the keep-alive and safety messages
missed() { "$vcu" status --config "$config" --wait 1.2 --stats 2>/dev/null | grep '^vcu-can-tx' | grep -o 'tx\.\(S1_ES_PGN61427\|CCVS1_PGN65265\|HVESSC1_PGN6912\|CN_PGN61483\)\.missed=[0-9]*' | sort; }
baseline=$(missed)
echo "soak: can-tx missed counters before the kills: $(echo $baseline)"
times=(); ready_times=(); roudi_times=(); stalls=0
# supervisord counts a death within startsecs (3 s) of a start as a failed start and backs
# off (1 s, 2 s, 3 s, ... before the next try): a kill is aimed only at a process that
# supervisord already calls RUNNING, so the figures are restart times, not back-off times
wait_running() { for _ in $(seq 1 50); do ctl status "$1" | grep -q RUNNING && return 0; sleep 0.2; done; fail "$1 not RUNNING"; }
for round in $(seq 1 "$rounds"); do
  victims=(can-rx fsm gpio ecu-sim can-tx); [ "$hmi" = 1 ] && victims+=(hmi)
  order=$(printf '%s\n' "${victims[@]}" | awk -v s="$RANDOM" 'BEGIN{srand(s)} {print rand() "\t" $0}' | sort | cut -f2)
  for service in $order; do
    sleep "0.$(( RANDOM % 9 + 1 ))"
    before=$(state)
    [ "$service" != can-tx ] && baseline=$(missed)
    wait_running "$service"
    old=$(ctl pid "$service")
    [ "$old" -gt 0 ] 2>/dev/null || fail "$service has no pid"
    kill -KILL "$old"
    killed=$(date +%s%N)
    new=""
    for _ in $(seq 1 100); do  # supervisord restarts after ~1 s, the new one beats within its first second
      new=$(ctl pid "$service" 2>/dev/null)
      if [ -n "$new" ] && [ "$new" != "$old" ] && [ "$new" -gt 0 ] 2>/dev/null \
         && "$vcu" status --config "$config" --wait 1.1 2>/dev/null | grep -q "^vcu-$service *$new "; then
        break
      fi
      new=""
    done
    [ -n "$new" ] || fail "round $round: vcu-$service did not come back"
    ms=$(( ($(date +%s%N) - killed) / 1000000 ))
    times+=("$ms")
    # the restart itself: kill -> the new process's "ready" line (its own UTC time stamp)
    ready_at=$(grep -m1 "\[$new\]: ready (pid $new" "$run/$service.log" | cut -d' ' -f1)
    if [ -n "$ready_at" ]; then
      ready_ms=$(( ($(date -d "$ready_at" +%s%N) - killed) / 1000000 ))
      ready_times+=("$ready_ms")
    else
      ready_ms=$ms  # vcu-hmi logs through Qt, without the services' ready line: its heartbeat counts
    fi
    echo "soak: round $round: SIGKILL vcu-$service ($old) -> $new ready after $ready_ms ms, its heartbeat seen after $ms ms"
    if [ "$ms" -gt 3000 ]; then  # slow: show why (the run folder is in the sandbox's /tmp)
      echo "soak:   slow restart; supervisord: $(grep "'$service'\|: $service " "$run/supervisord.log" | tail -4 | cut -c12-23,29- | tr '\n' '|')"
      echo "soak:   vcu-$service log: $(tail -5 "$run/$service.log" | cut -c1-160 | tr '\n' '|')"
    fi
    if [ "$service" = fsm ]; then
      after=$(state)
      [ "$after" = "$before" ] || fail "the FSM was in '$before' and came back in '$after'"
      echo "soak:   vcu-fsm resumed '$after'"
    fi
    if [ "$service" != can-tx ]; then
      after=$(missed)
      if [ "$after" != "$baseline" ]; then
        # supervisord restarts after ~1 s and the new process beats within its first second:
        # a restart over 3 s means the whole machine stalled (seen once on this shared 2-core
        # VM: 4.5 s, with 7 S1_ES cycles missed), which no service's death explains
        if [ "$ready_ms" -gt 3000 ]; then
          echo "soak:   machine stall ($ready_ms ms restart): can-tx missed cycles not attributed to vcu-$service: $(echo $after)"
          stalls=$((stalls + 1))
        else
          fail "can-tx missed keep-alive/safety cycles while vcu-$service died: before $(echo $baseline), after $(echo $after)"
        fi
      fi
    fi
  done
  # ---- iox-roudi: the frame streams' broker, and on the simulated bus the bus itself
  sleep "0.$(( RANDOM % 9 + 1 ))"
  declare -A oldpid
  keepers=(fsm gpio); [ "$hmi" = 1 ] && keepers+=(hmi)   # no iceoryx client of theirs dies with RouDi
  for p in roudi can-rx can-tx ecu-sim "${keepers[@]}"; do wait_running "$p"; oldpid[$p]=$(ctl pid "$p"); done
  kill -KILL "${oldpid[roudi]}"
  killed=$(date +%s%N)
  back=""
  for _ in $(seq 1 60); do
    status=$("$vcu" status --config "$config" --wait 1.1 2>/dev/null)
    back=yes
    for p in roudi can-rx can-tx ecu-sim; do
      new=$(ctl pid "$p" 2>/dev/null)
      if [ -z "$new" ] || [ "$new" = "${oldpid[$p]}" ] || ! [ "$new" -gt 0 ] 2>/dev/null; then back=""; break; fi
      if [ "$p" != roudi ] && ! echo "$status" | grep -q "^vcu-$p *$new "; then back=""; break; fi
    done
    [ -n "$back" ] && break
  done
  [ -n "$back" ] || fail "round $round: after the death of iox-roudi not every iceoryx client came back: $(ctl status | tr '\n' '|')"
  ms=$(( ($(date +%s%N) - killed) / 1000000 ))
  roudi_times+=("$ms")
  for p in "${keepers[@]}"; do
    [ "$(ctl pid "$p")" = "${oldpid[$p]}" ] || fail "vcu-$p was restarted by the death of iox-roudi"
  done
  grep -q "iox-roudi was restarted" "$run/can-tx.log" || fail "vcu-can-tx's log does not say why it ended"
  echo "soak: round $round: SIGKILL iox-roudi (${oldpid[roudi]}) -> RouDi, can-rx, can-tx, ecu-sim restarted and beating after $ms ms; ${keepers[*]} kept their pids"
  # the sim bus was down while RouDi was: the vehicle may have left Driving
  landed=$(state)
  if [ "$landed" != Driving ]; then
    case "$landed" in
      Ready|Connecting\ Driving) ;;
      *) signal_set internal.operator.FaultReset 1
         wait_state Ready || fail "round $round: after the RouDi outage the FSM is in '$(state)' (was '$landed') and FaultReset did not bring it to Ready" ;;
    esac
    signal_set internal.operator.ConnectDriving 0
    signal_set internal.operator.ConnectDriving 1
    wait_state Driving || fail "round $round: not Driving again after the RouDi outage: $(state)"
  fi
  recovered=$(( ($(date +%s%N) - killed) / 1000000 ))
  if [ "$landed" = Driving ]; then
    echo "soak:   the FSM stayed in Driving through the outage (looked $recovered ms after the kill)"
  else
    echo "soak:   the FSM was in '$landed' after the outage; Driving again $recovered ms after the kill"
  fi
done

p50() { printf '%s\n' "$@" | sort -n | sed -n "$(( ($# + 1) / 2 ))p"; }
maximum() { printf '%s\n' "$@" | sort -n | tail -1; }
count=${#times[@]}
rmax=$(maximum "${roudi_times[@]}")
echo "soak: iox-roudi killed ${#roudi_times[@]} time(s): every iceoryx client restarted, max $rmax ms until all beat"
echo "soak: $count kills, every service back; restart (kill -> ready) p50 $(p50 "${ready_times[@]}") ms, max $(maximum "${ready_times[@]}") ms; its heartbeat seen by vcu status p50 $(p50 "${times[@]}") ms, max $(maximum "${times[@]}") ms; keep-alive and safety messages: no missed cycle attributable to a death ($stalls machine stall(s) seen)"
echo "soak: PASS"
