#pragma once
// The receive settings of vcu-can-rx: the file named by "receive" in the vehicle
// configuration (config/hhea/receive.json), loaded by vcu-can-rx and checked by `vcu check`.
// Every key is optional; without the file the defaults hold.
//
//   {
//     "timeoutFactor": 3,                                  // timeout = 3 x the DBC cycle
//     "senders": {"VIC": {"expectedWhen": {"signal": "internal.gpio.Cl15", "eq": 1, "startMs": 1000}}},
//     "messages": {"HVESSS1_PGN61590": {"timeoutMs": 300}, "HVESSHIST_PGN64606": {"timeoutMs": 0},
//                  "RQST_VIC_PGN59904": {"expectedWhen": "always"}},
//     "safety": [{"message": "S1_ES_PGN61427", "maxDelayMs": 10, "headerCycleMs": 60}],
//     "forward": [{"from": "vehicle", "to": "battery", "id": "0x18FF5071", "rewriteId": "0x18FF5021"},
//                 {"from": "vehicle", "to": "battery", "pgn": 65280, "source": "0x71"}],
//     "transport": {"maxPacketsPerCts": 16},
//     "dm1": true,
//     "batchWindowUs": 1000
//   }
// Reference: services/can-rx/README.md.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "openvcu/config/vehicle.hpp"
#include "openvcu/core/result.hpp"

namespace openvcu::config {

/// A J1939-76 safety data group another node sends us: the SDM (a DBC message) and the
/// receiver's time limits. The SHM identifier follows from the SDM's.
struct SafetyGroup {
  std::size_t dataMessage{};         ///< index into the database's messages
  std::int64_t maxHeaderToDataNs{};  ///< SRVT: SHM -> SDM
  std::int64_t maxHeaderCycleNs{};   ///< SCT: SHM -> next SHM
};

/// When the messages of a sender are expected: while `signal` reads `equals`, from `startNs`
/// after it began to (the sender's time to wake). A receive timeout raises its fault only
/// while its message is expected; the signals still go stale when the message stops.
/// Example: {"signal": "internal.gpio.Cl15", "eq": 1, "startMs": 1000} -> expected from 1 s
/// after the Cl15 relay output went on, until it goes off.
struct ReceiveExpectation {
  std::string signal;      ///< catalog key, e.g. "internal.gpio.Cl15"
  double equals{};         ///< the value (the override or command when the slot has one, else the bus value)
  std::int64_t startNs{};  ///< grace after the condition became true
  std::string origin;      ///< where it was configured: "/senders/VIC/expectedWhen"
};

/// Copy frames of one bus to another through can-tx's send-request stream.
struct ForwardRule {
  std::size_t fromBus{};
  std::size_t toBus{};
  bool byPgn{};                            ///< true: match the J1939 PGN (extended frames); false: the exact ID
  std::uint32_t id{};                      ///< the ID (byPgn false) or the PGN (byPgn true)
  bool extended{true};                     ///< for byPgn false: 29-bit ID (IDs above 0x7FF always are)
  std::optional<std::uint8_t> source;      ///< byPgn: only from this source address
  std::optional<std::uint32_t> rewriteId;  ///< send with this ID instead (same ID kind)
};

/// ReceiveConfig::expectationOf for a message supervised from the receiver's start on.
inline constexpr std::int32_t ALWAYS_EXPECTED = -1;

struct ReceiveConfig {
  double timeoutFactor{3.0};
  /// Per DBC message (by index): receive timeout in ns, 0 = never stale. Filled for every
  /// message; those this node transmits have 0.
  std::vector<std::int64_t> timeoutNs;
  /// The conditions named by "expectedWhen" (senders' and messages'), each once.
  std::vector<ReceiveExpectation> expectations;
  /// Per DBC message (by index): its condition in `expectations`, or ALWAYS_EXPECTED.
  std::vector<std::int32_t> expectationOf;
  std::vector<SafetyGroup> safety;
  std::vector<ForwardRule> forward;
  std::uint8_t maxPacketsPerCts{16};
  bool dm1{true};
  /// After handling what woke it, vcu-can-rx lets frames gather this long before it waits
  /// again (Loop::setBatchWindow): fewer wake-ups at high rates, at most this much latency.
  std::uint32_t batchWindowUs{1000};
};

/// The defaults for `vehicle` (timeouts = factor x GenMsgCycleTime of received messages).
ReceiveConfig defaultReceiveConfig(const config::VehicleConfig& vehicle);

/// Loads vehicle.receiveFile (defaults when it is empty). Errors name the file and the
/// JSON path ("receive.json: /messages/HVESS1: unknown message; did you mean ...").
Result<ReceiveConfig> loadReceiveConfig(const config::VehicleConfig& vehicle);

}  // namespace openvcu::config
