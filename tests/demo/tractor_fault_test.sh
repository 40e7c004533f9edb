#!/bin/bash
# Tractor scenario "fault" (config/tractor/README.md), inside run_isolated.sh: in Ready the
# simulated BMS reports an isolation fault (`vcu sim fault bms_isolation on`) -> Fault; the
# VCU asks to disconnect and the contactors open; a reset while the fault is active is
# refused; with the fault gone the reset leads back through Standby to Ready. Then the
# traction inverter faults (state 15 and a DM1 with the red stop lamp) and the BMS falls
# silent (receive timeout), then the e-stop line goes low: each -> Fault, each cleared and
# reset -> Ready (a reset with the e-stop still pressed is refused).
NAME=tractor_fault
. "$(dirname "$0")/tractor_lib.sh"
key_on
sim_fault bms_isolation on
wait_state Fault 3 || fail "not in Fault after the isolation fault: '$(state)'"
wait_bus VCU.HVESSC1.HS_HiUBusCnctCmd == 0 2 || fail "HVESSC1 does not ask to disconnect in Fault"
wait_bus BMS.HVESSS1.HS_HiUBusPosCntctrSts == 0 3 || fail "the positive contactor did not open"
wait_bus BMS.HVESSS1.HS_HiUBusNegCntctrSts == 0 3 || fail "the negative contactor did not open"
wait_bus BMS.HVESSS1.HS_HiUBusCnctnSts == 0 3 || fail "the BMS still reports the bus connected"
vset internal.operator.FaultReset 1
wait_eff internal.operator.FaultReset == 0 3 || fail "the FSM did not consume the reset"
[ "$(state)" = Fault ] || fail "a reset with the isolation fault still active left Fault: '$(state)'"
sim_fault bms_isolation off
wait_bus BMS.HVESSS1.HS_HiUBusPasIslnTestSts == 1 3 || fail "the BMS still reports the isolation fault after it was cleared"
vset internal.operator.FaultReset 1
wait_state Ready 10 || fail "not back in Ready after the fault cleared and the reset: '$(state)'"
[ "$(bus BMS.HVESSS1.HS_HiUBusCnctnSts)" = 1 ] || fail "Ready again but the BMS is not connected"

sim_fault inverter_fault on
wait_state Fault 3 || fail "not in Fault after the inverter fault: '$(state)'"
wait_bus internal.dm1.TractionInverter.redStopLamp == 1 3 || fail "the inverter's DM1 red stop lamp was not decoded"
wait_bus BMS.HVESSS1.HS_HiUBusCnctnSts == 0 3 || fail "the HV bus was not disconnected on the inverter fault"
sim_fault inverter_fault off
wait_bus internal.dm1.TractionInverter.redStopLamp == 0 3 || fail "the inverter's DM1 still shows the red stop lamp"
vset internal.operator.FaultReset 1
wait_state Ready 10 || fail "not back in Ready after the inverter fault and the reset: '$(state)'"

sim_fault silent.BMS on
wait_state Fault 4 || fail "not in Fault 4 s after the BMS fell silent: '$(state)'"
sim_fault silent.BMS off
wait_bus BMS.HVESSS1.HS_HiUBusCnctnSts == 0 3 || fail "the BMS did not come back after its silence"
vset internal.operator.FaultReset 1
wait_state Ready 10 || fail "not back in Ready after the BMS timeout and the reset: '$(state)'"

vset internal.gpio.sim.EStop 0
wait_state Fault 3 || fail "not in Fault after the e-stop line went low: '$(state)'"
wait_bus internal.input.EStop == 1 1 || fail "the e-stop input does not read pressed"
vset internal.operator.FaultReset 1
wait_eff internal.operator.FaultReset == 0 3 || fail "the FSM did not consume the reset"
[ "$(state)" = Fault ] || fail "a reset with the e-stop pressed left Fault: '$(state)'"
vset internal.gpio.sim.EStop 1
wait_bus internal.input.EStop == 0 1 || fail "the e-stop input does not read released"
vset internal.operator.FaultReset 1
wait_state Ready 10 || fail "not back in Ready after the e-stop was released and reset: '$(state)'"
pass
