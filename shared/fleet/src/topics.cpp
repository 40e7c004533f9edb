#include "openvcu/fleet/topics.hpp"

namespace openvcu::fleet {
namespace {

constexpr std::size_t MAX_VEHICLE_ID = 64;

bool isIdCharacter(char c) noexcept {
  return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '-' || c == '_';
}

}  // namespace

std::string_view topicSuffix(Topic topic) noexcept {
  switch (topic) {
    case Topic::Status:
      return "status";
    case Topic::Birth:
      return "birth";
    case Topic::State:
      return "state";
    case Topic::Faults:
      return "faults";
    case Topic::Health:
      return "health";
    case Topic::Signals:
      return "signals";
  }
  return "status";
}

std::optional<Topic> topicFromSuffix(std::string_view suffix) noexcept {
  for (const Topic topic : ALL_TOPICS) {
    if (topicSuffix(topic) == suffix) return topic;
  }
  return std::nullopt;
}

bool isRetained(Topic topic) noexcept {
  return topic != Topic::Signals;
}

std::string commandTopicPrefix(std::string_view vehicleId) {
  return vehicleTopicRoot(vehicleId) + "cmd/";
}

std::string commandFilter(std::string_view vehicleId) {
  return commandTopicPrefix(vehicleId) + "+";
}

std::string commandAnswerSuffix(std::string_view cmdId) {
  std::string out = "cmd/";
  out += cmdId;
  out += "/answer";
  return out;
}

std::string vehicleTopicRoot(std::string_view vehicleId) {
  std::string out(TOPIC_ROOT);
  out += '/';
  out += vehicleId;
  out += '/';
  return out;
}

std::string vehicleTopic(std::string_view vehicleId, Topic topic) {
  return vehicleTopicRoot(vehicleId) + std::string(topicSuffix(topic));
}

std::string fleetFilter(Topic topic) {
  return vehicleTopic("+", topic);
}

std::optional<TopicName> parseTopic(std::string_view topic) {
  if (!topic.starts_with(TOPIC_ROOT) || topic.size() <= TOPIC_ROOT.size() || topic[TOPIC_ROOT.size()] != '/') {
    return std::nullopt;
  }
  const std::string_view rest = topic.substr(TOPIC_ROOT.size() + 1);
  const auto slash = rest.find('/');
  if (slash == std::string_view::npos) return std::nullopt;
  const std::string_view id = rest.substr(0, slash);
  if (id.empty() || id.size() > MAX_VEHICLE_ID) return std::nullopt;
  for (const char c : id) {
    if (!isIdCharacter(c)) return std::nullopt;
  }
  const auto kind = topicFromSuffix(rest.substr(slash + 1));
  if (!kind) return std::nullopt;
  return TopicName{std::string(id), *kind};
}

}  // namespace openvcu::fleet
