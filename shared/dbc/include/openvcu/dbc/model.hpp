#pragma once
// The DBC model: what a DBC file says, resolved and validated, independent of
// the text it came from. Built by dbc::parse(), written back by dbc::write(),
// compiled for the per-frame path by dbc::MessageCodec.
//
// @note plain values; not thread-safe to mutate, safe to share const.

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

namespace openvcu::dbc {

/// Where a definition came from. Compares equal regardless of the line, so that two
/// models parsed from differently formatted text of the same content are equal.
struct SourceLine {
  std::uint32_t line{};
  friend bool operator==(const SourceLine&, const SourceLine&) noexcept { return true; }
};

enum class ByteOrder : std::uint8_t {
  LittleEndian,  ///< Intel, "@1": start bit is the LSB
  BigEndian,     ///< Motorola, "@0": start bit is the MSB in DBC "sawtooth" numbering
};

enum class ValueType : std::uint8_t { Integer, Float32, Float64 };  ///< SIG_VALTYPE_ 0/1/2

enum class MuxRole : std::uint8_t {
  None,
  Multiplexor,             ///< "M"
  Multiplexed,             ///< "mN"
  MultiplexedMultiplexor,  ///< "mNM": selected by N and selecting others
};

enum class FrameFormat : std::uint8_t { StandardCan, ExtendedCan, StandardCanFd, ExtendedCanFd, J1939 };

enum class ObjectType : std::uint8_t {
  Network,
  Node,                 ///< BU_
  Message,              ///< BO_
  Signal,               ///< SG_
  EnvironmentVariable,  ///< EV_
  NodeSignalRelation,   ///< BU_SG_REL_
  NodeMessageRelation,  ///< BU_BO_REL_
  NodeEnvRelation,      ///< BU_EV_REL_
};

enum class AttributeType : std::uint8_t { Int, Hex, Float, String, Enum };

/// An attribute value as written: ENUM values keep the index the file wrote and are
/// resolved to text with the definition (each file has its own ENUM order).
struct AttributeValue {
  enum class Kind : std::uint8_t { Number, String };
  Kind kind{Kind::Number};
  double number{};
  std::string text;

  static AttributeValue fromNumber(double value) { return {Kind::Number, value, {}}; }
  static AttributeValue fromString(std::string value) { return {Kind::String, 0.0, std::move(value)}; }
  friend bool operator==(const AttributeValue&, const AttributeValue&) = default;
};

using Attributes = std::map<std::string, AttributeValue, std::less<>>;

struct AttributeDefinition {
  std::string name;
  ObjectType object{ObjectType::Network};
  AttributeType type{AttributeType::String};
  double minimum{};  ///< INT, HEX, FLOAT
  double maximum{};
  std::vector<std::string> enumValues;        ///< ENUM
  std::optional<AttributeValue> defaultValue; ///< BA_DEF_DEF_ / BA_DEF_DEF_REL_
  SourceLine source;
  friend bool operator==(const AttributeDefinition&, const AttributeDefinition&) = default;
};

struct ValueDescription {
  std::int64_t value{};
  std::string text;
  friend bool operator==(const ValueDescription&, const ValueDescription&) = default;
};

struct MuxRange {
  std::uint64_t low{};
  std::uint64_t high{};
  friend bool operator==(const MuxRange&, const MuxRange&) = default;
};

struct Signal {
  std::string name;
  std::uint32_t startBit{};  ///< as written: LSB (Intel) or MSB in sawtooth numbering (Motorola)
  std::uint32_t size{};      ///< bits; above 64 the signal loads but is not decodable
  ByteOrder byteOrder{ByteOrder::LittleEndian};
  bool isSigned{};
  ValueType valueType{ValueType::Integer};
  double factor{1.0};
  double offset{0.0};
  double minimum{0.0};
  double maximum{0.0};
  std::string unit;
  std::vector<std::string> receivers;
  MuxRole muxRole{MuxRole::None};
  std::uint64_t muxValue{};        ///< N of "mN" / "mNM"
  std::string muxSwitch;           ///< the multiplexor selecting this signal (resolved at load)
  std::vector<MuxRange> muxRanges; ///< SG_MUL_VAL_ ranges; empty means {muxValue}
  bool extendedMux{};              ///< the switch and ranges came from SG_MUL_VAL_
  std::string comment;
  std::vector<ValueDescription> valueDescriptions;
  Attributes attributes;           ///< explicit BA_ values only; defaults via Database
  SourceLine source;
  /// Resolved at load: SystemSignalLongSymbol when set (DBC names are limited to 32
  /// characters, so tools keep the full name there), else `name`.
  std::string displayName;

  /// 1..64 bits (32 for float32, 64 for float64): the codec can decode it.
  [[nodiscard]] bool decodable() const noexcept;
  /// VAL_ text for a raw value, or nullptr.
  [[nodiscard]] const std::string* describe(std::int64_t raw) const noexcept;
  friend bool operator==(const Signal&, const Signal&) = default;
};

/// The BO_ transmitter meaning "no node".
inline constexpr std::string_view NO_NODE = "Vector__XXX";
/// The pseudo message that collects signals not mapped to any frame.
inline constexpr std::string_view INDEPENDENT_SIGNALS = "VECTOR__INDEPENDENT_SIG_MSG";

struct Message {
  std::string name;
  std::uint32_t id{};          ///< without flags: 11 or 29 bits
  bool extended{};
  std::uint32_t declaredId{};  ///< the number as written in BO_ (flags included)
  std::uint32_t length{};      ///< bytes: 0..64 for frames, more for transport-protocol messages
  std::string transmitter;     ///< BO_ transmitter as written (may be Vector__XXX)
  std::vector<std::string> extraTransmitters;  ///< BO_TX_BU_
  std::string comment;
  std::vector<Signal> signals;
  Attributes attributes;
  /// Not a bus frame: VECTOR__INDEPENDENT_SIG_MSG or an ID with bit 29/30 set. Kept for
  /// round trips and tools, never matched against received frames.
  bool pseudo{};
  SourceLine source;

  // Resolved at load (attributes with their defaults):
  FrameFormat frameFormat{FrameFormat::StandardCan};
  std::optional<std::uint32_t> cycleTimeMs;  ///< GenMsgCycleTime when > 0
  std::string displayName;                   ///< SystemMessageLongSymbol when set, else `name`

  [[nodiscard]] bool isJ1939() const noexcept { return frameFormat == FrameFormat::J1939; }
  /// Transmitting nodes: the BO_ node (unless Vector__XXX) then BO_TX_BU_.
  [[nodiscard]] std::vector<std::string> transmitters() const;
  [[nodiscard]] const Signal* findSignal(std::string_view signalName) const noexcept;
  friend bool operator==(const Message&, const Message&) = default;
};

struct Node {
  std::string name;
  std::string comment;
  Attributes attributes;
  friend bool operator==(const Node&, const Node&) = default;
};

struct ValueTable {
  std::string name;
  std::vector<ValueDescription> values;
  friend bool operator==(const ValueTable&, const ValueTable&) = default;
};

struct EnvironmentVariable {
  std::string name;
  std::uint32_t type{};  ///< 0 integer, 1 float, 2 string
  double minimum{};
  double maximum{};
  std::string unit;
  double initialValue{};
  std::uint32_t id{};
  std::string accessType;  ///< DUMMY_NODE_VECTORn as written
  std::vector<std::string> accessNodes;
  std::optional<std::uint32_t> dataSize;  ///< ENVVAR_DATA_
  std::string comment;
  std::vector<ValueDescription> valueDescriptions;
  Attributes attributes;
  friend bool operator==(const EnvironmentVariable&, const EnvironmentVariable&) = default;
};

struct SignalGroup {
  std::uint32_t messageId{};  ///< declared ID of the message
  std::string name;
  std::uint32_t repetitions{};
  std::vector<std::string> signals;
  friend bool operator==(const SignalGroup&, const SignalGroup&) = default;
};

/// BA_REL_: an attribute on a node-signal / node-message / node-env relation.
struct RelationAttribute {
  std::string name;
  ObjectType relation{ObjectType::NodeSignalRelation};
  std::string node;
  std::uint32_t messageId{};  ///< declared ID (signal and message relations)
  std::string target;         ///< signal name or environment variable name
  AttributeValue value;
  friend bool operator==(const RelationAttribute&, const RelationAttribute&) = default;
};

/// A whole DBC file (or several merged). Lookups are O(1) through an index built by
/// reindex(), which parse() and merge() call.
class Database {
 public:
  std::string version;
  std::vector<std::string> newSymbols;  ///< NS_ list as written
  std::vector<Node> nodes;
  std::vector<ValueTable> valueTables;
  std::vector<Message> messages;
  std::vector<EnvironmentVariable> environmentVariables;
  std::vector<SignalGroup> signalGroups;
  std::vector<AttributeDefinition> attributeDefinitions;
  Attributes networkAttributes;
  std::vector<RelationAttribute> relationAttributes;
  std::string comment;  ///< network CM_
  std::string sourceEncoding{"utf-8"};  ///< "utf-8", "cp1252" (converted to UTF-8 at load) or "ascii"

  [[nodiscard]] const Message* findMessage(std::uint32_t id, bool extended) const noexcept;
  [[nodiscard]] const Message* findMessage(std::string_view name) const noexcept;
  [[nodiscard]] const Node* findNode(std::string_view name) const noexcept;
  [[nodiscard]] const AttributeDefinition* findAttributeDefinition(std::string_view name,
                                                                   ObjectType object) const noexcept;
  /// Explicit value, else the definition's default, else nullopt.
  [[nodiscard]] std::optional<AttributeValue> attribute(const Attributes& explicitValues,
                                                        std::string_view name, ObjectType object) const;
  /// An ENUM attribute's text (index resolved through the file's own ENUM list), a
  /// STRING attribute's text, or a number's decimal text.
  [[nodiscard]] std::optional<std::string> attributeText(const Attributes& explicitValues,
                                                         std::string_view name, ObjectType object) const;
  /// GenSigStartValue as a raw value, if set (explicitly or by default).
  [[nodiscard]] std::optional<double> startValueRaw(const Signal& signal) const;

  /// Rebuilds the lookup index and the resolved message fields (frame format, cycle).
  void reindex();

  /// Index equality is derived from the content: databases compare by content only.
  friend bool operator==(const Database& a, const Database& b) { return a.sameContent(b); }

 private:
  [[nodiscard]] bool sameContent(const Database& other) const;
  std::unordered_map<std::uint64_t, std::size_t> m_byId;  ///< (extended << 32 | id) -> index
  std::unordered_map<std::string, std::size_t> m_byName;
  std::unordered_map<std::string, std::size_t> m_nodeByName;
};

std::string_view toString(ObjectType object) noexcept;
std::string_view toString(FrameFormat format) noexcept;

}  // namespace openvcu::dbc
