#pragma once
// Reading DBC files for the dbc commands: every diagnostic is kept (dbc::loadFile stops at
// the first error; `vcu` shows them all), and several files merge into one database in the
// order given, like dbc::loadFiles.

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "openvcu/core/input_file.hpp"
#include "openvcu/core/result.hpp"
#include "openvcu/dbc/parser.hpp"
#include "sink.hpp"

namespace openvcu::cli {

/// The whole file under the input-file rule (openvcu/core/input_file.hpp: a regular file
/// within the kind's size limit), or an Error located at the file ("cannot open: No such
/// file or directory", "not a regular file (directory)").
Result<std::string> readFileBytes(const std::string& path, input::FileKind kind = input::DBC_FILE);

/// Reads and parses one DBC file; diagnostics are named after `path` as given.
Result<dbc::ParseOutput> parseFile(const std::string& path);

/// Counts shown by `dbc check` and `dbc info`: bus messages (pseudo messages such as
/// VECTOR__INDEPENDENT_SIG_MSG are not counted), their signals, and nodes.
struct DatabaseCounts {
  std::size_t messages{};
  std::size_t signals{};
  std::size_t nodes{};
};
DatabaseCounts countDatabase(const dbc::Database& database) noexcept;

/// Loads the DBC files a command works on: parses each, reports every error (and every
/// warning when `showWarnings`) on `err`, and merges the files in order. Empty after
/// reporting when a file is unreadable, has errors, or conflicts with an earlier one.
std::optional<dbc::Database> loadDatabase(const std::vector<std::string>& paths, Sink& err, bool showWarnings);

}  // namespace openvcu::cli
