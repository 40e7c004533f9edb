#pragma once
// DBC text -> Database. The parser accepts the Vector DBC grammar and the odd cases
// real files contain (see docs/design/dbc.md), never crashes or hangs on any input,
// and reports anything malformed as "file:line:col: reason".
//
//   BO_ 2566844926 EEC1: 8 Vector__XXX
//    SG_ EngineSpeed : 24|16@1+ (0.125,0) [0|8031.875] "rpm" Vector__XXX
//   -> Message{name "EEC1", id 0x18F004FE, extended, length 8,
//              signals {EngineSpeed: start 24, size 16, Intel, unsigned, 0.125 rpm/bit}}

#include "openvcu/core/error.hpp"
#include "openvcu/core/result.hpp"
#include "openvcu/dbc/model.hpp"

#include <string>
#include <string_view>
#include <vector>

namespace openvcu::dbc {

struct ParseOutput {
  Database database;
  std::vector<Error> diagnostics;  ///< errors and warnings in file order

  [[nodiscard]] bool hasErrors() const noexcept;
  [[nodiscard]] std::size_t errorCount() const noexcept;
  [[nodiscard]] std::size_t warningCount() const noexcept;
};

/// Parses DBC text. UTF-8 is kept; other bytes are read as Windows-1252 and
/// converted. With errors the database holds what could be read, for tools only.
/// @note thread-safe (no shared state); never throws.
ParseOutput parse(std::string_view text, std::string_view fileName = "<dbc>");

/// Reads and parses a file; refuses it (first error) if anything is malformed. The file
/// is read under the input-file rule (openvcu/core/input_file.hpp): a regular file of at
/// most 64 MiB ("/dev/zero: not a regular file (character device)").
/// Warnings are appended to *warnings when given.
Result<Database> loadFile(const std::string& path, std::vector<Error>* warnings = nullptr);

/// Loads several files and merges them into one database (the "combined DBC").
Result<Database> loadFiles(const std::vector<std::string>& paths, std::vector<Error>* warnings = nullptr);

/// Merges `other` into `into`: identical definitions are kept once; a message with the
/// same ID or name but another definition, or an attribute defined with two types, is a
/// conflict and the merge is refused with the reason (into is left unchanged).
Status merge(Database& into, const Database& other, std::string_view otherName);

/// Writes the database back as DBC text (UTF-8). parse(write(db)).database == db.
std::string write(const Database& database);

}  // namespace openvcu::dbc
