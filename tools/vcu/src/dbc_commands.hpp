#pragma once
// The `vcu dbc` command group: check, info, decode. registerDbcCommands() adds them to the
// app; the run*() functions are the commands themselves, callable without CLI11 (tests).
//
//   vcu dbc check vehicle.dbc body.dbc
//   vcu dbc info vehicle.dbc --message EEC1
//   vcu dbc decode --format csv vehicle.dbc drive.log > drive.csv

#include <cstdint>
#include <string>
#include <vector>

#include "cli.hpp"
#include "decode_output.hpp"
#include "openvcu/dbc/matcher.hpp"

namespace openvcu::cli {

struct CheckOptions {
  std::vector<std::string> files;
  bool quiet{};  ///< hide warnings (they are still counted)
};

struct InfoOptions {
  std::string file;
  std::string message;  ///< only this message (name, long name or ID); empty: all
};

struct DecodeOptions {
  std::vector<std::string> dbcFiles;  ///< merged in order
  std::string logFile;                ///< "-" reads standard input
  DecodeFormat format{DecodeFormat::Jsonl};
  dbc::MatchMode match{dbc::MatchMode::J1939};
  std::uint64_t limit{};  ///< stop after this many frames; 0: no limit
  bool stats{};           ///< print frame counts on stderr at the end
};

/// Malformed log lines printed one by one before only their count is reported.
inline constexpr std::uint64_t MAX_REPORTED_LOG_ERRORS = 20;

/// `vcu dbc check`: diagnostics on err, one summary line per file on out, merge check.
ExitCode runCheck(const CheckOptions& options, Streams streams);
/// `vcu dbc info`: messages and signals as aligned text.
ExitCode runInfo(const InfoOptions& options, Streams streams);
/// `vcu dbc decode`: streams the log, one JSON object per frame or CSV rows per signal.
ExitCode runDecode(const DecodeOptions& options, Streams streams);

/// Adds `dbc` and its subcommands to `app`; the command that runs stores its exit code
/// in `context` (which must outlive the parse).
void registerDbcCommands(CLI::App& app, CommandContext& context);

}  // namespace openvcu::cli
