#pragma once
// Internal: what the statement parser collects before it resolves references.
// Statements that refer to messages and signals (CM_, BA_, VAL_, SIG_VALTYPE_,
// SG_MUL_VAL_, BO_TX_BU_) are applied after the whole file is read, so their order
// in the file does not matter.

#include "openvcu/core/error.hpp"
#include "openvcu/dbc/model.hpp"

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace openvcu::dbc::detail {

struct Where {
  std::uint32_t line{};
  std::uint32_t column{};
};

/// Which object a CM_ / BA_ / VAL_ refers to.
struct Target {
  ObjectType object{ObjectType::Network};
  std::string name;            ///< node, environment variable
  std::uint32_t messageId{};   ///< declared ID
  std::string signal;
};

struct PendingComment {
  Target target;
  std::string text;
  Where where;
};

struct PendingAttribute {
  std::string name;
  Target target;
  AttributeValue value;
  Where where;
};

struct PendingValues {
  Target target;  ///< Signal or EnvironmentVariable
  std::vector<ValueDescription> values;
  Where where;
};

struct PendingValueType {
  std::uint32_t messageId{};
  std::string signal;
  std::uint32_t type{};
  Where where;
};

struct PendingMux {
  std::uint32_t messageId{};
  std::string signal;
  std::string switchName;
  std::vector<MuxRange> ranges;
  Where where;
};

struct PendingTransmitters {
  std::uint32_t messageId{};
  std::vector<std::string> nodes;
  Where where;
};

struct PendingState {
  std::vector<PendingComment> comments;
  std::vector<PendingAttribute> attributes;
  std::vector<PendingValues> values;
  std::vector<PendingValueType> valueTypes;
  std::vector<PendingMux> muxes;
  std::vector<PendingTransmitters> transmitters;
  std::vector<Where> messageLines;  ///< per Database::messages index
  /// mux indicator text per signal, [message][signal], for resolution errors
  std::vector<std::vector<Where>> signalWhere;
};

/// Resolves pending references, multiplexing, IDs and attributes; appends diagnostics.
void resolve(Database& database, PendingState& pending, std::string_view fileName,
             std::vector<Error>& diagnostics);

}  // namespace openvcu::dbc::detail
