#!/bin/bash
# Tractor scenario "start" (config/tractor/README.md), inside run_isolated.sh: key on ->
# Connecting -> Ready with the BMS connected (both contactors closed), the main relay and the
# DC-DC on, the J1939-76 pair HVESSC1 accepted by the simulated BMS.
NAME=tractor_start
. "$(dirname "$0")/tractor_lib.sh"
up
wait_state Standby 5 || fail "not in Standby at start: '$(state)'"
# the BMS' first status frame may come a moment after the services beat (a loaded machine)
wait_bus BMS.HVESSS1.HS_HiUBusCnctnSts == 0 5 ||
  fail "the BMS is connected before the key (or silent): '$(bus BMS.HVESSS1.HS_HiUBusCnctnSts)'"
vset internal.gpio.sim.KeySwitch 1
wait_bus internal.input.Key == 1 3 || fail "the key switch input did not reach internal.input.Key"
wait_bus VCU.HVESSC1.HS_HiUBusCnctCmd == 1 3 || fail "HVESSC1 never asked to connect"
wait_state Ready 10 || fail "not Ready 10 s after key on: '$(state)'"
[ "$(bus BMS.HVESSS1.HS_HiUBusCnctnSts)" = 1 ] || fail "Ready but the BMS reports $(bus BMS.HVESSS1.HS_HiUBusCnctnSts), not connected (1)"
[ "$(bus BMS.HVESSS1.HS_HiUBusPosCntctrSts)" = 1 ] || fail "positive contactor not closed"
[ "$(bus BMS.HVESSS1.HS_HiUBusNegCntctrSts)" = 1 ] || fail "negative contactor not closed"
wait_bus internal.gpio.MainRelay == 1 2 || fail "the main relay output is not on"
wait_bus DCDC.DCDC_Status.DCDC_State == 1 2 || fail "the DC-DC does not run in Ready"
# the J1939-76 pair HVESSC1 (SHM, then the SDM 0.5 ms later) is accepted by the simulated BMS
sim=$("$vcu" status --config "$config" --wait 1.2 2>/dev/null | grep '^vcu-ecu-sim')
ok=$(grep -o 'vic_pairs_ok=[0-9]*' <<<"$sim" | cut -d= -f2)
refused=$(grep -o 'vic_pairs_refused=[0-9]*' <<<"$sim" | cut -d= -f2)
[ -n "$ok" ] && [ "$ok" -ge 5 ] || fail "the simulated BMS accepted ${ok:-no} J1939-76 pairs: $sim"
[ "$refused" = 0 ] || fail "the simulated BMS refused $refused J1939-76 pairs"
pass
