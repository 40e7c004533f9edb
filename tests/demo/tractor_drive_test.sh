#!/bin/bash
# Tractor scenario "drive" (config/tractor/README.md), inside run_isolated.sh: Ready -> Drive
# with the hand throttle at 1200 rpm -> Driving; TSC1 speed control reaches the simulated
# traction inverter and its EEC1 speed follows; the set button brings it to 600 rpm; Drive off
# -> Ready with the request back to 0.
NAME=tractor_drive
. "$(dirname "$0")/tractor_lib.sh"
key_on
vset internal.operator.SpeedRequest 1200
vset internal.operator.Drive Drive
wait_state Driving 5 || fail "not Driving after Drive: '$(state)'"
wait_bus VCU.TSC1_TractionInv.OverrideControlMode == 1 2 || fail "TSC1 is not in speed control"
wait_bus VCU.TSC1_TractionInv.RequestedSpeed == 1200 2 || fail "TSC1 does not request 1200 rpm: $(bus VCU.TSC1_TractionInv.RequestedSpeed)"
wait_bus TractionInverter.TI_Status.InverterState == 3 3 || fail "the traction inverter does not run"
wait_bus TractionInverter.EEC1_TractionInv.EngineSpeed '>=' 1100 5 || fail "the motor speed did not follow to 1200 rpm: $(bus TractionInverter.EEC1_TractionInv.EngineSpeed)"
wait_bus PumpInverter.PUMP_Status.PumpSpeed '>=' 1400 5 || fail "the hydraulic pump did not reach 1500 rpm"
[ "$(bus VCU.CCVS1.ParkingBrakeSwitch)" = 0 ] || fail "the parking brake is still set while driving"
vset internal.operator.SpeedRequest 600
vset internal.operator.SpeedSet Set
wait_bus VCU.TSC1_TractionInv.RequestedSpeed == 600 2 || fail "the set button did not send 600 rpm"
wait_bus TractionInverter.EEC1_TractionInv.EngineSpeed '<=' 700 5 || fail "the motor speed did not follow down to 600 rpm: $(bus TractionInverter.EEC1_TractionInv.EngineSpeed)"
[ "$(state)" = Driving ] || fail "left Driving on a speed change: '$(state)'"
vset internal.operator.Drive Off
wait_state Ready 5 || fail "not back in Ready after Drive off: '$(state)'"
wait_bus VCU.TSC1_TractionInv.OverrideControlMode == 0 2 || fail "TSC1 still in speed control in Ready"
wait_bus TractionInverter.EEC1_TractionInv.EngineSpeed '<=' 100 5 || fail "the motor did not stop"
pass
