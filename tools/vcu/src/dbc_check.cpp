// vcu dbc check: parse, report every diagnostic, summarise, check that the files merge.
#include <optional>

#include "dbc_commands.hpp"
#include "dbc_loading.hpp"
#include "diagnostics.hpp"

namespace openvcu::cli {
namespace {

std::string plural(std::size_t count, std::string_view noun) {
  std::string text = std::to_string(count);
  text += ' ';
  text += noun;
  if (count != 1) text += 's';
  return text;
}

std::string summaryLine(std::string_view name, const DatabaseCounts& counts, std::size_t errors, std::size_t warnings) {
  std::string line(name);
  line += ": " + plural(counts.messages, "message") + ", " + plural(counts.signals, "signal") + ", " +
          plural(counts.nodes, "node") + ", " + plural(errors, "error") + ", " + plural(warnings, "warning") + '\n';
  return line;
}

/// A database without messages describes no traffic: "VERSION \"\"" alone parses cleanly.
constexpr std::string_view NO_MESSAGES = "no messages (no BO_ line): a DBC describes at least one message";

}  // namespace

ExitCode runCheck(const CheckOptions& options, Streams streams) {
  bool failed = false;
  std::optional<dbc::Database> combined;  // the error-free files merged so far
  std::size_t mergedFiles = 0;
  std::size_t mergeConflicts = 0;
  for (const std::string& path : options.files) {
    Result<dbc::ParseOutput> parseResult = parseFile(path);
    if (!parseResult) {
      report(streams.err, parseResult.error());
      failed = true;
      continue;
    }
    const dbc::ParseOutput& parsed = *parseResult;
    for (const Error& diagnostic : parsed.diagnostics) {
      if (diagnostic.severity != Severity::Warning || !options.quiet) report(streams.err, diagnostic);
    }
    const DatabaseCounts counts = countDatabase(parsed.database);
    std::size_t errors = parsed.errorCount();
    std::size_t warnings = parsed.warningCount();
    if (counts.messages == 0) {
      // one file of several may hold only nodes or attributes; the merged set must have messages
      const bool alone = options.files.size() < 2;
      const Error empty{std::string(NO_MESSAGES), Location{path, 0, 0, {}},
                        alone ? Severity::Error : Severity::Warning};
      if (alone || !options.quiet) report(streams.err, empty);
      ++(alone ? errors : warnings);
    }
    streams.out.write(summaryLine(path, counts, errors, warnings));
    if (errors > 0) {
      failed = true;
      continue;
    }
    if (options.files.size() < 2) continue;
    if (!combined) {
      combined = parsed.database;
      mergedFiles = 1;
    } else if (Status mergeResult = dbc::merge(*combined, parsed.database, path); !mergeResult) {
      report(streams.err, mergeResult.error());  // merge() names the first conflict; the file is left out
      ++mergeConflicts;
      failed = true;
    } else {
      ++mergedFiles;
    }
  }
  if (combined && options.files.size() >= 2) {
    std::string name = "merged (" + plural(mergedFiles, "file");
    if (mergeConflicts > 0) name += ", " + plural(mergeConflicts, "conflicting file") + " left out";
    name += ')';
    const DatabaseCounts counts = countDatabase(*combined);
    std::size_t errors = mergeConflicts;
    if (counts.messages == 0) {
      report(streams.err, Error{name + ": " + std::string(NO_MESSAGES)});
      ++errors;
      failed = true;
    }
    streams.out.write(summaryLine(name, counts, errors, 0));
  }
  return failed ? ExitCode::Failure : ExitCode::Ok;
}

}  // namespace openvcu::cli
