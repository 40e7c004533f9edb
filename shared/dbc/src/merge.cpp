// Merging several DBC files into one database (the thesis' "combined DBC").
#include "openvcu/dbc/parser.hpp"

#include <algorithm>
#include <cstdio>

namespace openvcu::dbc {

namespace {
std::string hexId(std::uint32_t id) {
  char buffer[16];
  std::snprintf(buffer, sizeof buffer, "0x%X", id);
  return buffer;
}

/// Appends the items of `from` that `into` does not hold yet (identical definitions once).
template <typename T>
void appendMissing(std::vector<T>& into, const std::vector<T>& from) {
  const std::size_t existing = into.size();
  for (const T& item : from) {
    if (std::find(into.begin(), into.begin() + static_cast<std::ptrdiff_t>(existing), item) ==
        into.begin() + static_cast<std::ptrdiff_t>(existing)) {
      into.push_back(item);
    }
  }
}
}  // namespace

Status merge(Database& into, const Database& other, std::string_view otherName) {
  Database combined = into;  // work on a copy: a refused merge changes nothing
  const std::string where(otherName);
  for (const Message& msg : other.messages) {
    const Message* sameId = msg.pseudo ? nullptr : combined.findMessage(msg.id, msg.extended);
    const Message* sameName = combined.findMessage(msg.name);
    if (sameId && *sameId == msg) continue;
    if (msg.pseudo && sameName && *sameName == msg) continue;  // pseudo messages have no ID to compare
    if (sameId) {
      return Error{"message '" + msg.name + "' (ID " + hexId(msg.id) + ") conflicts with '" + sameId->name +
                       "' of the same ID defined differently",
                   Location{where, msg.source.line, 0, {}}};
    }
    if (sameName && !msg.pseudo) {
      return Error{"message name '" + msg.name + "' already used for ID " + hexId(sameName->id),
                   Location{where, msg.source.line, 0, {}}};
    }
    combined.messages.push_back(msg);
    combined.reindex();
  }
  for (const Node& node : other.nodes) {
    if (!combined.findNode(node.name)) combined.nodes.push_back(node);
  }
  for (const AttributeDefinition& def : other.attributeDefinitions) {
    const AttributeDefinition* existing = combined.findAttributeDefinition(def.name, def.object);
    if (!existing) {
      combined.attributeDefinitions.push_back(def);
    } else if (existing->type != def.type ||
               (def.type == AttributeType::Enum && existing->enumValues != def.enumValues)) {
      return Error{"attribute '" + def.name + "' is defined with another type or ENUM list",
                   Location{where, def.source.line, 0, {}}};
    }
  }
  for (const ValueTable& table : other.valueTables) {
    bool present = false;
    for (const ValueTable& mine : combined.valueTables) present = present || mine.name == table.name;
    if (!present) combined.valueTables.push_back(table);
  }
  for (const auto& [name, value] : other.networkAttributes) combined.networkAttributes.emplace(name, value);
  appendMissing(combined.environmentVariables, other.environmentVariables);
  appendMissing(combined.signalGroups, other.signalGroups);
  appendMissing(combined.relationAttributes, other.relationAttributes);
  if (combined.comment.empty()) combined.comment = other.comment;
  combined.reindex();
  into = std::move(combined);
  return {};
}

}  // namespace openvcu::dbc
