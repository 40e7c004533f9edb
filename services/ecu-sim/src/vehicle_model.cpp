#include "vehicle_model.hpp"

#include <algorithm>
#include <cmath>

#include "openvcu/j1939/time_date.hpp"

namespace openvcu::ecusim {
namespace {

constexpr std::string_view FAULT_NAMES[FAULT_COUNT] = {"battery", "isolation",    "contactor_stuck", "pdu",
                                                       "hvlp",    "hvlp_shutdown", "editron",        "obc",
                                                       "soc_low", "soc_high", "shm_expectation"};
// HS_HiUBusCnctnSts
constexpr int AWAITING = 0, CONNECTED = 1, CONNECTING = 2, DISCONNECTING = 3, CHARGING = 5, FAULTED = 14;
/// Largest |Time/Date - system clock| accepted as a correct answer (the wire has 0.25 s steps).
constexpr std::int64_t TIME_TOLERANCE_S = 2;

}  // namespace

std::string_view faultName(Fault fault) noexcept { return FAULT_NAMES[static_cast<std::size_t>(fault)]; }

std::optional<Fault> faultByName(std::string_view name) noexcept {
  for (std::size_t i = 0; i < FAULT_COUNT; ++i) {
    if (FAULT_NAMES[i] == name) return static_cast<Fault>(i);
  }
  return std::nullopt;
}

Result<VehicleModel> VehicleModel::create(VirtualBus& bus, const config::SimConfig& config) {
  VehicleModel model(bus, config);
  if (Status resolved = model.resolve(); !resolved) return resolved.error();
  bus.setSilent("VIC", true);  // asleep until the keep-alive (and the wake signal) come
  model.m_soc = config.initialSoc;
  model.m_socBeforeLow = config.initialSoc;
  return model;
}

Status VehicleModel::resolve() {
  Status status;
  const auto in = [&](const char* message, const char* signal, bridge::SignalRef& target) {
    auto ref = m_bus->input(message, signal);
    if (!ref) {
      if (status) status = Error{"simulated vehicle: " + ref.error().message};
      return;
    }
    target = *ref;
  };
  const auto out = [&](const std::string& message, const char* signal, bridge::SignalRef& target) {
    auto ref = m_bus->output(message, signal);
    if (!ref) {
      if (status) status = Error{"simulated vehicle: " + ref.error().message};
      return;
    }
    target = *ref;
  };
  in("S1_ES_PGN61427", "Control_Es_Relay", m_esRelay);
  in("HVESSC1_PGN6912", "HS_OperConsent", m_consent);
  in("CCVS1_PGN65265", "Wheel_Based_Veh_Spd", m_ccvsAny);
  in("HVESSC1_PGN6912", "HS_HiUBusCnctCmd", m_hvesscAny);
  in("CN_PGN61483", "Crash_Typ", m_crashType);
  in("PDU_Rx_1", "Close_GroupA_Contactors", m_contactorA);
  in("PDU_Rx_1", "Close_GroupB_Contactors", m_contactorB);
  in("BMS", "BMS_Control", m_bmsControl);
  in("BMS", "BMS_Max_Current", m_bmsMaxCurrent);
  in("BMS", "BMS_Max_Voltage", m_bmsMaxVoltage);
  in("VCU", "VCU_DCDC_Command", m_dcdcCommand);
  in("VCU", "VCU_DCDC_SetV", m_dcdcSetV);
  in("VCU", "VCU_DCDC_MaxI", m_dcdcMaxI);
  in("CMD_MOT_0", "cmd_mot_request", m_motRequest);
  in("CMD_MOT_2", "cmd_mot_n_ref", m_motSpeedRef);
  in("RQST_ES_PGN59904", "RQST_PGN", m_rqstPgn);
  out("HVESSS1_PGN61590", "HS_HiUBusCnctnSts", m_cnctnSts);
  out("HVESSS1_PGN61590", "HS_OperationalSts", m_operSts);
  out("HVESSS1_PGN61590", "HS_HiUBusPosCntctrSts", m_posCntctr);
  out("HVESSS1_PGN61590", "HS_HiUBusNegCntctrSts", m_negCntctr);
  out("HVESSS1_PGN61590", "PermissionToClose", m_permission);
  out("HVESSS1_PGN61590", "HS_IntChrgrSts", m_intChrgr);
  out("HVESSS1_PGN61590", "HS_HVILSts", m_hvil);
  out("HVESSS1_PGN61590", "HS_HiUBusPasIslnTestSts", m_pasIsln);
  out("HVESSS1_PGN61590", "HS_SOCSts", m_socSts);
  out("HVESSD1_PGN61584", "HS_ULvl", m_uLvl);
  out("HVESSD1_PGN61584", "HS_I", m_currentOut);
  out("HVESSD1_PGN61584", "HS_AvlChPwr", m_avlCh);
  out("HVESSD1_PGN61584", "HS_AvlDchaPwr", m_avlDcha);
  out("HVESSD2_PGN61585", "HS_FastUpdSOC", m_socOut);
  out("PropA_C3_PGN61184", "UChLimLong", m_uChLim);
  out("PropA_C3_PGN61184", "IChLimLong", m_iChLim);
  out("HVESSHIST_PGN64606", "HS_StofHealth", m_soh);
  out("RQST_VIC_PGN59904", "RQST_VIC_PGN", m_rqstVic);
  out("PDU_Tx_1", "byPDU_Status", m_pduStatus);
  out("PDU_Tx_1", "GroupA_Contactors_State", m_groupA);
  out("PDU_Tx_1", "GroupB_Contactors_State", m_groupB);
  out("PDU_Tx_2", "HV_DC_1_U_V", m_pduU);
  out("PDU_Tx_2", "HV_DC_1_I_A", m_pduI);
  out("OBC", "OBC_Output_Voltage", m_obcU);
  out("OBC", "OBC_Output_Current", m_obcI);
  out("OBC", "OBC_Hardware_Fault", m_obcFault);
  out("OBC", "OBC_Charger_Ready", m_obcReady);
  out("OBC", "OBC_Comm_Fault", m_obcComm);
  out("DCDC", "DC_Output_Voltage", m_dcU);
  out("DCDC", "DC_Output_Current", m_dcI);
  out("DCDC", "DC_Output_Status", m_dcSts);
  out("ST_MOT_2", "st_mot_fault", m_motFault);
  out("ST_MOT_2", "st_mot_run", m_motRun);
  out("ST_MOT_1", "st_mot_n", m_motN);
  out("ST_MOT_3", "st_mot_u_dc", m_motUdc);
  const char* suffixes[4] = {"", "_2", "_3", "_4"};
  for (std::size_t i = 0; i < 4; ++i) {
    const std::string s = suffixes[i];
    Inverter& inverter = m_inverters[i];
    in(("HC1_Demands" + s).c_str(), "ControlWord", inverter.controlWord);
    in(("HC1_Demands" + s).c_str(), "Torque_Request", inverter.torqueRequest);
    out("HS2_Status_Feedback" + s, "InverterStatus", inverter.statusOut);
    out("HS2_Status_Feedback" + s, "Torque_Actual", inverter.torque);
    out("HS2_Status_Feedback" + s, "Speed_Actual", inverter.speed);
    out("HS2_Status_Feedback" + s, "DC_Link_Current", inverter.current);
    out("HS_Drive_State_Feedback" + s, "Drive_State", inverter.driveState);
    out("HS3_Temperature_Feedback" + s, "DC_Link_Voltage", inverter.dcLink);
  }
  if (!status) return status;
  auto soh = m_bus->outputMessage("HVESSHIST_PGN64606");
  auto rqst = m_bus->outputMessage("RQST_VIC_PGN59904");
  if (!soh || !rqst) return Error{"simulated vehicle: " + (soh ? rqst.error() : soh.error()).message};
  m_sohMessage = *soh;
  m_rqstVicMessage = *rqst;
  m_bus->set(m_rqstVic, j1939::PGN_TIME_DATE);
  m_bus->set(m_soh, m_config->stateOfHealth);
  m_timeDateId = j1939::Id::fromPgn(j1939::PGN_TIME_DATE, 6, 0x21, j1939::GLOBAL_ADDRESS).toCanId();
  return {};
}

void VehicleModel::setFault(Fault fault, bool active) noexcept {
  const std::size_t index = static_cast<std::size_t>(fault);
  if (m_faults[index] == active) return;
  m_faults[index] = active;
  if (fault == Fault::SocLow || fault == Fault::SocHigh) {
    if (active) {
      m_socBeforeLow = m_soc;
      m_soc = fault == Fault::SocLow ? m_config->lowSoc : m_config->highSoc;
    } else {
      m_soc = m_socBeforeLow;
    }
  }
}

void VehicleModel::receive(const can::Frame& frame, std::int64_t atNs) noexcept {
  // Asleep, the VIC checks no pairs (a powered-down ECU has no receiver state): the pairs the
  // VCU sends while it wakes or after it went to sleep are neither used nor refused.
  if (m_awake) {
    switch (m_pairs.receive(frame, atNs, fault(Fault::ShmExpectation))) {
      case SafetyPairs::Outcome::Header:
      case SafetyPairs::Outcome::NotUsed:
        return;
      case SafetyPairs::Outcome::Used:  // only a good pair's data is used
        m_bus->receive(frame, atNs);
        m_relayRequest = m_bus->get(m_esRelay);
        m_lastGoodPairNs = atNs;
        return;
      case SafetyPairs::Outcome::NotPaired:
        break;
    }
  }
  if ((frame.id & 0x03FFFF00) == (m_timeDateId & 0x03FFFF00) && m_timeAnswerPending) {
    m_timeAnswerPending = false;
    const auto decoded = j1939::decodeTimeDate(frame.payload());
    const auto instant = decoded ? decoded->toUtcInstant() : std::nullopt;
    const std::int64_t nowS = m_realtimeNs / 1'000'000'000;
    if (instant && std::llabs(instant->unixSeconds - nowS) <= TIME_TOLERANCE_S) {
      ++m_timeAnswers;
    } else {
      ++m_timeAnswerErrors;
    }
  }
  m_bus->receive(frame, atNs);
}

void VehicleModel::stepVic(std::int64_t nowNs, double dt, bool wake) {
  const auto recent = [&](bridge::SignalRef ref) {
    const std::int64_t at = m_bus->lastReceivedNs(ref);
    return at != 0 && nowNs - at <= m_config->keepAliveTimeoutNs;
  };
  const bool keepAlive = recent(m_ccvsAny) && recent(m_hvesscAny) && recent(m_crashType);
  const bool wasAwake = m_awake;
  m_awake = keepAlive && wake;
  if (m_awake != wasAwake) {
    m_bus->setSilent("VIC", !m_awake);
    // Woken, its J1939-76 receivers start without history: the first pair synchronises, and
    // the gap since the pairs it saw before it slept is no cycle timeout.
    m_pairs.reset();
  }
  // the relay request lapses when no good pair came for the keep-alive timeout
  const bool pairsFresh = m_lastGoodPairNs != 0 && nowNs - m_lastGoodPairNs <= m_config->keepAliveTimeoutNs;
  const int request = pairsFresh ? static_cast<int>(std::lround(m_relayRequest)) : 0;
  const bool consent = m_bus->get(m_consent) == 1;
  const bool crash = m_bus->get(m_crashType) == 1;
  const bool faulted = fault(Fault::Battery) || fault(Fault::Isolation);
  const auto to = [&](int connection) {
    if (connection == m_connection) return;
    m_connection = connection;
    m_connectionSinceNs = nowNs;
  };
  const std::int64_t in = nowNs - m_connectionSinceNs;
  if (!m_awake) {
    to(AWAITING);
  } else if (faulted || crash) {
    to(faulted ? FAULTED : AWAITING);
  } else {
    const bool wantsDriving = request == 3;
    const bool wantsCharging = request == 2 || request == 5;
    switch (m_connection) {
      case FAULTED:  // the fault is gone: the HV bus stays open until a new request
        to(AWAITING);
        break;
      case AWAITING:
        if ((wantsDriving || wantsCharging) && consent) to(CONNECTING);
        break;
      case CONNECTING:
        if (!wantsDriving && !wantsCharging) {
          to(AWAITING);
        } else if (in >= m_config->connectNs) {
          to(wantsDriving ? CONNECTED : CHARGING);
        }
        break;
      case CONNECTED:
      case CHARGING:
        if (!wantsDriving && !wantsCharging) to(DISCONNECTING);
        break;
      case DISCONNECTING:
        if (in >= m_config->disconnectNs) to(AWAITING);
        break;
      default:
        to(AWAITING);
    }
  }
  // the pack: current from the loads (A, discharge positive), SOC by coulomb counting
  double load = 0;
  for (const Inverter& inverter : m_inverters) {
    if (inverter.stage == 5 && inverter.status == 10) load += m_config->drivingCurrent / 4.0;
  }
  if (m_bus->get(m_dcdcCommand) == 1 && hvPresent()) load += m_config->dcdcCurrent * 14.0 / 600.0;
  double charge = 0;
  if (m_connection == CHARGING && !fault(Fault::Obc) && m_bus->get(m_bmsControl) == 0 && m_soc < m_config->fullSoc) {
    const double asked = std::isnan(m_bus->get(m_bmsMaxCurrent)) ? 0 : m_bus->get(m_bmsMaxCurrent);
    charge = std::min(asked, m_config->chargeCurrentLimit);
  }
  m_current = hvPresent() ? load - charge : 0.0;
  m_soc = std::clamp(m_soc - m_current * dt / 3600.0 / m_config->capacityAh * 100.0, 0.0, 100.0);
}

void VehicleModel::stepPowerNodes(std::int64_t, double dt) {
  const double ocv = m_config->emptyVoltage + (m_config->fullVoltage - m_config->emptyVoltage) * m_soc / 100.0;
  const double pack = ocv - m_current * m_config->resistanceOhm;
  // PDU: contactors close on command only while the battery is connected
  const bool wantA = m_bus->get(m_contactorA) == 1;
  const bool wantB = m_bus->get(m_contactorB) == 1;
  const bool stuck = fault(Fault::ContactorStuck);
  m_closedA = (wantA && hvPresent()) || (stuck && m_closedA);
  m_closedB = (wantB && hvPresent()) || (stuck && m_closedB);
  m_bus->set(m_pduStatus, fault(Fault::Pdu) ? 2 : 1);
  m_bus->set(m_groupA, m_closedA ? 1 : 0);
  m_bus->set(m_groupB, m_closedB ? 1 : 0);
  const bool busLive = hvPresent() && (m_closedA || m_closedB);
  m_bus->set(m_pduU, busLive ? pack : 0);
  m_bus->set(m_pduI, busLive ? m_current : 0);
  // OBC and DC-DC
  const bool charging = m_connection == CHARGING && m_current < 0;
  m_bus->set(m_obcFault, fault(Fault::Obc) ? 1 : 0);
  m_bus->set(m_obcReady, hvPresent() && !fault(Fault::Obc) ? 1 : 0);
  m_bus->set(m_obcComm, 0);
  m_bus->set(m_obcU, charging ? pack : 0);
  m_bus->set(m_obcI, charging ? -m_current : 0);
  const bool dcdcOn = m_bus->get(m_dcdcCommand) == 1 && hvPresent();
  m_bus->set(m_dcSts, dcdcOn ? 1 : 0);
  const double setV = std::isnan(m_bus->get(m_dcdcSetV)) ? 0 : m_bus->get(m_dcdcSetV);
  const double maxI = std::isnan(m_bus->get(m_dcdcMaxI)) ? 0 : m_bus->get(m_dcdcMaxI);
  m_bus->set(m_dcU, dcdcOn ? setV : 0);
  m_bus->set(m_dcI, dcdcOn ? std::min(maxI, m_config->dcdcCurrent) : 0);
  // Editron
  const bool run = m_bus->get(m_motRequest) == 1 && busLive && !fault(Fault::Editron);
  m_bus->set(m_motFault, fault(Fault::Editron) ? 2 : 1);
  m_bus->set(m_motRun, run ? 1 : 0);
  // the speed follows cmd_mot_n_ref with a 0.5 s time constant while running, else coasts to 0
  const double reference = run && !std::isnan(m_bus->get(m_motSpeedRef)) ? m_bus->get(m_motSpeedRef) : 0.0;
  m_motSpeed += (reference - m_motSpeed) * std::min(1.0, dt / 0.5);
  m_bus->set(m_motN, m_motSpeed);
  m_bus->set(m_motUdc, busLive ? pack : 0);
  // VIC measurements
  m_bus->set(m_uLvl, pack);
  m_bus->set(m_currentOut, m_current);
  m_bus->set(m_socOut, m_soc);
  m_bus->set(m_avlCh, m_soc < m_config->fullSoc ? m_config->chargeCurrentLimit * pack / 1000.0 : 0);
  m_bus->set(m_avlDcha, m_soc > 5 ? 150 : 0);
  m_bus->set(m_uChLim, m_config->chargeVoltageLimit);
  m_bus->set(m_iChLim, m_soc < m_config->fullSoc ? m_config->chargeCurrentLimit : 0);
}

void VehicleModel::stepInverters(std::int64_t nowNs) {
  const bool busLive = hvPresent() && (m_closedA || m_closedB);
  for (std::size_t i = 0; i < m_inverters.size(); ++i) {
    Inverter& inverter = m_inverters[i];
    const double word = m_bus->get(inverter.controlWord);
    const int commanded = std::isnan(word) ? 6 : static_cast<int>(std::lround(word));
    // the enable sequence: 6 (disabled) -> 3 (energised, needs the HV bus) -> 5 (enabled);
    // 6 from anywhere at once; a step out of order is not followed
    if (commanded == 6) {
      inverter.stage = 6;
    } else if (nowNs >= inverter.stepAtNs && commanded != inverter.stage) {
      if ((commanded == 3 && inverter.stage == 6 && busLive) || (commanded == 5 && inverter.stage == 3)) {
        inverter.stage = commanded;
        inverter.stepAtNs = nowNs + m_config->inverterStepNs;
      }
    }
    if (!busLive && inverter.stage != 6) inverter.stage = 6;
    int status = inverter.stage == 6 ? 8 : inverter.stage == 3 ? 9 : 10;
    if (i == 0 && fault(Fault::Hvlp)) status = 1;
    if (i == 0 && fault(Fault::HvlpShutdown)) status = 13;
    inverter.status = status;
    const bool enabled = status == 10;
    const double torque = enabled && !std::isnan(m_bus->get(inverter.torqueRequest)) ? m_bus->get(inverter.torqueRequest) : 0;
    m_bus->set(inverter.statusOut, status);
    m_bus->set(inverter.driveState, inverter.stage == 6 ? 0 : inverter.stage);
    m_bus->set(inverter.torque, torque);
    m_bus->set(inverter.speed, enabled ? torque * 10 : 0);
    m_bus->set(inverter.current, enabled ? m_config->drivingCurrent / 4.0 : 0);
    m_bus->set(inverter.dcLink, busLive ? std::min(m_config->fullVoltage, 2047.0) : 0);
  }
}

void VehicleModel::publishVic() {
  const bool closed = hvPresent();
  m_bus->set(m_cnctnSts, m_connection);
  m_bus->set(m_operSts, m_connection == FAULTED ? 14 : closed ? 2 : 1);
  m_bus->set(m_posCntctr, closed ? 1 : 0);
  m_bus->set(m_negCntctr, closed ? 1 : 0);
  m_bus->set(m_permission, m_connection == FAULTED ? 0 : 10);
  m_bus->set(m_intChrgr, m_connection == CHARGING ? 1 : 0);
  m_bus->set(m_hvil, 1);
  m_bus->set(m_pasIsln, fault(Fault::Isolation) ? 2 : 0);
  m_bus->set(m_socSts, m_soc < 20 ? 1 : 0);
}

}  // namespace openvcu::ecusim
