// Database -> DBC text. Numbers use the shortest text that reads back to the same
// double, so parse(write(db)) == db.
#include "openvcu/dbc/parser.hpp"

#include <algorithm>
#include <charconv>
#include <string>

namespace openvcu::dbc {
namespace {

class Writer {
 public:
  explicit Writer(const Database& db) : m_db(db) {}

  std::string run() {
    header();
    for (const ValueTable& table : m_db.valueTables) {
      m_out += "VAL_TABLE_ " + table.name;
      valueList(table.values);
      m_out += " ;\n";
    }
    m_out += '\n';
    for (const Message& msg : m_db.messages) message(msg);
    for (const Message& msg : m_db.messages) {
      if (msg.extraTransmitters.empty()) continue;
      m_out += "BO_TX_BU_ " + std::to_string(msg.declaredId) + " :";
      for (std::size_t i = 0; i < msg.extraTransmitters.size(); ++i) {
        m_out += (i == 0 ? " " : ",") + msg.extraTransmitters[i];
      }
      m_out += ";\n";
    }
    environment();
    comments();
    attributeDefinitions();
    attributeValues();
    valueDescriptions();
    signalGroups();
    valueTypes();
    muxValues();
    return std::move(m_out);
  }

 private:
  void number(double value) {
    char buffer[40];
    const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
    m_out.append(buffer, result.ptr);
  }
  void quoted(std::string_view text) {
    m_out += '"';
    for (const char c : text) {
      if (c == '"' || c == '\\') m_out += '\\';
      m_out += c;
    }
    m_out += '"';
  }
  void value(const AttributeValue& v) {
    if (v.kind == AttributeValue::Kind::String) {
      quoted(v.text);
    } else {
      number(v.number);
    }
  }
  void valueList(const std::vector<ValueDescription>& values) {
    for (const auto& description : values) {
      m_out += ' ' + std::to_string(description.value) + ' ';
      quoted(description.text);
    }
  }

  void header() {
    m_out += "VERSION ";
    quoted(m_db.version);
    m_out += "\n\nNS_ :\n";
    for (const auto& symbol : m_db.newSymbols) m_out += "\t" + symbol + "\n";
    m_out += "\nBS_:\n\nBU_:";
    for (const Node& node : m_db.nodes) m_out += ' ' + node.name;
    m_out += "\n";
  }

  void message(const Message& msg) {
    m_out += "BO_ " + std::to_string(msg.declaredId) + ' ' + msg.name + ": " + std::to_string(msg.length) + ' ' +
             msg.transmitter + '\n';
    for (const Signal& sig : msg.signals) {
      m_out += " SG_ " + sig.name + ' ';
      switch (sig.muxRole) {
        case MuxRole::None: break;
        case MuxRole::Multiplexor: m_out += "M "; break;
        case MuxRole::Multiplexed: m_out += 'm' + std::to_string(sig.muxValue) + ' '; break;
        case MuxRole::MultiplexedMultiplexor: m_out += 'm' + std::to_string(sig.muxValue) + "M "; break;
      }
      m_out += ": " + std::to_string(sig.startBit) + '|' + std::to_string(sig.size) + '@' +
               (sig.byteOrder == ByteOrder::LittleEndian ? '1' : '0') + (sig.isSigned ? '-' : '+') + " (";
      number(sig.factor);
      m_out += ',';
      number(sig.offset);
      m_out += ") [";
      number(sig.minimum);
      m_out += '|';
      number(sig.maximum);
      m_out += "] ";
      quoted(sig.unit);
      for (std::size_t i = 0; i < sig.receivers.size(); ++i) m_out += (i == 0 ? " " : ",") + sig.receivers[i];
      m_out += '\n';
    }
    m_out += '\n';
  }

  void environment() {
    for (const auto& env : m_db.environmentVariables) {
      m_out += "EV_ " + env.name + ": " + std::to_string(env.type) + " [";
      number(env.minimum);
      m_out += '|';
      number(env.maximum);
      m_out += "] ";
      quoted(env.unit);
      m_out += ' ';
      number(env.initialValue);
      m_out += ' ' + std::to_string(env.id) + ' ' + env.accessType;
      for (std::size_t i = 0; i < env.accessNodes.size(); ++i) m_out += (i == 0 ? " " : ",") + env.accessNodes[i];
      m_out += ";\n";
    }
    for (const auto& env : m_db.environmentVariables) {
      if (env.dataSize) m_out += "ENVVAR_DATA_ " + env.name + ": " + std::to_string(*env.dataSize) + ";\n";
    }
  }

  // "CM_ <target>"<text>";" for a non-empty comment; nothing for an empty one.
  void comment(const std::string& target, const std::string& text) {
    if (text.empty()) return;
    m_out += "CM_ " + target;
    quoted(text);
    m_out += ";\n";
  }

  void comments() {
    comment("", m_db.comment);
    for (const Node& node : m_db.nodes) comment("BU_ " + node.name + ' ', node.comment);
    for (const Message& msg : m_db.messages) {
      const std::string id = std::to_string(msg.declaredId);
      comment("BO_ " + id + ' ', msg.comment);
      for (const Signal& sig : msg.signals) comment("SG_ " + id + ' ' + sig.name + ' ', sig.comment);
    }
    for (const auto& env : m_db.environmentVariables) comment("EV_ " + env.name + ' ', env.comment);
  }

  static bool isRelation(ObjectType object) {
    return object == ObjectType::NodeSignalRelation || object == ObjectType::NodeMessageRelation ||
           object == ObjectType::NodeEnvRelation;
  }

  void attributeDefinitions() {
    for (const auto& def : m_db.attributeDefinitions) {
      m_out += isRelation(def.object) ? "BA_DEF_REL_ " : "BA_DEF_ ";
      if (def.object != ObjectType::Network) m_out += std::string(toString(def.object)) + ' ';
      quoted(def.name);
      switch (def.type) {
        case AttributeType::Int: m_out += " INT "; break;
        case AttributeType::Hex: m_out += " HEX "; break;
        case AttributeType::Float: m_out += " FLOAT "; break;
        case AttributeType::String: m_out += " STRING"; break;
        case AttributeType::Enum: m_out += " ENUM "; break;
      }
      if (def.type == AttributeType::Int || def.type == AttributeType::Hex || def.type == AttributeType::Float) {
        number(def.minimum);
        m_out += ' ';
        number(def.maximum);
      }
      for (std::size_t i = 0; i < def.enumValues.size(); ++i) {
        if (i > 0) m_out += ',';
        quoted(def.enumValues[i]);
      }
      m_out += ";\n";
    }
    // One BA_DEF_DEF_ per name: it applies to every definition of that name.
    std::vector<std::pair<std::string, bool>> written;
    for (const auto& def : m_db.attributeDefinitions) {
      if (!def.defaultValue) continue;
      const std::pair<std::string, bool> key{def.name, isRelation(def.object)};
      if (std::find(written.begin(), written.end(), key) != written.end()) continue;
      written.push_back(key);
      m_out += isRelation(def.object) ? "BA_DEF_DEF_REL_ " : "BA_DEF_DEF_ ";
      quoted(def.name);
      m_out += ' ';
      value(*def.defaultValue);
      m_out += ";\n";
    }
  }

  void attributeLine(const std::string& name, const std::string& target, const AttributeValue& v) {
    m_out += "BA_ ";
    quoted(name);
    m_out += target + ' ';
    value(v);
    m_out += ";\n";
  }

  void attributeValues() {
    for (const auto& [name, v] : m_db.networkAttributes) attributeLine(name, "", v);
    for (const Node& node : m_db.nodes) {
      for (const auto& [name, v] : node.attributes) attributeLine(name, " BU_ " + node.name, v);
    }
    for (const Message& msg : m_db.messages) {
      for (const auto& [name, v] : msg.attributes) attributeLine(name, " BO_ " + std::to_string(msg.declaredId), v);
      for (const Signal& sig : msg.signals) {
        for (const auto& [name, v] : sig.attributes) {
          attributeLine(name, " SG_ " + std::to_string(msg.declaredId) + ' ' + sig.name, v);
        }
      }
    }
    for (const auto& env : m_db.environmentVariables) {
      for (const auto& [name, v] : env.attributes) attributeLine(name, " EV_ " + env.name, v);
    }
    for (const auto& rel : m_db.relationAttributes) {
      m_out += "BA_REL_ ";
      quoted(rel.name);
      m_out += ' ' + std::string(toString(rel.relation)) + ' ' + rel.node + ' ';
      if (rel.relation == ObjectType::NodeSignalRelation) {
        m_out += "SG_ " + std::to_string(rel.messageId) + ' ' + rel.target + ' ';
      } else if (rel.relation == ObjectType::NodeMessageRelation) {
        m_out += std::to_string(rel.messageId) + ' ';
      } else {
        m_out += rel.target + ' ';
      }
      value(rel.value);
      m_out += ";\n";
    }
  }

  void valueDescriptions() {
    for (const Message& msg : m_db.messages) {
      for (const Signal& sig : msg.signals) {
        if (sig.valueDescriptions.empty()) continue;
        m_out += "VAL_ " + std::to_string(msg.declaredId) + ' ' + sig.name;
        valueList(sig.valueDescriptions);
        m_out += " ;\n";
      }
    }
    for (const auto& env : m_db.environmentVariables) {
      if (env.valueDescriptions.empty()) continue;
      m_out += "VAL_ " + env.name;
      valueList(env.valueDescriptions);
      m_out += " ;\n";
    }
  }

  void signalGroups() {
    for (const auto& group : m_db.signalGroups) {
      m_out += "SIG_GROUP_ " + std::to_string(group.messageId) + ' ' + group.name + ' ' +
               std::to_string(group.repetitions) + " :";
      for (const auto& sig : group.signals) m_out += ' ' + sig;
      m_out += ";\n";
    }
  }

  void valueTypes() {
    for (const Message& msg : m_db.messages) {
      for (const Signal& sig : msg.signals) {
        if (sig.valueType == ValueType::Integer) continue;
        m_out += "SIG_VALTYPE_ " + std::to_string(msg.declaredId) + ' ' + sig.name + " : " +
                 (sig.valueType == ValueType::Float32 ? "1" : "2") + ";\n";
      }
    }
  }

  void muxValues() {
    for (const Message& msg : m_db.messages) {
      for (const Signal& sig : msg.signals) {
        if (!sig.extendedMux) continue;
        m_out += "SG_MUL_VAL_ " + std::to_string(msg.declaredId) + ' ' + sig.name + ' ' + sig.muxSwitch;
        for (std::size_t i = 0; i < sig.muxRanges.size(); ++i) {
          m_out += (i == 0 ? " " : ", ") + std::to_string(sig.muxRanges[i].low) + '-' +
                   std::to_string(sig.muxRanges[i].high);
        }
        m_out += ";\n";
      }
    }
  }

  const Database& m_db;
  std::string m_out;
};

}  // namespace

std::string write(const Database& database) { return Writer(database).run(); }

}  // namespace openvcu::dbc
