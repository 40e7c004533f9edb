// Merging several DBC files into one database (the thesis' "combined DBC").
#include "openvcu/dbc/parser.hpp"

#include <cstdio>

namespace openvcu::dbc {

namespace {
std::string hexId(std::uint32_t id) {
  char buffer[16];
  std::snprintf(buffer, sizeof buffer, "0x%X", id);
  return buffer;
}
}  // namespace

Status merge(Database& into, const Database& other, std::string_view otherName) {
  Database combined = into;  // work on a copy: a refused merge changes nothing
  const std::string where(otherName);
  for (const Message& msg : other.messages) {
    const Message* sameId = msg.pseudo ? nullptr : combined.findMessage(msg.id, msg.extended);
    const Message* sameName = combined.findMessage(msg.name);
    if (sameId && *sameId == msg) continue;
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
  combined.environmentVariables.insert(combined.environmentVariables.end(), other.environmentVariables.begin(),
                                       other.environmentVariables.end());
  combined.signalGroups.insert(combined.signalGroups.end(), other.signalGroups.begin(), other.signalGroups.end());
  combined.relationAttributes.insert(combined.relationAttributes.end(), other.relationAttributes.begin(),
                                     other.relationAttributes.end());
  if (combined.comment.empty()) combined.comment = other.comment;
  combined.reindex();
  into = std::move(combined);
  return {};
}

}  // namespace openvcu::dbc
