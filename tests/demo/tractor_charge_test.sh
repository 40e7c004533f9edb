#!/bin/bash
# Tractor scenario "charge" (config/tractor/README.md), inside run_isolated.sh: Ready ->
# Charge -> Charging; the simulated charger charges at the VCU's 30 A, the pack current turns
# negative and the SOC rises; Charge off -> Ready with the charger idle.
NAME=tractor_charge
. "$(dirname "$0")/tractor_lib.sh"
key_on
soc_before=$(bus BMS.HVESSD2.HS_FastUpdSOC)
[ -n "$soc_before" ] || fail "no SOC from the BMS"
vset internal.operator.Charge Charge
wait_state Charging 5 || fail "not Charging after Charge: '$(state)'"
wait_bus VCU.CHG_Command.ChargeEnable == 1 2 || fail "CHG_Command does not enable the charger"
wait_bus VCU.CHG_Command.MaxChargeCurrent == 30 2 || fail "CHG_Command does not allow 30 A"
wait_bus Charger.CHG_Status.ChargerState == 1 3 || fail "the charger does not charge"
wait_bus Charger.CHG_Status.ChargerOutputCurrent '>=' 25 6 || fail "the charger current did not reach 25 A: $(bus Charger.CHG_Status.ChargerOutputCurrent)"
wait_bus BMS.HVESSD1.HS_I '<' 0 2 || fail "the pack current is not negative (charging): $(bus BMS.HVESSD1.HS_I)"
wait_bus BMS.HVESSD2.HS_FastUpdSOC '>=' "$(awk -v s="$soc_before" 'BEGIN { print s + 0.1 }')" 8 ||
  fail "the SOC did not rise by 0.1 %: $soc_before -> $(bus BMS.HVESSD2.HS_FastUpdSOC)"
vset internal.operator.Charge Off
wait_state Ready 5 || fail "not back in Ready after Charge off: '$(state)'"
wait_bus Charger.CHG_Status.ChargerState == 0 3 || fail "the charger still charges in Ready"
pass
