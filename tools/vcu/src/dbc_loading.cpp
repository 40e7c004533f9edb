#include "dbc_loading.hpp"

#include "diagnostics.hpp"

namespace openvcu::cli {

Result<std::string> readFileBytes(const std::string& path, input::FileKind kind) {
  return input::readWholeFile(path, kind);
}

Result<dbc::ParseOutput> parseFile(const std::string& path) {
  Result<std::string> readResult = readFileBytes(path);
  if (!readResult) return readResult.error();
  return dbc::parse(*readResult, path);
}

DatabaseCounts countDatabase(const dbc::Database& database) noexcept {
  DatabaseCounts counts;
  for (const dbc::Message& message : database.messages) {
    if (message.pseudo) continue;
    ++counts.messages;
    counts.signals += message.signals.size();
  }
  counts.nodes = database.nodes.size();
  return counts;
}

std::optional<dbc::Database> loadDatabase(const std::vector<std::string>& paths, Sink& err, bool showWarnings) {
  if (paths.empty()) {
    reportError(err, "no DBC file given");
    return std::nullopt;
  }
  std::optional<dbc::Database> combined;
  bool failed = false;
  for (const std::string& path : paths) {
    Result<dbc::ParseOutput> parseResult = parseFile(path);
    if (!parseResult) {
      report(err, parseResult.error());
      failed = true;
      continue;
    }
    for (const Error& diagnostic : parseResult->diagnostics) {
      if (diagnostic.severity == Severity::Error || showWarnings) report(err, diagnostic);
    }
    if (parseResult->hasErrors()) {
      failed = true;
      continue;
    }
    if (failed) continue;  // keep reporting the other files' diagnostics, skip the merge
    if (!combined) {
      combined = std::move(parseResult->database);
    } else if (Status mergeResult = dbc::merge(*combined, parseResult->database, path); !mergeResult) {
      report(err, mergeResult.error());
      failed = true;
    }
  }
  if (failed) return std::nullopt;
  return combined;
}

}  // namespace openvcu::cli
