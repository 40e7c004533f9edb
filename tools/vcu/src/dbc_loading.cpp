#include "dbc_loading.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>

#include "diagnostics.hpp"

namespace openvcu::cli {
namespace {

Error fileError(const std::string& path, std::string_view what, int reason) {
  std::string message(what);
  message += ": ";
  message += reason != 0 ? std::strerror(reason) : "unknown error";
  return Error{std::move(message), Location{path, 0, 0, {}}};
}

struct FileCloser {
  void operator()(std::FILE* file) const noexcept { std::fclose(file); }
};

}  // namespace

Result<std::string> readFileBytes(const std::string& path) {
  errno = 0;
  std::unique_ptr<std::FILE, FileCloser> file(std::fopen(path.c_str(), "rb"));
  if (!file) return fileError(path, "cannot open", errno);
  std::string bytes;
  constexpr std::size_t CHUNK = 64 * 1024;
  for (;;) {
    const std::size_t used = bytes.size();
    bytes.resize(used + CHUNK);
    errno = 0;
    const std::size_t count = std::fread(bytes.data() + used, 1, CHUNK, file.get());
    bytes.resize(used + count);
    if (count < CHUNK) {
      if (std::ferror(file.get())) return fileError(path, "cannot read", errno);  // e.g. a directory
      return bytes;
    }
  }
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
