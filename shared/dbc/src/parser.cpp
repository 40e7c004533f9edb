// DBC statement parser: text -> Database (+ pending references resolved in resolve.cpp).
#include "openvcu/dbc/parser.hpp"

#include "openvcu/core/input_file.hpp"
#include "openvcu/core/text.hpp"
#include "parser_state.hpp"
#include "scanner.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <unordered_set>

namespace openvcu::dbc {
namespace {

using detail::PendingState;
using detail::Scanner;
using detail::Target;
using detail::Where;

constexpr std::size_t MAX_DIAGNOSTICS = 1000;
/// Statements between two checks for a pending stop signal (one system call each).
constexpr std::size_t STOP_CHECK_STATEMENTS = 4096;

bool isKeyword(std::string_view word) noexcept { return detail::isStatementKeyword(word); }

class Parser {
 public:
  Parser(std::string_view text, std::string_view fileName, ParseOutput& out)
      : m_scan(text), m_file(fileName), m_out(out) {}

  void run() {
    std::size_t statements = 0;
    while (true) {
      m_scan.skipSpace();
      if (m_scan.atEnd()) break;
      // A service blocks SIGTERM while it loads its DBCs (the largest allowed file takes
      // seconds): a pending one ends the parse, the file is refused (issue 19).
      if (++statements % STOP_CHECK_STATEMENTS == 0 && input::stopSignalPending()) {
        error(m_scan.position(), "reading stopped: SIGTERM or SIGINT is pending");
        return;
      }
      if (m_out.diagnostics.size() >= MAX_DIAGNOSTICS) {
        error(m_scan.position(), "too many errors; giving up");
        break;
      }
      const std::size_t start = m_scan.position();
      const std::string_view keyword = m_scan.word();
      if (keyword.empty()) {
        error(start, std::string("unexpected character '") + printable(m_scan.peek()) + "'");
        resync();
        continue;
      }
      const std::size_t before = m_out.diagnostics.size();
      if (!statement(keyword, start)) {
        // A malformed comment changes no layout: report it, keep the file.
        if (keyword == "CM_") {
          for (std::size_t i = before; i < m_out.diagnostics.size(); ++i) {
            m_out.diagnostics[i].severity = Severity::Warning;
            m_out.diagnostics[i].message += "; comment ignored";
          }
        }
        resync();
      }
      reportScannerProblems();
    }
    reportScannerProblems();
    applyDefaults();
    detail::resolve(m_out.database, m_pending, m_file, m_out.diagnostics);
  }

 private:
  // ------------------------------------------------------------ diagnostics
  /// Unterminated strings and comments are errors even inside a CM_ (whose own problems
  /// are warnings): they would have swallowed the statements after them.
  void reportScannerProblems() {
    for (Scanner::Problem& problem : m_scan.takeProblems()) error(problem.position, std::move(problem.message));
  }
  Where where(std::size_t position) const {
    const auto [line, column] = m_scan.lineColumn(position);
    return Where{line, column};
  }
  void report(std::size_t position, std::string message, Severity severity) {
    const Where at = where(position);
    // Quoted names (attribute names, strings) may hold any byte: escaped so that a
    // diagnostic stays one printable line whoever prints it.
    m_out.diagnostics.push_back(
        Error{escapeControlCharacters(message), Location{std::string(m_file), at.line, at.column, {}}, severity});
  }
  void error(std::size_t position, std::string message) { report(position, std::move(message), Severity::Error); }
  void warning(std::size_t position, std::string message) { report(position, std::move(message), Severity::Warning); }
  /// Error at the current position (after skipping blanks) that names what was expected.
  bool expected(std::string_view what) {
    m_scan.skipBlanks();
    std::string found = m_scan.atLineEnd() ? "end of line" : std::string("'") + printable(m_scan.peek()) + "'";
    error(m_scan.position(), "expected " + std::string(what) + ", found " + found);
    return false;
  }
  static std::string printable(char c) {
    if (c == '\0') return "end of file";
    const auto u = static_cast<unsigned char>(c);
    if (u < 0x20 || u >= 0x7F) {
      static constexpr char HEX[] = "0123456789ABCDEF";
      return std::string("\\x") + HEX[u >> 4] + HEX[u & 0xF];
    }
    return std::string(1, c);
  }

  /// Skips to the next line whose first word is a statement keyword.
  void resync() {
    m_scan.skipLine();
    while (!m_scan.atEnd()) {
      const std::size_t lineStart = m_scan.position();
      m_scan.skipBlanks();
      const std::string_view next = m_scan.word();
      m_scan.setPosition(lineStart);
      if (!next.empty() && isKeyword(next)) return;
      m_scan.skipLine();
    }
  }

  /// Ends a ';'-terminated statement. A missing ';' is accepted (with a warning) when the
  /// next line starts a statement, as some generators omit it.
  bool terminate(std::string_view statementName) {
    if (m_scan.accept(';')) return true;
    const std::size_t here = m_scan.position();
    m_scan.skipSpace();
    const std::string_view next = m_scan.peekWord();
    if (m_scan.atEnd() || (m_scan.atLineStart() && isKeyword(next))) {
      warning(here, std::string(statementName) + " statement without ';'");
      return true;
    }
    m_scan.setPosition(here);
    return expected("';'");
  }

  // ------------------------------------------------------------ token helpers
  bool name(std::string& out, std::string_view what, bool acrossLines = true) {
    acrossLines ? m_scan.skipSpace() : m_scan.skipBlanks();
    const std::string_view w = m_scan.word();
    if (w.empty()) return expected(what);
    out.assign(w);
    return true;
  }
  bool punct(char c) {
    if (m_scan.accept(c)) return true;
    return expected(std::string("'") + c + "'");
  }
  bool number(double& out, std::string_view what) {
    m_scan.skipSpace();
    const std::size_t at = m_scan.position();
    bool outOfRange = false;
    const auto value = m_scan.number(&outOfRange);
    if (!value) return expected(what);
    if (outOfRange) warning(at, "number out of the double range; clamped");
    out = *value;
    return true;
  }
  bool messageId(std::uint32_t& out) {
    m_scan.skipSpace();
    const std::size_t at = m_scan.position();
    const auto value = m_scan.unsignedInteger();
    if (!value) return expected("message ID");
    if (*value > 0xFFFFFFFFull) {
      error(at, "message ID " + std::to_string(*value) + " exceeds 32 bits");
      return false;
    }
    out = static_cast<std::uint32_t>(*value);
    return true;
  }
  bool unsignedValue(std::uint32_t& out, std::string_view what) {
    m_scan.skipSpace();
    const std::size_t at = m_scan.position();
    const auto value = m_scan.unsignedInteger();
    if (!value) return expected(what);
    if (*value > 0xFFFFFFFFull) {
      error(at, std::string(what) + " too large");
      return false;
    }
    out = static_cast<std::uint32_t>(*value);
    return true;
  }
  bool quoted(std::string& out, std::string_view what) {
    m_scan.skipSpace();
    bool unterminated = false;
    auto value = m_scan.quoted(&unterminated);
    if (unterminated) return false;  // the scanner keeps the problem, reported as an error
    if (!value) return expected(what);
    out = std::move(*value);
    return true;
  }
  /// A number or a quoted string (attribute values).
  bool attributeValue(AttributeValue& out) {
    m_scan.skipSpace();
    if (m_scan.peek() == '"') {
      std::string text;
      if (!quoted(text, "attribute value")) return false;
      out = AttributeValue::fromString(std::move(text));
      return true;
    }
    double value = 0;
    if (!number(value, "attribute value (number or string)")) return false;
    out = AttributeValue::fromNumber(value);
    return true;
  }
  /// `value "text"` pairs until ';' (or a missing ';' before the next statement).
  bool valueDescriptions(std::vector<ValueDescription>& out) {
    while (true) {
      m_scan.skipSpace();
      if (m_scan.peek() == ';' || m_scan.atEnd()) return true;
      if (m_scan.atLineStart() && isKeyword(m_scan.peekWord())) return true;
      const std::size_t at = m_scan.position();
      double key = 0;
      if (!number(key, "value")) return false;
      if (key != std::floor(key) || std::fabs(key) > 9.2e18) {
        error(at, "value description key must be an integer");
        return false;
      }
      ValueDescription description;
      description.value = static_cast<std::int64_t>(key);
      if (!quoted(description.text, "value description text")) return false;
      out.push_back(std::move(description));
    }
  }
  /// A node list separated by blanks or commas, to the end of the line.
  void nodeList(std::vector<std::string>& out) {
    while (true) {
      m_scan.skipBlanks();
      if (m_scan.peek() == ',') {
        m_scan.setPosition(m_scan.position() + 1);
        continue;
      }
      const std::string_view w = m_scan.word();
      if (w.empty()) return;
      out.emplace_back(w);
    }
  }
  bool endOfLine(std::string_view statementName) {
    if (m_scan.atLineEnd()) return true;
    if (m_scan.peek() == ';') {  // tolerated: some writers end BO_/SG_ lines with ';'
      m_scan.setPosition(m_scan.position() + 1);
      if (m_scan.atLineEnd()) return true;
    }
    error(m_scan.position(), "unexpected text after " + std::string(statementName));
    return false;
  }

  /// Parses the object part of CM_ / BA_ (BU_ name, BO_ id, SG_ id name, EV_ name, or none).
  bool target(Target& out) {
    const std::string_view kind = m_scan.peekWord();
    if (kind == "BU_" || kind == "BO_" || kind == "SG_" || kind == "EV_") {
      m_scan.skipSpace();
      m_scan.word();
      if (kind == "BU_") {
        out.object = ObjectType::Node;
        return name(out.name, "node name");
      }
      if (kind == "EV_") {
        out.object = ObjectType::EnvironmentVariable;
        return name(out.name, "environment variable name");
      }
      if (!messageId(out.messageId)) return false;
      if (kind == "BO_") {
        out.object = ObjectType::Message;
        return true;
      }
      out.object = ObjectType::Signal;
      return name(out.signal, "signal name");
    }
    out.object = ObjectType::Network;
    return true;
  }

  // ------------------------------------------------------------ statements
  bool statement(std::string_view keyword, std::size_t start) {
    if (keyword == "VERSION") return version();
    if (keyword == "NS_") return newSymbols();
    if (keyword == "BS_") return bitTiming();
    if (keyword == "BU_") return nodes(start);
    if (keyword == "VAL_TABLE_") return valueTable();
    if (keyword == "BO_") return message(start);
    if (keyword == "SG_") {
      error(start, "SG_ outside a BO_ message");
      return false;
    }
    if (keyword == "BO_TX_BU_") return transmitters(start);
    if (keyword == "CM_") return comment(start);
    if (keyword == "BA_DEF_") return attributeDefinition(start, false);
    if (keyword == "BA_DEF_REL_") return attributeDefinition(start, true);
    if (keyword == "BA_DEF_DEF_") return attributeDefault(start, false);
    if (keyword == "BA_DEF_DEF_REL_") return attributeDefault(start, true);
    if (keyword == "BA_") return attribute(start);
    if (keyword == "BA_REL_") return relationAttribute(start);
    if (keyword == "VAL_") return values(start);
    if (keyword == "SIG_VALTYPE_") return valueType(start);
    if (keyword == "SIG_GROUP_") return signalGroup();
    if (keyword == "EV_") return environmentVariable();
    if (keyword == "ENVVAR_DATA_") return environmentData(start);
    if (keyword == "SG_MUL_VAL_") return muxValues(start);
    if (isKeyword(keyword)) {
      warning(start, std::string(keyword) + " statement is not used by openvcu; skipped");
      return skipStatement();
    }
    error(start, "unknown statement '" + std::string(keyword) + "'");
    return false;
  }

  /// Skips a statement openvcu does not use: to its ';' or the next statement line.
  bool skipStatement() {
    while (!m_scan.atEnd()) {
      m_scan.skipSpace();
      const char c = m_scan.peek();
      if (c == ';') {
        m_scan.setPosition(m_scan.position() + 1);
        return true;
      }
      if (m_scan.atLineStart() && isKeyword(m_scan.peekWord())) return true;
      if (c == '"') {
        if (!m_scan.quoted()) return true;
      } else if (m_scan.word().empty()) {
        m_scan.setPosition(m_scan.position() + 1);
      }
    }
    return true;
  }

  bool version() {
    m_scan.skipBlanks();
    if (m_scan.peek() != '"') return true;  // "VERSION" alone
    return quoted(m_out.database.version, "version string");
  }

  bool newSymbols() {
    if (!punct(':')) return false;
    // Entries are indented, one or more per line, until a line that is not indented.
    while (true) {
      const std::size_t saved = m_scan.position();
      m_scan.skipSpace();
      if (m_scan.atEnd()) return true;
      const std::size_t here = m_scan.position();
      const bool indented = m_scan.lineColumn(here).second > 1;
      const std::string_view w = m_scan.peekWord();
      if (!indented || w.empty() || w == "BS_" || w == "BU_") {
        m_scan.setPosition(saved);
        return true;
      }
      m_scan.word();
      m_out.database.newSymbols.emplace_back(w);
    }
  }

  bool bitTiming() {
    if (!m_scan.accept(':', false)) return expected("':'");
    // "BS_: 500 : 12,34" is legal but unused; skip to the end of the line.
    m_scan.skipBlanks();
    if (!m_scan.atLineEnd()) m_scan.skipLine();
    return true;
  }

  bool nodes(std::size_t start) {
    if (!punct(':')) return false;
    // Node names may continue on indented lines (tesla_can.dbc), up to the next statement;
    // a line starting in column 1 is the next statement, even a misspelt one.
    const std::uint32_t statementLine = where(start).line;
    while (true) {
      m_scan.skipSpace();
      if (m_scan.atEnd()) return true;
      const std::size_t at = m_scan.position();
      const Where here = where(at);
      if (here.line != statementLine && here.column == 1) return true;
      const std::string_view w = m_scan.peekWord();
      if (w.empty() || isKeyword(w)) return true;
      m_scan.word();
      if (!m_nodeNames.emplace(w).second) warning(at, "node '" + std::string(w) + "' listed twice in BU_");
      Node node;
      node.name.assign(w);
      m_out.database.nodes.push_back(std::move(node));
    }
  }

  bool valueTable() {
    ValueTable table;
    if (!name(table.name, "value table name")) return false;
    if (!valueDescriptions(table.values)) return false;
    if (!terminate("VAL_TABLE_")) return false;
    m_out.database.valueTables.push_back(std::move(table));
    return true;
  }

  bool message(std::size_t start) {
    Message msg;
    if (!messageId(msg.declaredId)) return false;
    if (!name(msg.name, "message name")) return false;
    if (!punct(':')) return false;
    if (!unsignedValue(msg.length, "message length")) return false;
    m_scan.skipBlanks();
    msg.transmitter.assign(m_scan.word());
    if (!endOfLine("BO_")) return false;
    msg.source.line = where(start).line;
    std::vector<Where> signalLines;
    // Its SG_ lines follow.
    while (true) {
      const std::size_t saved = m_scan.position();
      m_scan.skipSpace();
      const std::size_t at = m_scan.position();
      if (m_scan.word() != "SG_") {
        m_scan.setPosition(saved);
        break;
      }
      Signal sig;
      if (!signal(sig)) {
        // Keep the message; drop the broken signal line and continue with the next.
        m_scan.skipLine();
        continue;
      }
      sig.source.line = where(at).line;
      signalLines.push_back(where(at));
      msg.signals.push_back(std::move(sig));
    }
    m_pending.messageLines.push_back(where(start));
    m_pending.signalWhere.push_back(std::move(signalLines));
    m_out.database.messages.push_back(std::move(msg));
    return true;
  }

  bool signal(Signal& sig) {
    if (!name(sig.name, "signal name", false)) return false;
    m_scan.skipBlanks();
    if (m_scan.peek() != ':') {
      const std::size_t at = m_scan.position();
      const std::string_view indicator = m_scan.word();
      if (!muxIndicator(indicator, sig)) {
        error(at, "bad multiplexer indicator '" + std::string(indicator) + "'");
        return false;
      }
    }
    if (!punct(':')) return false;
    if (!unsignedValue(sig.startBit, "start bit")) return false;
    if (!punct('|')) return false;
    if (!unsignedValue(sig.size, "signal size")) return false;
    if (!punct('@')) return false;
    m_scan.skipBlanks();
    const char order = m_scan.peek();
    if (order != '0' && order != '1') return expected("byte order 0 (Motorola) or 1 (Intel)");
    sig.byteOrder = order == '1' ? ByteOrder::LittleEndian : ByteOrder::BigEndian;
    m_scan.setPosition(m_scan.position() + 1);
    const char sign = m_scan.peek();
    if (sign != '+' && sign != '-') return expected("'+' (unsigned) or '-' (signed)");
    sig.isSigned = sign == '-';
    m_scan.setPosition(m_scan.position() + 1);
    if (!punct('(')) return false;
    if (!number(sig.factor, "factor")) return false;
    if (!punct(',')) return false;
    if (!number(sig.offset, "offset")) return false;
    if (!punct(')')) return false;
    if (!punct('[')) return false;
    if (!number(sig.minimum, "minimum")) return false;
    if (!punct('|')) return false;
    if (!number(sig.maximum, "maximum")) return false;
    if (!punct(']')) return false;
    if (!quoted(sig.unit, "unit string")) return false;
    nodeList(sig.receivers);
    return endOfLine("SG_");
  }

  static bool muxIndicator(std::string_view text, Signal& sig) {
    if (text == "M") {
      sig.muxRole = MuxRole::Multiplexor;
      return true;
    }
    if (text.empty() || text[0] != 'm') return false;
    std::string_view digits = text.substr(1);
    bool alsoMultiplexor = false;
    if (!digits.empty() && digits.back() == 'M') {
      alsoMultiplexor = true;
      digits.remove_suffix(1);
    }
    if (digits.empty()) {
      // A bare "m" (seen in vw_pq.dbc) carries no selector value: read as "M".
      if (alsoMultiplexor) return false;
      sig.muxRole = MuxRole::Multiplexor;
      return true;
    }
    std::uint64_t value = 0;
    for (const char c : digits) {
      if (c < '0' || c > '9' || value > (UINT64_MAX - 9) / 10) return false;
      value = value * 10 + static_cast<std::uint64_t>(c - '0');
    }
    sig.muxRole = alsoMultiplexor ? MuxRole::MultiplexedMultiplexor : MuxRole::Multiplexed;
    sig.muxValue = value;
    return true;
  }

  // Names separated by spaces or commas, up to ';', the end or a keyword at a line start.
  bool nameList(std::vector<std::string>& names, std::string_view what) {
    while (true) {
      m_scan.skipSpace();
      if (m_scan.peek() == ',') {
        m_scan.setPosition(m_scan.position() + 1);
        continue;
      }
      if (m_scan.peek() == ';' || m_scan.atEnd()) return true;
      if (m_scan.atLineStart() && isKeyword(m_scan.peekWord())) return true;
      const std::string_view w = m_scan.word();
      if (w.empty()) return expected(what);
      names.emplace_back(w);
    }
  }

  bool transmitters(std::size_t start) {
    detail::PendingTransmitters pending;
    pending.where = where(start);
    if (!messageId(pending.messageId)) return false;
    if (!punct(':')) return false;
    if (!nameList(pending.nodes, "node name")) return false;
    if (!terminate("BO_TX_BU_")) return false;
    m_pending.transmitters.push_back(std::move(pending));
    return true;
  }

  bool comment(std::size_t start) {
    detail::PendingComment pending;
    pending.where = where(start);
    if (!target(pending.target)) return false;
    if (!quoted(pending.text, "comment string")) return false;
    if (!terminate("CM_")) return false;
    m_pending.comments.push_back(std::move(pending));
    return true;
  }

  static std::optional<ObjectType> objectKeyword(std::string_view word) {
    if (word == "BU_") return ObjectType::Node;
    if (word == "BO_") return ObjectType::Message;
    if (word == "SG_") return ObjectType::Signal;
    if (word == "EV_") return ObjectType::EnvironmentVariable;
    if (word == "BU_SG_REL_") return ObjectType::NodeSignalRelation;
    if (word == "BU_BO_REL_") return ObjectType::NodeMessageRelation;
    if (word == "BU_EV_REL_") return ObjectType::NodeEnvRelation;
    return std::nullopt;
  }

  bool attributeDefinition(std::size_t start, bool relation) {
    AttributeDefinition def;
    def.source.line = where(start).line;
    m_scan.skipSpace();
    if (m_scan.peek() != '"') {
      const std::size_t at = m_scan.position();
      const auto object = objectKeyword(m_scan.word());
      const bool relationObject = object && (*object == ObjectType::NodeSignalRelation ||
                                             *object == ObjectType::NodeMessageRelation ||
                                             *object == ObjectType::NodeEnvRelation);
      if (!object || relation != relationObject) {
        error(at, relation ? "expected BU_SG_REL_, BU_BO_REL_ or BU_EV_REL_"
                           : "expected BU_, BO_, SG_, EV_ or the attribute name");
        return false;
      }
      def.object = *object;
    } else if (relation) {
      return expected("relation type");
    }
    if (!quoted(def.name, "attribute name")) return false;
    m_scan.skipSpace();
    const std::size_t typeAt = m_scan.position();
    const std::string_view type = m_scan.word();
    if (type == "INT" || type == "HEX" || type == "FLOAT") {
      def.type = type == "INT" ? AttributeType::Int : type == "HEX" ? AttributeType::Hex : AttributeType::Float;
      if (!number(def.minimum, "minimum")) return false;
      if (!number(def.maximum, "maximum")) return false;
    } else if (type == "STRING") {
      def.type = AttributeType::String;
    } else if (type == "ENUM") {
      def.type = AttributeType::Enum;
      while (true) {
        m_scan.skipSpace();
        if (m_scan.peek() != '"') break;
        std::string value;
        if (!quoted(value, "enum value")) return false;
        def.enumValues.push_back(std::move(value));
        if (!m_scan.accept(',')) break;
      }
    } else {
      warning(typeAt, "attribute '" + def.name + "' has unknown type '" + std::string(type) +
                          "'; read as STRING");
      def.type = AttributeType::String;
      skipStatement();
      m_out.database.attributeDefinitions.push_back(std::move(def));
      return true;
    }
    if (!terminate("BA_DEF_")) return false;
    m_out.database.attributeDefinitions.push_back(std::move(def));
    return true;
  }

  bool attributeDefault(std::size_t start, bool relation) {
    PendingDefault pending;
    pending.position = start;
    pending.relation = relation;
    if (!quoted(pending.name, "attribute name")) return false;
    if (!attributeValue(pending.value)) return false;
    if (!terminate(relation ? "BA_DEF_DEF_REL_" : "BA_DEF_DEF_")) return false;
    m_defaults.push_back(std::move(pending));
    return true;
  }

  /// BA_DEF_DEF_ names no object type: it sets the default of every definition of that
  /// name (BA_DEF_DEF_REL_: of the relation definitions), wherever they are in the file.
  void applyDefaults() {
    for (const PendingDefault& pending : m_defaults) {
      bool found = false;
      for (auto& def : m_out.database.attributeDefinitions) {
        const bool isRelation = def.object == ObjectType::NodeSignalRelation ||
                                def.object == ObjectType::NodeMessageRelation ||
                                def.object == ObjectType::NodeEnvRelation;
        if (def.name == pending.name && isRelation == pending.relation) {
          def.defaultValue = pending.value;
          found = true;
        }
      }
      if (!found) warning(pending.position, "default for undefined attribute '" + pending.name + "'");
    }
  }

  bool attribute(std::size_t start) {
    detail::PendingAttribute pending;
    pending.where = where(start);
    if (!quoted(pending.name, "attribute name")) return false;
    if (!target(pending.target)) return false;
    if (!attributeValue(pending.value)) return false;
    if (!terminate("BA_")) return false;
    m_pending.attributes.push_back(std::move(pending));
    return true;
  }

  bool relationAttribute(std::size_t start) {
    RelationAttribute rel;
    if (!quoted(rel.name, "attribute name")) return false;
    m_scan.skipSpace();
    const std::size_t at = m_scan.position();
    const auto object = objectKeyword(m_scan.word());
    if (!object || (*object != ObjectType::NodeSignalRelation && *object != ObjectType::NodeMessageRelation &&
                    *object != ObjectType::NodeEnvRelation)) {
      error(at, "expected BU_SG_REL_, BU_BO_REL_ or BU_EV_REL_");
      return false;
    }
    rel.relation = *object;
    if (!name(rel.node, "node name")) return false;
    if (rel.relation == ObjectType::NodeSignalRelation) {
      m_scan.skipSpace();
      if (m_scan.word() != "SG_") return expected("SG_");
      if (!messageId(rel.messageId)) return false;
      if (!name(rel.target, "signal name")) return false;
    } else if (rel.relation == ObjectType::NodeMessageRelation) {
      if (!messageId(rel.messageId)) return false;
    } else {
      if (!name(rel.target, "environment variable name")) return false;
    }
    if (!attributeValue(rel.value)) return false;
    if (!terminate("BA_REL_")) return false;
    (void)start;
    m_out.database.relationAttributes.push_back(std::move(rel));
    return true;
  }

  bool values(std::size_t start) {
    detail::PendingValues pending;
    pending.where = where(start);
    m_scan.skipSpace();
    const std::size_t saved = m_scan.position();
    const auto id = m_scan.unsignedInteger();
    if (id) {
      if (*id > 0xFFFFFFFFull) {
        error(saved, "message ID exceeds 32 bits");
        return false;
      }
      pending.target.object = ObjectType::Signal;
      pending.target.messageId = static_cast<std::uint32_t>(*id);
      if (!name(pending.target.signal, "signal name")) return false;
    } else {
      pending.target.object = ObjectType::EnvironmentVariable;
      if (!name(pending.target.name, "message ID or environment variable name")) return false;
    }
    if (!valueDescriptions(pending.values)) return false;
    if (!terminate("VAL_")) return false;
    m_pending.values.push_back(std::move(pending));
    return true;
  }

  bool valueType(std::size_t start) {
    detail::PendingValueType pending;
    pending.where = where(start);
    if (!messageId(pending.messageId)) return false;
    if (!name(pending.signal, "signal name")) return false;
    m_scan.accept(':');
    if (!unsignedValue(pending.type, "value type (0, 1 or 2)")) return false;
    if (pending.type > 2) {
      error(m_scan.position(), "SIG_VALTYPE_ must be 0 (integer), 1 (float32) or 2 (float64)");
      return false;
    }
    if (!terminate("SIG_VALTYPE_")) return false;
    m_pending.valueTypes.push_back(std::move(pending));
    return true;
  }

  bool signalGroup() {
    SignalGroup group;
    if (!messageId(group.messageId)) return false;
    if (!name(group.name, "signal group name")) return false;
    if (!unsignedValue(group.repetitions, "repetitions")) return false;
    if (!punct(':')) return false;
    if (!nameList(group.signals, "signal name")) return false;
    if (!terminate("SIG_GROUP_")) return false;
    m_out.database.signalGroups.push_back(std::move(group));
    return true;
  }

  bool environmentVariable() {
    EnvironmentVariable env;
    if (!name(env.name, "environment variable name")) return false;
    if (!punct(':')) return false;
    if (!unsignedValue(env.type, "environment variable type")) return false;
    if (!punct('[')) return false;
    if (!number(env.minimum, "minimum")) return false;
    if (!punct('|')) return false;
    if (!number(env.maximum, "maximum")) return false;
    if (!punct(']')) return false;
    if (!quoted(env.unit, "unit")) return false;
    if (!number(env.initialValue, "initial value")) return false;
    if (!unsignedValue(env.id, "environment variable ID")) return false;
    if (!name(env.accessType, "access type")) return false;
    while (true) {
      m_scan.skipSpace();
      if (m_scan.peek() == ',') {
        m_scan.setPosition(m_scan.position() + 1);
        continue;
      }
      if (m_scan.peek() == ';' || m_scan.atEnd()) break;
      if (m_scan.atLineStart() && isKeyword(m_scan.peekWord())) break;  // ';' missing: terminate() warns
      const std::string_view w = m_scan.word();
      if (w.empty()) return expected("node name");
      env.accessNodes.emplace_back(w);
    }
    if (!terminate("EV_")) return false;
    m_out.database.environmentVariables.push_back(std::move(env));
    return true;
  }

  bool environmentData(std::size_t start) {
    std::string envName;
    if (!name(envName, "environment variable name")) return false;
    if (!punct(':')) return false;
    std::uint32_t size = 0;
    if (!unsignedValue(size, "data size")) return false;
    if (!terminate("ENVVAR_DATA_")) return false;
    for (auto& env : m_out.database.environmentVariables) {
      if (env.name == envName) {
        env.dataSize = size;
        return true;
      }
    }
    warning(start, "ENVVAR_DATA_ for undefined environment variable '" + envName + "'");
    return true;
  }

  bool muxValues(std::size_t start) {
    detail::PendingMux pending;
    pending.where = where(start);
    if (!messageId(pending.messageId)) return false;
    if (!name(pending.signal, "signal name")) return false;
    if (!name(pending.switchName, "multiplexor name")) return false;
    while (true) {
      m_scan.skipSpace();
      MuxRange range;
      const auto low = m_scan.unsignedInteger();
      if (!low) return expected("range 'low-high'");
      if (!punct('-')) return false;
      m_scan.skipSpace();
      const auto high = m_scan.unsignedInteger();
      if (!high) return expected("range upper bound");
      range.low = *low;
      range.high = *high;
      if (range.high < range.low) {
        error(m_scan.position(), "range upper bound below lower bound");
        return false;
      }
      pending.ranges.push_back(range);
      if (!m_scan.accept(',')) break;
    }
    if (!terminate("SG_MUL_VAL_")) return false;
    m_pending.muxes.push_back(std::move(pending));
    return true;
  }

  struct PendingDefault {
    std::string name;
    AttributeValue value;
    std::size_t position{};
    bool relation{};
  };

  Scanner m_scan;
  std::vector<PendingDefault> m_defaults;
  std::string_view m_file;
  ParseOutput& m_out;
  PendingState m_pending;
  std::unordered_set<std::string> m_nodeNames;  ///< BU_ names seen so far, to warn about repeats
};

}  // namespace

bool ParseOutput::hasErrors() const noexcept { return errorCount() > 0; }

std::size_t ParseOutput::errorCount() const noexcept {
  return static_cast<std::size_t>(std::count_if(diagnostics.begin(), diagnostics.end(),
                                                [](const Error& e) { return e.severity == Severity::Error; }));
}

std::size_t ParseOutput::warningCount() const noexcept {
  return static_cast<std::size_t>(std::count_if(diagnostics.begin(), diagnostics.end(),
                                                [](const Error& e) { return e.severity == Severity::Warning; }));
}

ParseOutput parse(std::string_view text, std::string_view fileName) {
  ParseOutput out;
  std::string converted;
  if (text.size() >= 3 && text.substr(0, 3) == "\xEF\xBB\xBF") text.remove_prefix(3);  // UTF-8 BOM
  if (text::isValidUtf8(text)) {
    const bool ascii = std::all_of(text.begin(), text.end(), [](char c) { return static_cast<unsigned char>(c) < 0x80; });
    out.database.sourceEncoding = ascii ? "ascii" : "utf-8";
  } else {
    converted = text::cp1252ToUtf8(text);
    text = converted;
    out.database.sourceEncoding = "cp1252";
  }
  // Any line-end convention: CRLF (Windows) and CR alone (classic Mac OS) become LF, so
  // lines, columns and multi-line comments read alike. Columns do not move: only the CR
  // before an LF is dropped, a lone CR is replaced in place.
  std::string normalized;
  if (text.find('\r') != std::string_view::npos) {
    normalized.reserve(text.size());
    for (std::size_t i = 0; i < text.size(); ++i) {
      if (text[i] != '\r') {
        normalized += text[i];
      } else if (i + 1 >= text.size() || text[i + 1] != '\n') {
        normalized += '\n';
      }
    }
    text = normalized;
  }
  Parser parser(text, fileName, out);
  parser.run();
  std::stable_sort(out.diagnostics.begin(), out.diagnostics.end(), [](const Error& a, const Error& b) {
    return a.location.line < b.location.line;
  });
  return out;
}

Result<Database> loadFile(const std::string& path, std::vector<Error>* warnings) {
  Result<std::string> content = input::readWholeFile(path, input::DBC_FILE);
  if (!content) return content.error();
  ParseOutput out = parse(*content, path);
  for (const Error& diagnostic : out.diagnostics) {
    if (diagnostic.severity == Severity::Error) return diagnostic;
  }
  if (warnings) {
    for (Error& diagnostic : out.diagnostics) {
      if (diagnostic.severity == Severity::Warning) warnings->push_back(std::move(diagnostic));
    }
  }
  return std::move(out.database);
}

Result<Database> loadFiles(const std::vector<std::string>& paths, std::vector<Error>* warnings) {
  if (paths.empty()) return Error{"no DBC file given"};
  auto first = loadFile(paths.front(), warnings);
  if (!first) return first;
  Database combined = std::move(*first);
  for (std::size_t i = 1; i < paths.size(); ++i) {
    auto next = loadFile(paths[i], warnings);
    if (!next) return next.error();
    if (auto merged = merge(combined, *next, paths[i]); !merged) return merged.error();
  }
  return combined;
}

}  // namespace openvcu::dbc
