#pragma once
// The HHEA nodes' behaviour on top of the virtual bus, stepped with the time passed in
// (tests drive it with a fake clock):
//   VIC/BMS  checks the VCU's J1939-76 pairs (SafetyPairChecker: CRC, sequence, SHM->SDM
//            time, SHM cycle), taking as the SDM the next frame after the SHM with the
//            SDM's PGN, SA and DA (priority not compared, as J1939-76 does), and uses
//            Control_Es_Relay only from a good pair; sleeps (falls
//            silent) without the keep-alive (CCVS1, HVESSC1, CN) or the wake signal; HV
//            connection: awaiting -> connecting -> connected (3) / connected for charging
//            (2, 5) with consent and no fault, disconnecting on 0; pack voltage, current and
//            SOC from load and charge; charge limits; SOH on request; asks for Time/Date
//            every second and checks the answers;
//   PDU      contactors close on command only while the battery is connected;
//   OBC      charges (BMS_Control 0) within BMS_Max_Current and the VIC's limit while the
//            battery is connected for charging; DC-DC follows its command;
//   Editron  runs on cmd_mot_request with HV present; HVLP x4: ControlWord 6 -> 3 -> 5
//            reflected in InverterStatus 8 -> 9 -> 10 (and Drive_State), torque and speed.
// Faults (Fault below) are injected and cleared by name; every one changes what the nodes
// send, never the checks of the VCU side.

#include <array>
#include <atomic>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "openvcu/config/simulation.hpp"
#include "openvcu/j1939/safety.hpp"
#include "safety_pairs.hpp"
#include "virtual_bus.hpp"

namespace openvcu::ecusim {

enum class Fault : std::uint8_t {
  Battery,         ///< VIC reports HS_HiUBusCnctnSts 14 and opens
  Isolation,       ///< isolation test error: the VIC refuses HV (status 14)
  ContactorStuck,  ///< the PDU's contactors stay closed when commanded open
  Pdu,             ///< byPDU_Status 2 (fault)
  Hvlp,            ///< inverter 0x71 reports InverterStatus 1 (fault)
  HvlpShutdown,    ///< inverter 0x71 reports 13 (fault shutdown)
  Editron,         ///< st_mot_fault 2
  Obc,             ///< OBC_Hardware_Fault 1, no charge current
  SocLow,          ///< SOC jumps to the configured low value (restored when cleared)
  SocHigh,         ///< SOC jumps to the configured high value (restored when cleared)
  ShmExpectation,  ///< the VIC expects another SDM CRC: every pair is refused
  Count,
};
inline constexpr std::size_t FAULT_COUNT = static_cast<std::size_t>(Fault::Count);

/// "battery", "isolation", "contactor_stuck", "pdu", "hvlp", "hvlp_shutdown", "editron",
/// "obc", "soc_low", "soc_high", "shm_expectation".
[[nodiscard]] std::string_view faultName(Fault fault) noexcept;
[[nodiscard]] std::optional<Fault> faultByName(std::string_view name) noexcept;

class VehicleModel {
 public:
  static Result<VehicleModel> create(VirtualBus& bus, const config::SimConfig& config);

  /// A VCU frame: J1939-76 headers and data go through the VIC's checkers first.
  void receive(const can::Frame& frame, std::int64_t atNs) noexcept;
  /// Advances every node to `nowNs`; `wake` is the wake signal's level (true without one).
  /// `send` gets the answers to requests (HVESSHIST).
  template <typename Send>
  void step(std::int64_t nowNs, std::int64_t realtimeNs, bool wake, Send&& send);
  /// Sends the cyclic frames due (the bus's sendDue, noting the VIC's Time/Date requests).
  template <typename Send>
  void sendDue(std::int64_t nowNs, Send&& send);

  void setFault(Fault fault, bool active) noexcept;
  [[nodiscard]] bool fault(Fault fault) const noexcept { return m_faults[static_cast<std::size_t>(fault)]; }

  // observations (heartbeat, tests)
  [[nodiscard]] double soc() const noexcept { return m_soc; }
  [[nodiscard]] int connection() const noexcept { return m_connection; }
  [[nodiscard]] bool awake() const noexcept { return m_awake; }
  [[nodiscard]] int inverterStatus(std::size_t i) const noexcept { return m_inverters[i].status; }
  [[nodiscard]] const SafetyStats& safety() const noexcept { return m_pairs.stats(); }
  [[nodiscard]] std::uint64_t timeRequests() const noexcept { return m_timeRequests; }
  [[nodiscard]] std::uint64_t timeAnswers() const noexcept { return m_timeAnswers; }
  [[nodiscard]] std::uint64_t timeAnswerErrors() const noexcept { return m_timeAnswerErrors; }
  [[nodiscard]] std::uint64_t sohAnswers() const noexcept { return m_sohAnswers; }
  /// The last pair verdict changed since the previous call (for one fault event per change).
  [[nodiscard]] std::optional<j1939::SafetyResult> takeSafetyChange() noexcept { return m_pairs.takeChange(); }

 private:
  struct Inverter {
    bridge::SignalRef controlWord, torqueRequest;                            ///< VCU inputs
    bridge::SignalRef statusOut, torque, speed, current, driveState, dcLink;  ///< outputs
    int status{8};
    int stage{6};             ///< the last ControlWord followed
    std::int64_t stepAtNs{};  ///< when the next ControlWord may be followed
  };
  VehicleModel(VirtualBus& bus, const config::SimConfig& config)
      : m_bus(&bus), m_config(&config), m_pairs(config.safety) {}
  Status resolve();
  void stepVic(std::int64_t nowNs, double dt, bool wake);
  void stepPowerNodes(std::int64_t nowNs, double dt);
  void stepInverters(std::int64_t nowNs);
  void publishVic();
  [[nodiscard]] bool hvPresent() const noexcept { return m_connection == 1 || m_connection == 5; }

  VirtualBus* m_bus;
  const config::SimConfig* m_config;
  std::array<bool, FAULT_COUNT> m_faults{};
  // VCU inputs
  bridge::SignalRef m_esRelay{}, m_consent{}, m_ccvsAny{}, m_hvesscAny{}, m_crashType{}, m_contactorA{}, m_contactorB{},
      m_bmsControl{}, m_bmsMaxCurrent{}, m_bmsMaxVoltage{}, m_dcdcCommand{}, m_dcdcSetV{}, m_dcdcMaxI{}, m_motRequest{},
      m_rqstPgn{}, m_motSpeedRef{};
  std::uint32_t m_timeDateId{};
  // VIC outputs
  bridge::SignalRef m_cnctnSts{}, m_operSts{}, m_posCntctr{}, m_negCntctr{}, m_permission{}, m_intChrgr{}, m_hvil{},
      m_pasIsln{}, m_socSts{}, m_uLvl{}, m_currentOut{}, m_avlCh{}, m_avlDcha{}, m_socOut{}, m_uChLim{}, m_iChLim{}, m_soh{},
      m_rqstVic{};
  std::size_t m_sohMessage{}, m_rqstVicMessage{};
  // PDU, OBC, DC-DC, Editron outputs
  bridge::SignalRef m_pduStatus{}, m_groupA{}, m_groupB{}, m_pduU{}, m_pduI{}, m_obcU{}, m_obcI{}, m_obcFault{}, m_obcReady{},
      m_obcComm{}, m_dcU{}, m_dcI{}, m_dcSts{}, m_motFault{}, m_motRun{}, m_motN{}, m_motUdc{};
  std::array<Inverter, 4> m_inverters{};
  SafetyPairs m_pairs;
  // state
  double m_relayRequest{0};   ///< Control_Es_Relay from the last good pair
  std::int64_t m_lastGoodPairNs{};
  bool m_awake{};
  int m_connection{0};        ///< HS_HiUBusCnctnSts
  std::int64_t m_connectionSinceNs{};
  double m_soc{};
  double m_socBeforeLow{};  ///< the SOC before soc_low / soc_high, restored when cleared
  double m_current{};
  bool m_closedA{}, m_closedB{};
  double m_motSpeed{};  ///< Editron rpm, first order towards cmd_mot_n_ref
  std::int64_t m_lastStepNs{};
  std::int64_t m_timeRequestAtNs{};
  std::int64_t m_lastRqstNs{};
  std::uint64_t m_timeRequests{}, m_timeAnswers{}, m_timeAnswerErrors{}, m_sohAnswers{};
  bool m_timeAnswerPending{};
  std::int64_t m_realtimeNs{};
};

template <typename Send>
void VehicleModel::step(std::int64_t nowNs, std::int64_t realtimeNs, bool wake, Send&& send) {
  const double dt = m_lastStepNs == 0 ? 0.0 : static_cast<double>(nowNs - m_lastStepNs) / 1e9;
  m_lastStepNs = nowNs;
  m_realtimeNs = realtimeNs;
  // SOH on request: the VCU's Request for PGN 64606 gets one HVESSHIST
  const std::int64_t rqstAt = m_bus->lastReceivedNs(m_rqstPgn);
  if (rqstAt != 0 && rqstAt != m_lastRqstNs) {
    m_lastRqstNs = rqstAt;
    if (m_awake && m_bus->get(m_rqstPgn) == 64606) {
      m_bus->sendNow(m_sohMessage, nowNs, send);
      ++m_sohAnswers;
    }
  }
  stepVic(nowNs, dt, wake);
  stepPowerNodes(nowNs, dt);
  stepInverters(nowNs);
  publishVic();
  // Time/Date: the VIC asks every second (its cyclic RQST_VIC message); the answer must
  // come within timeDateAnswer (receive() takes it)
  if (m_timeAnswerPending && nowNs - m_timeRequestAtNs > m_config->timeDateAnswerNs) {
    m_timeAnswerPending = false;
    ++m_timeAnswerErrors;
  }
}

template <typename Send>
void VehicleModel::sendDue(std::int64_t nowNs, Send&& send) {
  const std::uint32_t requestId = m_bus->frameId(m_rqstVicMessage);
  m_bus->sendDue(nowNs, [&](std::size_t busIndex, const can::Frame& frame) {
    if (frame.id == requestId) {
      ++m_timeRequests;
      m_timeAnswerPending = true;
      m_timeRequestAtNs = nowNs;
    }
    send(busIndex, frame);
  });
}

}  // namespace openvcu::ecusim
