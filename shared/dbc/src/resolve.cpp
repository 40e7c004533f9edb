// Applies the references collected while parsing (CM_, BA_, VAL_, SIG_VALTYPE_,
// SG_MUL_VAL_, BO_TX_BU_), classifies IDs and resolves multiplexing.
#include "openvcu/dbc/codec.hpp"
#include "openvcu/j1939/id.hpp"
#include "parser_state.hpp"

#include <algorithm>
#include <bitset>
#include <cstdio>
#include <unordered_map>
#include <unordered_set>

namespace openvcu::dbc::detail {
namespace {

std::string hexId(std::uint32_t id) {
  char buffer[16];
  std::snprintf(buffer, sizeof buffer, "0x%X", id);
  return buffer;
}

class Resolver {
 public:
  Resolver(Database& db, PendingState& pending, std::string_view file, std::vector<Error>& diagnostics)
      : m_db(db), m_pending(pending), m_file(file), m_diagnostics(diagnostics) {}

  void run() {
    classifyIds();
    indexMessages();
    checkAttributeDefinitions();
    for (auto& item : m_pending.transmitters) applyTransmitters(item);
    for (auto& item : m_pending.comments) applyComment(item);
    for (auto& item : m_pending.values) applyValues(item);
    for (auto& item : m_pending.valueTypes) applyValueType(item);
    for (auto& item : m_pending.attributes) applyAttribute(item);
    for (auto& item : m_pending.muxes) applyMux(item);
    for (std::size_t i = 0; i < m_db.messages.size(); ++i) resolveMultiplexing(i);
    for (std::size_t i = 0; i < m_db.messages.size(); ++i) {
      checkLayout(i);
      checkMultiplexorCount(i);
      checkOverlaps(i);
    }
    m_db.reindex();
  }

 private:
  void report(Where where, std::string message, Severity severity) {
    // Names quoted from the file may hold any byte: escaped, one printable line.
    m_diagnostics.push_back(
        Error{escapeControlCharacters(message), Location{std::string(m_file), where.line, where.column, {}}, severity});
  }
  void error(Where where, std::string message) { report(where, std::move(message), Severity::Error); }
  void warning(Where where, std::string message) { report(where, std::move(message), Severity::Warning); }

  /// BO_ IDs: bit 31 flags a 29-bit ID; a number above 0x7FF without it is a 29-bit ID
  /// written without the flag (opendbc does this); bits 29/30 make it no CAN ID at all.
  void classifyIds() {
    for (std::size_t i = 0; i < m_db.messages.size(); ++i) {
      Message& msg = m_db.messages[i];
      const std::uint32_t declared = msg.declaredId;
      const bool flagged = (declared & 0x80000000u) != 0;
      const std::uint32_t withoutFlag = declared & 0x7FFFFFFFu;
      if (msg.name == INDEPENDENT_SIGNALS || (withoutFlag & 0x60000000u) != 0) {
        msg.pseudo = true;
        msg.extended = flagged;
        msg.id = withoutFlag & 0x1FFFFFFFu;
        if (msg.name != INDEPENDENT_SIGNALS) {
          warning(m_pending.messageLines[i], "message '" + msg.name + "' has ID " + hexId(declared) +
                                                 " with bit 29 or 30 set: not a CAN identifier; kept but never matched");
        }
        continue;
      }
      msg.extended = flagged || withoutFlag > 0x7FFu;
      msg.id = withoutFlag;
    }
  }

  void indexMessages() {
    std::unordered_map<std::string_view, std::size_t> messageNames;
    for (std::size_t i = 0; i < m_db.messages.size(); ++i) {
      const Message& msg = m_db.messages[i];
      // Names are how configuration, tools and the signal catalog ("Message.Signal") refer
      // to messages: a second message of one name would make them ambiguous.
      if (const auto [first, inserted] = messageNames.emplace(msg.name, i); !inserted) {
        error(m_pending.messageLines[i], "message name '" + msg.name + "' is used twice (ID " + hexId(msg.declaredId) +
                                             " here, ID " + hexId(m_db.messages[first->second].declaredId) +
                                             " at line " + std::to_string(m_pending.messageLines[first->second].line) +
                                             ")");
      }
      const auto [it, inserted] = m_byDeclared.emplace(msg.declaredId, i);
      if (!inserted) {
        warning(m_pending.messageLines[i], "message '" + msg.name + "' repeats ID " + hexId(msg.declaredId) +
                                               " of '" + m_db.messages[it->second].name +
                                               "'; references by ID resolve to the first");
      }
      // 29-bit IDs written without the flag are referenced either way by CM_/BA_/VAL_.
      if (msg.extended) m_byDeclared.emplace(msg.id | 0x80000000u, i);
      if (msg.extended) m_byDeclared.emplace(msg.id, i);
      std::unordered_map<std::string, std::size_t> names;
      for (std::size_t s = 0; s < msg.signals.size(); ++s) {
        if (!names.emplace(msg.signals[s].name, s).second) {
          warning(m_pending.signalWhere[i][s], "signal '" + msg.signals[s].name + "' defined twice in message '" + msg.name +
                                                   "'; references by name (CM_, BA_, VAL_) resolve to the first");
        }
      }
    }
  }

  /// BA_DEF_ given twice for one name and object type: the first definition holds (it is
  /// what values are checked against and defaults come from), so a second one with another
  /// type or ENUM list is an error, as it is when merging files.
  void checkAttributeDefinitions() {
    const auto& definitions = m_db.attributeDefinitions;
    std::unordered_map<std::string, std::size_t> firstOf;
    for (std::size_t i = 0; i < definitions.size(); ++i) {
      const AttributeDefinition& def = definitions[i];
      const std::string key = std::string(toString(def.object)) + '\n' + def.name;
      const auto [it, inserted] = firstOf.emplace(key, i);
      if (inserted) continue;
      const AttributeDefinition& first = definitions[it->second];
      if (first.type == def.type && (def.type != AttributeType::Enum || first.enumValues == def.enumValues)) continue;
      error(Where{def.source.line, 0}, "attribute '" + def.name + "' (" + std::string(toString(def.object)) +
                                            ") defined again with another " +
                                            (first.type == def.type ? "ENUM list" : "type") + " (first at line " +
                                            std::to_string(first.source.line) + ")");
    }
  }

  Message* findMessage(std::uint32_t declaredId, Where where, std::string_view statement) {
    const auto it = m_byDeclared.find(declaredId);
    if (it == m_byDeclared.end()) {
      warning(where, std::string(statement) + " refers to undefined message ID " + std::to_string(declaredId) + "; ignored");
      return nullptr;
    }
    return &m_db.messages[it->second];
  }

  Signal* findSignal(std::uint32_t declaredId, const std::string& name, Where where, std::string_view statement) {
    Message* msg = findMessage(declaredId, where, statement);
    if (!msg) return nullptr;
    for (Signal& sig : msg->signals) {
      if (sig.name == name) return &sig;
    }
    warning(where, std::string(statement) + " refers to undefined signal '" + name + "' of message '" + msg->name + "'; ignored");
    return nullptr;
  }

  Node* findNode(const std::string& name, Where where, std::string_view statement) {
    for (Node& node : m_db.nodes) {
      if (node.name == name) return &node;
    }
    warning(where, std::string(statement) + " refers to undefined node '" + name + "'; ignored");
    return nullptr;
  }

  EnvironmentVariable* findEnv(const std::string& name, Where where, std::string_view statement) {
    for (EnvironmentVariable& env : m_db.environmentVariables) {
      if (env.name == name) return &env;
    }
    warning(where, std::string(statement) + " refers to undefined environment variable '" + name + "'; ignored");
    return nullptr;
  }

  void applyTransmitters(const PendingTransmitters& item) {
    Message* msg = findMessage(item.messageId, item.where, "BO_TX_BU_");
    if (!msg) return;
    for (const auto& node : item.nodes) msg->extraTransmitters.push_back(node);
  }

  void applyComment(const PendingComment& item) {
    const Target& t = item.target;
    switch (t.object) {
      case ObjectType::Network:
        m_db.comment = item.text;  // several network comments: the last wins, as in Vector tools
        break;
      case ObjectType::Node:
        if (Node* node = findNode(t.name, item.where, "CM_")) node->comment = item.text;
        break;
      case ObjectType::Message:
        if (Message* msg = findMessage(t.messageId, item.where, "CM_")) msg->comment = item.text;
        break;
      case ObjectType::Signal:
        if (Signal* sig = findSignal(t.messageId, t.signal, item.where, "CM_")) sig->comment = item.text;
        break;
      case ObjectType::EnvironmentVariable:
        if (EnvironmentVariable* env = findEnv(t.name, item.where, "CM_")) env->comment = item.text;
        break;
      default:
        break;
    }
  }

  void applyValues(PendingValues& item) {
    if (item.target.object == ObjectType::Signal) {
      if (Signal* sig = findSignal(item.target.messageId, item.target.signal, item.where, "VAL_")) {
        sig->valueDescriptions = std::move(item.values);
      }
    } else if (EnvironmentVariable* env = findEnv(item.target.name, item.where, "VAL_")) {
      env->valueDescriptions = std::move(item.values);
    }
  }

  void applyValueType(const PendingValueType& item) {
    Signal* sig = findSignal(item.messageId, item.signal, item.where, "SIG_VALTYPE_");
    if (!sig) return;
    sig->valueType = item.type == 1 ? ValueType::Float32 : item.type == 2 ? ValueType::Float64 : ValueType::Integer;
    const std::uint32_t needed = item.type == 1 ? 32 : item.type == 2 ? 64 : 0;
    if (needed != 0 && sig->size != needed) {
      warning(item.where, "signal '" + sig->name + "' is " + std::to_string(sig->size) + " bits but SIG_VALTYPE_ " +
                              std::to_string(item.type) + " needs " + std::to_string(needed) + "; not decodable");
    }
  }

  void applyAttribute(PendingAttribute& item) {
    const Target& t = item.target;
    const AttributeDefinition* def = m_db.findAttributeDefinition(item.name, t.object);
    if (!def) {
      warning(item.where, "value for undefined attribute '" + item.name + "' (" + std::string(toString(t.object)) + ")");
    } else {
      checkAttributeValue(*def, item.value, item.where);
    }
    Attributes* into = nullptr;
    switch (t.object) {
      case ObjectType::Network: into = &m_db.networkAttributes; break;
      case ObjectType::Node:
        if (Node* node = findNode(t.name, item.where, "BA_")) into = &node->attributes;
        break;
      case ObjectType::Message:
        if (Message* msg = findMessage(t.messageId, item.where, "BA_")) into = &msg->attributes;
        break;
      case ObjectType::Signal:
        if (Signal* sig = findSignal(t.messageId, t.signal, item.where, "BA_")) into = &sig->attributes;
        break;
      case ObjectType::EnvironmentVariable:
        if (EnvironmentVariable* env = findEnv(t.name, item.where, "BA_")) into = &env->attributes;
        break;
      default: break;
    }
    if (into) (*into)[item.name] = std::move(item.value);
  }

  void checkAttributeValue(const AttributeDefinition& def, const AttributeValue& value, Where where) {
    const bool wantsString = def.type == AttributeType::String;
    if (def.type == AttributeType::Enum) {
      if (value.kind == AttributeValue::Kind::Number &&
          (value.number < 0 || value.number >= static_cast<double>(def.enumValues.size()))) {
        warning(where, "attribute '" + def.name + "' value " + std::to_string(static_cast<long long>(value.number)) +
                           " is not an index of its ENUM list");
      }
      return;
    }
    if (wantsString != (value.kind == AttributeValue::Kind::String)) {
      warning(where, "attribute '" + def.name + "' expects " + (wantsString ? "a string" : "a number"));
    }
  }

  void applyMux(const PendingMux& item) {
    Signal* sig = findSignal(item.messageId, item.signal, item.where, "SG_MUL_VAL_");
    if (!sig) return;
    const Message* msg = findMessage(item.messageId, item.where, "SG_MUL_VAL_");
    if (!msg->findSignal(item.switchName)) {
      error(item.where, "SG_MUL_VAL_ names multiplexor '" + item.switchName + "' that message '" + msg->name + "' does not have");
      return;
    }
    sig->muxSwitch = item.switchName;
    sig->muxRanges = item.ranges;
    sig->extendedMux = true;
  }

  void resolveMultiplexing(std::size_t messageIndex) {
    Message& msg = m_db.messages[messageIndex];
    // Roots select without being selected. An "M" with its own SG_MUL_VAL_ is a nested
    // multiplexor written the way cantools dumps it (instead of "mNM").
    std::vector<const Signal*> roots;
    for (const Signal& sig : msg.signals) {
      if (sig.muxRole == MuxRole::Multiplexor && !sig.extendedMux) roots.push_back(&sig);
    }
    for (std::size_t s = 0; s < msg.signals.size(); ++s) {
      Signal& sig = msg.signals[s];
      const Where where = m_pending.signalWhere[messageIndex][s];
      const bool multiplexed = sig.muxRole == MuxRole::Multiplexed || sig.muxRole == MuxRole::MultiplexedMultiplexor;
      if (!multiplexed) {
        if (sig.extendedMux && sig.muxRole == MuxRole::Multiplexor && sig.muxSwitch != sig.name) continue;
        if (sig.extendedMux) {
          warning(where, "SG_MUL_VAL_ for '" + sig.name + "', which is not multiplexed (no mN); ignored");
          sig.extendedMux = false;
          sig.muxSwitch.clear();
          sig.muxRanges.clear();
        }
        continue;
      }
      if (sig.muxSwitch.empty()) {
        if (roots.empty()) {
          warning(where, "multiplexed signal '" + sig.name + "' but message '" + msg.name + "' has no multiplexor (M); not decodable");
          continue;
        }
        if (roots.size() > 1) {
          warning(where, "message '" + msg.name + "' has several multiplexors and no SG_MUL_VAL_ for '" + sig.name +
                             "'; using '" + roots.front()->name + "'");
        }
        sig.muxSwitch = roots.front()->name;
      }
      const Signal* sw = msg.findSignal(sig.muxSwitch);
      if (sw && sw->muxRole != MuxRole::Multiplexor && sw->muxRole != MuxRole::MultiplexedMultiplexor) {
        warning(where, "'" + sig.name + "' is selected by '" + sw->name + "', which is not marked as multiplexor (M)");
      }
    }
    // A selection chain must end at a root: a cycle would select nothing ever.
    for (std::size_t s = 0; s < msg.signals.size(); ++s) {
      const Signal* cursor = &msg.signals[s];
      std::size_t steps = 0;
      while (cursor && !cursor->muxSwitch.empty() && steps <= msg.signals.size()) {
        cursor = msg.findSignal(cursor->muxSwitch);
        ++steps;
      }
      if (steps > msg.signals.size()) {
        error(m_pending.signalWhere[messageIndex][s], "multiplexor chain of '" + msg.signals[s].name + "' loops");
        msg.signals[s].muxSwitch.clear();
      }
    }
  }

  /// Layout checks: sizes, bits outside the frame.
  void checkLayout(std::size_t messageIndex) {
    Message& msg = m_db.messages[messageIndex];
    if (msg.pseudo) return;
    const std::uint64_t frameBits = static_cast<std::uint64_t>(msg.length) * 8;
    for (std::size_t s = 0; s < msg.signals.size(); ++s) {
      const Signal& sig = msg.signals[s];
      const Where where = m_pending.signalWhere[messageIndex][s];
      if (sig.size == 0) {
        error(where, "signal '" + sig.name + "' has size 0");
        continue;
      }
      if (sig.size > 64) {
        warning(where, "signal '" + sig.name + "' is " + std::to_string(sig.size) + " bits: loaded, not decodable (limit 64)");
      }
      // Highest bit index the signal touches in LSB0 numbering.
      std::uint64_t lowestByte = 0;
      std::uint64_t highestByte = 0;
      if (sig.byteOrder == ByteOrder::LittleEndian) {
        lowestByte = sig.startBit / 8;
        highestByte = (static_cast<std::uint64_t>(sig.startBit) + sig.size - 1) / 8;
      } else {
        lowestByte = sig.startBit / 8;
        const std::uint64_t msbLinear = (sig.startBit / 8) * 8 + (7 - sig.startBit % 8);
        highestByte = (msbLinear + sig.size - 1) / 8;
      }
      if ((highestByte + 1) * 8 > frameBits) {
        warning(where, "signal '" + sig.name + "' (bytes " + std::to_string(lowestByte) + ".." + std::to_string(highestByte) +
                           ") lies outside the " + std::to_string(msg.length) + "-byte message '" + msg.name +
                           "'; decoded only from longer frames");
      }
      if (sig.factor == 0.0) warning(where, "signal '" + sig.name + "' has factor 0");
    }
  }

  /// The codec decodes the signals of at most MessageCodec::MAX_MUX_SLOTS multiplexors per
  /// message; the signals of any further multiplexor would be skipped without a word.
  void checkMultiplexorCount(std::size_t messageIndex) {
    const Message& msg = m_db.messages[messageIndex];
    if (msg.pseudo) return;
    std::unordered_set<std::string_view> switches;
    for (const Signal& sig : msg.signals) {
      if (!sig.muxSwitch.empty()) switches.insert(sig.muxSwitch);
    }
    if (switches.size() <= MessageCodec::MAX_MUX_SLOTS) return;
    warning(m_pending.messageLines[messageIndex],
            "message '" + msg.name + "' has " + std::to_string(switches.size()) + " multiplexors; only the signals of " +
                std::to_string(MessageCodec::MAX_MUX_SLOTS) +
                " of them can be decoded (the codec's limit per message), the others are not decodable");
  }

  /// The bits a signal occupies, as a mask over its byte window (at most 9 bytes for a
  /// signal of up to 64 bits), LSB0 numbering: bit k of the mask = frame bit lowByte*8 + k.
  /// Room for a second window that starts up to 8 bytes later, shifted onto this one.
  static constexpr std::size_t MASK_BITS = 9 * 8 + 8 * 8;
  using Mask = std::bitset<MASK_BITS>;
  struct BitWindow {
    std::uint64_t lowByte{};
    std::uint64_t highByte{};
    Mask mask;
  };
  static BitWindow bitWindow(const Signal& sig) {
    BitWindow window;
    window.lowByte = sig.startBit / 8;
    const std::uint64_t base = window.lowByte * 8;
    if (sig.byteOrder == ByteOrder::LittleEndian) {
      for (std::uint64_t k = 0; k < sig.size; ++k) window.mask.set(sig.startBit + k - base);
      window.highByte = (std::uint64_t{sig.startBit} + sig.size - 1) / 8;
    } else {
      // Motorola: MSB at the start bit, then towards lower bits and on into the next byte.
      const std::uint64_t msbLinear = base + (7 - sig.startBit % 8);
      for (std::uint64_t k = 0; k < sig.size; ++k) {
        const std::uint64_t linear = msbLinear + k;
        const std::uint64_t position = (linear / 8) * 8 + (7 - linear % 8);
        window.mask.set(position - base);
      }
      window.highByte = (msbLinear + sig.size - 1) / 8;
    }
    return window;
  }

  /// The conditions under which a signal is present: (multiplexor index, ranges) from its
  /// own selector up the chain. Empty for a signal that is always present.
  struct Condition {
    std::size_t switchIndex{};
    std::vector<MuxRange> ranges;
  };
  static std::vector<Condition> presence(const Message& msg, std::size_t signalIndex) {
    std::vector<Condition> conditions;
    const Signal* cursor = &msg.signals[signalIndex];
    while (!cursor->muxSwitch.empty() && conditions.size() <= msg.signals.size()) {
      const Signal* sw = msg.findSignal(cursor->muxSwitch);
      if (!sw) break;
      Condition condition;
      condition.switchIndex = static_cast<std::size_t>(sw - msg.signals.data());
      condition.ranges = cursor->muxRanges.empty() ? std::vector<MuxRange>{MuxRange{cursor->muxValue, cursor->muxValue}}
                                                   : cursor->muxRanges;
      conditions.push_back(std::move(condition));
      cursor = sw;
    }
    return conditions;
  }
  /// Can both be present in one frame: no multiplexor both depend on selects them with
  /// values that exclude each other.
  static bool canCoexist(const std::vector<Condition>& a, const std::vector<Condition>& b) {
    for (const Condition& ca : a) {
      for (const Condition& cb : b) {
        if (ca.switchIndex != cb.switchIndex) continue;
        bool shared = false;
        for (const MuxRange& ra : ca.ranges) {
          for (const MuxRange& rb : cb.ranges) shared = shared || (ra.low <= rb.high && rb.low <= ra.high);
        }
        if (!shared) return false;
      }
    }
    return true;
  }

  /// Signals that share a bit and can be present in the same frame (multiplexing
  /// respected): a warning at the later one. Both still decode as written; encoding one
  /// changes the other. Up to MAX_OVERLAPS_SHOWN pairs per message are named.
  void checkOverlaps(std::size_t messageIndex) {
    static constexpr std::size_t MAX_OVERLAPS_SHOWN = 16;
    const Message& msg = m_db.messages[messageIndex];
    if (msg.pseudo) return;
    std::vector<std::size_t> order;
    std::vector<BitWindow> windows(msg.signals.size());
    for (std::size_t s = 0; s < msg.signals.size(); ++s) {
      const Signal& sig = msg.signals[s];
      if (sig.size == 0 || sig.size > 64) continue;  // reported by checkLayout
      windows[s] = bitWindow(sig);
      order.push_back(s);
    }
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
      return windows[a].lowByte < windows[b].lowByte || (windows[a].lowByte == windows[b].lowByte && a < b);
    });
    std::vector<std::vector<Condition>> conditions(msg.signals.size());
    std::vector<bool> known(msg.signals.size(), false);
    auto conditionsOf = [&](std::size_t s) -> const std::vector<Condition>& {
      if (!known[s]) {
        conditions[s] = presence(msg, s);
        known[s] = true;
      }
      return conditions[s];
    };
    std::size_t found = 0;
    for (std::size_t i = 0; i < order.size(); ++i) {
      const std::size_t a = order[i];
      for (std::size_t j = i + 1; j < order.size() && windows[order[j]].lowByte <= windows[a].highByte; ++j) {
        const std::size_t b = order[j];
        // b starts at most 8 bytes after a (their windows meet): shifted onto a's window.
        const std::size_t shift = static_cast<std::size_t>((windows[b].lowByte - windows[a].lowByte) * 8);
        const Mask common = windows[a].mask & (windows[b].mask << shift);
        if (common.none() || !canCoexist(conditionsOf(a), conditionsOf(b))) continue;
        ++found;
        if (found > MAX_OVERLAPS_SHOWN) continue;
        std::size_t lowest = 0;
        while (!common.test(lowest)) ++lowest;
        const std::uint64_t bit = windows[a].lowByte * 8 + lowest;
        const std::size_t first = std::min(a, b);
        const std::size_t later = std::max(a, b);
        warning(m_pending.signalWhere[messageIndex][later],
                "signals '" + msg.signals[first].name + "' and '" + msg.signals[later].name + "' of message '" +
                    msg.name + "' overlap (bit " + std::to_string(bit) +
                    ") and can be present together; encoding one changes the other");
      }
    }
    if (found > MAX_OVERLAPS_SHOWN) {
      warning(m_pending.messageLines[messageIndex], "message '" + msg.name + "' has " +
                                                        std::to_string(found - MAX_OVERLAPS_SHOWN) +
                                                        " more overlapping signal pairs");
    }
  }

  Database& m_db;
  PendingState& m_pending;
  std::string_view m_file;
  std::vector<Error>& m_diagnostics;
  std::unordered_map<std::uint32_t, std::size_t> m_byDeclared;
};

}  // namespace

void resolve(Database& database, PendingState& pending, std::string_view fileName, std::vector<Error>& diagnostics) {
  Resolver(database, pending, fileName, diagnostics).run();
}

}  // namespace openvcu::dbc::detail
