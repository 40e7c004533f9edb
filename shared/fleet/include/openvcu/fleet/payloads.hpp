#pragma once
// The payloads of fleet telemetry parsed for a consumer (docs/design/telemetry.md,
// "Payloads"; the producer is services/telemetry). JSON, "v": 1; the status is plain text.
// Only what a consumer reads is kept; members it does not know are ignored (a newer producer
// may add some). A payload that is not the format gives an Error saying what is wrong.
//
//   parseState(R"({"v":1,"seq":41,"t":1764259200123,"state":"Driving","previous":"Ready",
//                 "event":"drive","atUnixMs":1764259200100})")
//     -> StateMessage{.seq = 41, .unixMs = 1764259200123, .state = "Driving", ...}
//   parseStatus("offline") -> false (online: true)

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "openvcu/core/result.hpp"

namespace openvcu::fleet {

/// The payload format version this code reads.
inline constexpr int PAYLOAD_VERSION = 1;

/// Fault severities as the producer names them, least to most severe
/// ("info", "warning", "error", "critical"; display::faultSeverityName()).
enum class FaultLevel : std::uint8_t { Info, Warning, Error, Critical };
[[nodiscard]] std::optional<FaultLevel> faultLevelFromName(std::string_view name) noexcept;
[[nodiscard]] std::string_view faultLevelName(FaultLevel level) noexcept;

struct BirthSignal {
  std::string name;
  std::string unit;
};
/// openvcu/<id>/birth (retained): what the vehicle is.
struct BirthMessage {
  std::string vehicleId;
  std::string instance;
  std::string software;
  std::string configHash;
  std::vector<BirthSignal> signals;
  bool commandsEnabled{};
  std::uint64_t nextSeq{};
  std::int64_t unixMs{};
};

/// openvcu/<id>/state: one FSM transition.
struct StateMessage {
  std::uint64_t seq{};
  std::int64_t unixMs{};  ///< "t": when the message was built
  std::string state;
  std::string previous;
  std::string event;
  std::int64_t atUnixMs{};  ///< when the transition happened
};

struct ActiveFault {
  std::string source;
  std::string name;
  FaultLevel level{FaultLevel::Error};
  std::string text;
};
struct Dm1Count {
  std::string node;
  std::int64_t activeDtcs{};
};
/// openvcu/<id>/faults: the whole active set.
struct FaultsMessage {
  std::uint64_t seq{};
  std::int64_t unixMs{};
  std::vector<ActiveFault> active;
  std::vector<Dm1Count> dm1;
};

struct ServiceState {
  std::string name;
  std::string status;  ///< "Ready", "Stale", "NotConnected", ...
  std::string text;
  std::int64_t restarts{};
};
/// openvcu/<id>/health.
struct HealthMessage {
  std::uint64_t seq{};
  std::int64_t unixMs{};
  std::vector<ServiceState> services;
  std::uint64_t queuePending{};
  std::uint64_t queueDropped{};
  std::uint64_t linkConnects{};
  std::uint64_t linkRefused{};
};

struct SignalSample {
  std::string name;
  std::int64_t unixMs{};
  double value{};
};
/// openvcu/<id>/signals: samples in the order sent, names resolved.
struct SignalsMessage {
  std::uint64_t seq{};
  std::int64_t unixMs{};
  std::vector<SignalSample> samples;
};

/// "online" -> true, "offline" -> false; anything else an error.
Result<bool> parseStatus(std::string_view payload);
Result<BirthMessage> parseBirth(std::string_view payload);
Result<StateMessage> parseState(std::string_view payload);
Result<FaultsMessage> parseFaults(std::string_view payload);
Result<HealthMessage> parseHealth(std::string_view payload);
Result<SignalsMessage> parseSignals(std::string_view payload);

}  // namespace openvcu::fleet
