#include "openvcu/dbc/model.hpp"

#include <algorithm>
#include <cmath>

namespace openvcu::dbc {

bool Signal::decodable() const noexcept {
  if (size == 0 || size > 64) return false;
  if (valueType == ValueType::Float32) return size == 32;
  if (valueType == ValueType::Float64) return size == 64;
  return true;
}

const std::string* Signal::describe(std::int64_t raw) const noexcept {
  for (const auto& description : valueDescriptions) {
    if (description.value == raw) return &description.text;
  }
  return nullptr;
}

std::vector<std::string> Message::transmitters() const {
  std::vector<std::string> out;
  if (!transmitter.empty() && transmitter != NO_NODE) out.push_back(transmitter);
  for (const auto& node : extraTransmitters) {
    if (std::find(out.begin(), out.end(), node) == out.end()) out.push_back(node);
  }
  return out;
}

const Signal* Message::findSignal(std::string_view signalName) const noexcept {
  for (const Signal& sig : signals) {
    if (sig.name == signalName) return &sig;
  }
  return nullptr;
}

const Message* Database::findMessage(std::uint32_t id, bool extended) const noexcept {
  const auto it = m_byId.find((static_cast<std::uint64_t>(extended) << 32) | id);
  return it == m_byId.end() ? nullptr : &messages[it->second];
}

const Message* Database::findMessage(std::string_view name) const noexcept {
  const auto it = m_byName.find(std::string(name));
  return it == m_byName.end() ? nullptr : &messages[it->second];
}

const Node* Database::findNode(std::string_view name) const noexcept {
  const auto it = m_nodeByName.find(std::string(name));
  return it == m_nodeByName.end() ? nullptr : &nodes[it->second];
}

const AttributeDefinition* Database::findAttributeDefinition(std::string_view name,
                                                             ObjectType object) const noexcept {
  for (const auto& def : attributeDefinitions) {
    if (def.name == name && def.object == object) return &def;
  }
  return nullptr;
}

std::optional<AttributeValue> Database::attribute(const Attributes& explicitValues, std::string_view name,
                                                  ObjectType object) const {
  if (const auto it = explicitValues.find(name); it != explicitValues.end()) return it->second;
  if (const AttributeDefinition* def = findAttributeDefinition(name, object)) return def->defaultValue;
  return std::nullopt;
}

std::optional<std::string> Database::attributeText(const Attributes& explicitValues, std::string_view name,
                                                   ObjectType object) const {
  const auto value = attribute(explicitValues, name, object);
  if (!value) return std::nullopt;
  if (value->kind == AttributeValue::Kind::String) return value->text;
  const AttributeDefinition* def = findAttributeDefinition(name, object);
  if (def && def->type == AttributeType::Enum) {
    const double index = value->number;
    if (index >= 0 && index < static_cast<double>(def->enumValues.size()) && index == std::floor(index)) {
      return def->enumValues[static_cast<std::size_t>(index)];
    }
    return std::nullopt;
  }
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.17g", value->number);
  return std::string(buffer);
}

std::optional<double> Database::startValueRaw(const Signal& signal) const {
  const auto value = attribute(signal.attributes, "GenSigStartValue", ObjectType::Signal);
  if (!value || value->kind != AttributeValue::Kind::Number) return std::nullopt;
  return value->number;
}

namespace {

/// VFrameFormat as Vector's INT encoding (used when a file declares it INT, not ENUM).
std::optional<FrameFormat> frameFormatFromNumber(double value) {
  switch (static_cast<int>(value)) {
    case 0: return FrameFormat::StandardCan;
    case 1: return FrameFormat::ExtendedCan;
    case 3: return FrameFormat::J1939;
    case 14: return FrameFormat::StandardCanFd;
    case 15: return FrameFormat::ExtendedCanFd;
    default: return std::nullopt;
  }
}

std::optional<FrameFormat> frameFormatFromText(std::string_view text) {
  if (text == "StandardCAN") return FrameFormat::StandardCan;
  if (text == "ExtendedCAN") return FrameFormat::ExtendedCan;
  if (text == "StandardCAN_FD") return FrameFormat::StandardCanFd;
  if (text == "ExtendedCAN_FD") return FrameFormat::ExtendedCanFd;
  if (text == "J1939PG") return FrameFormat::J1939;
  return std::nullopt;
}

}  // namespace

void Database::reindex() {
  m_byId.clear();
  m_byName.clear();
  m_nodeByName.clear();
  const AttributeDefinition* frameFormatDef = findAttributeDefinition("VFrameFormat", ObjectType::Message);
  const auto protocol = attributeText(networkAttributes, "ProtocolType", ObjectType::Network);
  const bool j1939Network = protocol && *protocol == "J1939";
  for (std::size_t i = 0; i < messages.size(); ++i) {
    Message& msg = messages[i];
    if (!msg.pseudo) m_byId.emplace((static_cast<std::uint64_t>(msg.extended) << 32) | msg.id, i);
    m_byName.emplace(msg.name, i);

    std::optional<FrameFormat> format;
    if (frameFormatDef) {
      if (frameFormatDef->type == AttributeType::Enum || frameFormatDef->type == AttributeType::String) {
        if (auto text = attributeText(msg.attributes, "VFrameFormat", ObjectType::Message)) {
          format = frameFormatFromText(*text);
        }
      } else if (auto value = attribute(msg.attributes, "VFrameFormat", ObjectType::Message);
                 value && value->kind == AttributeValue::Kind::Number) {
        format = frameFormatFromNumber(value->number);
      }
    }
    if (!format && j1939Network && msg.extended) format = FrameFormat::J1939;
    if (!format) {
      const bool fd = msg.length > 8 && msg.length <= 64;
      format = msg.extended ? (fd ? FrameFormat::ExtendedCanFd : FrameFormat::ExtendedCan)
                            : (fd ? FrameFormat::StandardCanFd : FrameFormat::StandardCan);
    }
    msg.frameFormat = *format;

    msg.displayName = attributeText(msg.attributes, "SystemMessageLongSymbol", ObjectType::Message).value_or(msg.name);
    if (msg.displayName.empty()) msg.displayName = msg.name;
    for (Signal& sig : msg.signals) {
      sig.displayName = attributeText(sig.attributes, "SystemSignalLongSymbol", ObjectType::Signal).value_or(sig.name);
      if (sig.displayName.empty()) sig.displayName = sig.name;
    }

    msg.cycleTimeMs.reset();
    if (auto cycle = attribute(msg.attributes, "GenMsgCycleTime", ObjectType::Message);
        cycle && cycle->kind == AttributeValue::Kind::Number && cycle->number > 0 && cycle->number < 4.0e9) {
      msg.cycleTimeMs = static_cast<std::uint32_t>(cycle->number);
    }
  }
  for (std::size_t i = 0; i < nodes.size(); ++i) m_nodeByName.emplace(nodes[i].name, i);
}

bool Database::sameContent(const Database& other) const {
  // sourceEncoding describes the input bytes, not the content.
  return version == other.version && newSymbols == other.newSymbols && nodes == other.nodes &&
         valueTables == other.valueTables && messages == other.messages &&
         environmentVariables == other.environmentVariables && signalGroups == other.signalGroups &&
         attributeDefinitions == other.attributeDefinitions && networkAttributes == other.networkAttributes &&
         relationAttributes == other.relationAttributes && comment == other.comment;
}

std::string_view toString(ObjectType object) noexcept {
  switch (object) {
    case ObjectType::Network: return "network";
    case ObjectType::Node: return "BU_";
    case ObjectType::Message: return "BO_";
    case ObjectType::Signal: return "SG_";
    case ObjectType::EnvironmentVariable: return "EV_";
    case ObjectType::NodeSignalRelation: return "BU_SG_REL_";
    case ObjectType::NodeMessageRelation: return "BU_BO_REL_";
    case ObjectType::NodeEnvRelation: return "BU_EV_REL_";
  }
  return "?";
}

std::string_view toString(FrameFormat format) noexcept {
  switch (format) {
    case FrameFormat::StandardCan: return "StandardCAN";
    case FrameFormat::ExtendedCan: return "ExtendedCAN";
    case FrameFormat::StandardCanFd: return "StandardCAN_FD";
    case FrameFormat::ExtendedCanFd: return "ExtendedCAN_FD";
    case FrameFormat::J1939: return "J1939PG";
  }
  return "?";
}

}  // namespace openvcu::dbc
