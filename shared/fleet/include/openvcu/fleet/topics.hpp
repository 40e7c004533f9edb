#pragma once
// The topic layout of fleet telemetry (docs/design/telemetry.md, "Topics"): one tree per
// vehicle under "openvcu/<vehicleId>/", one topic per kind of message. The producer
// (vcu-telemetry) and every consumer (`vcu fleet`) name topics through these functions.
//
//   vehicleTopic("hhea-01", Topic::State)   -> "openvcu/hhea-01/state"
//   fleetFilter(Topic::Status)              -> "openvcu/+/status"
//   parseTopic("openvcu/hhea-01/faults")    -> {vehicleId "hhea-01", Topic::Faults}
//   parseTopic("openvcu/hhea-01/cmd/7")     -> empty (not a vehicle -> fleet message kind)

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace openvcu::fleet {

/// The first level of every topic.
inline constexpr std::string_view TOPIC_ROOT = "openvcu";

/// The messages a vehicle publishes (vehicle -> fleet).
enum class Topic : std::uint8_t { Status, Birth, State, Faults, Health, Signals };

/// Every kind, in the order a watcher subscribes to them.
inline constexpr std::array<Topic, 6> ALL_TOPICS{Topic::Status, Topic::Birth,  Topic::State,
                                                 Topic::Faults, Topic::Health, Topic::Signals};

/// The status payloads (plain text, not JSON): "online" at each connect, the last will "offline".
inline constexpr std::string_view STATUS_ONLINE = "online";
inline constexpr std::string_view STATUS_OFFLINE = "offline";

/// "status", "birth", "state", "faults", "health", "signals".
[[nodiscard]] std::string_view topicSuffix(Topic topic) noexcept;
/// The kind named by a suffix, or empty.
[[nodiscard]] std::optional<Topic> topicFromSuffix(std::string_view suffix) noexcept;
/// True for the kinds published retained: status, birth, and the last state, faults and health,
/// so a watcher that connects later learns them at once (an offline vehicle's last ones stay).
/// Signals are not retained: a batch holds only the signals that moved.
[[nodiscard]] bool isRetained(Topic topic) noexcept;

/// "openvcu/<vehicleId>/" (the prefix of all of one vehicle's topics).
[[nodiscard]] std::string vehicleTopicRoot(std::string_view vehicleId);
/// "openvcu/<vehicleId>/<suffix>".
[[nodiscard]] std::string vehicleTopic(std::string_view vehicleId, Topic topic);
/// "openvcu/+/<suffix>": one kind of every vehicle.
[[nodiscard]] std::string fleetFilter(Topic topic);

/// "openvcu/<vehicleId>/cmd/": the prefix of the commands to one vehicle (fleet -> vehicle).
[[nodiscard]] std::string commandTopicPrefix(std::string_view vehicleId);
/// "openvcu/<vehicleId>/cmd/+": what a vehicle subscribes to when it takes remote commands.
[[nodiscard]] std::string commandFilter(std::string_view vehicleId);
/// "cmd/<cmdId>/answer": the answer's topic below the vehicle's root (a queue record's topic line).
[[nodiscard]] std::string commandAnswerSuffix(std::string_view cmdId);

struct TopicName {
  std::string vehicleId;
  Topic topic{};
};
/// "openvcu/<id>/<suffix>" with a valid id (1-64 of A-Z a-z 0-9 - _) and a known suffix ->
/// the parts; anything else (other roots, deeper topics like cmd/<id>) -> empty.
[[nodiscard]] std::optional<TopicName> parseTopic(std::string_view topic);

}  // namespace openvcu::fleet
