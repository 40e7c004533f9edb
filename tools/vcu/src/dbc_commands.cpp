// `vcu dbc ...`: registers check, info and decode on the CLI11 app. Each subcommand's
// description and footer are its manual (`vcu dbc decode --help`).
#include "dbc_commands.hpp"

#include <CLI/CLI.hpp>

#include "cli_checks.hpp"
#include <memory>

namespace openvcu::cli {
namespace {

constexpr const char* CHECK_DESCRIPTION = "Parse DBC files and report every problem";

constexpr const char* CHECK_FOOTER =
    "Diagnostics go to stderr as 'file:line:col: error|warning: reason'; one summary line\n"
    "per file goes to stdout:\n"
    "  vehicle.dbc: 42 messages, 310 signals, 9 nodes, 0 errors, 3 warnings\n"
    "With several files, also checks that they merge into one database (what decode and\n"
    "the services do with several DBCs): a message with the same ID or name but another\n"
    "definition, or an attribute defined with two types, is a conflict. The first conflict\n"
    "of each file is reported, the file is left out, and a 'merged (...)' line follows.\n"
    "\n"
    "Example:\n"
    "  vcu dbc check vehicle.dbc body.dbc\n"
    "Exit: 0 no errors (warnings allowed), 1 an error, an unreadable file or a merge\n"
    "conflict, 2 usage error.\n";

constexpr const char* INFO_DESCRIPTION = "List a DBC file's messages and signals as aligned text";

constexpr const char* INFO_FOOTER =
    "Messages: ID (hex) and IDE (std/ext), name (short/long when a long name is set),\n"
    "length, transmitters, J1939 PGN/priority/SA/DA for 29-bit IDs (DA only for PDU1),\n"
    "cycle time, frame format (VFrameFormat), comment on one line.\n"
    "Signals: name, start|size@order sign (DBC notation, 1 Intel, 0 Motorola), type,\n"
    "factor, offset, [min|max], unit, mux role (M multiplexor, mN selected by N,\n"
    "mNM both, ranges from SG_MUL_VAL_ 'by' their switch), number of value\n"
    "descriptions (VAL_), receivers. '-' means none.\n"
    "A file with errors is not listed: its errors are printed (see 'vcu dbc check').\n"
    "\n"
    "Examples:\n"
    "  vcu dbc info vehicle.dbc\n"
    "  vcu dbc info vehicle.dbc --message EEC1\n"
    "  vcu dbc info vehicle.dbc -m 0x18FEF1FE\n"
    "Exit: 0 listed, 1 unreadable file, errors in it, or no such message, 2 usage error.\n";

constexpr const char* DECODE_DESCRIPTION = "Decode a CAN log (candump, ASC) to JSON Lines or CSV";

constexpr const char* DECODE_FOOTER =
    "Decodes with one or more DBC files (merged in order), streaming: memory stays\n"
    "constant whatever the log size.\n"
    "LOG: candump -L '(t) can0 18FEF100#0102...', candump's console output\n"
    "'(t)  can0  123   [2]  DE AD', CAN FD '123##1...', or Vector ASC (.asc or ASC\n"
    "header); the format is detected per line. '-' reads standard input.\n"
    "--format jsonl (default): one JSON object per frame:\n"
    "  {\"t\":1700000000.012345,\"bus\":\"can0\",\"id\":217056510,\"ext\":true,\"msg\":\"EEC1\",\n"
    "   \"signals\":{\"EngineSpeed\":1250.5},\"raw\":{\"EngineSpeed\":10004}}\n"
    "  t: seconds as logged (null without a time); id: without flag bits; msg: the\n"
    "  message (long name if set) or null with empty objects when no message matches;\n"
    "  signals: physical values, raw: raw values, by signal long name; only the active\n"
    "  multiplexed signals and signals inside the received bytes are listed. Integral\n"
    "  values below 2^53 print as integers, NaN/infinity as \"nan\", \"inf\", \"-inf\".\n"
    "  Same shape as dbc-oracle.py decode (which names 'bus' 'ch').\n"
    "--format csv: header 't,bus,id,ext,msg,signal,raw,physical', one row per decoded\n"
    "  signal; a frame without decoded signals is one row with the last three empty.\n"
    "J1939-21 transport (BAM and RTS/CTS, per channel, source and destination): after the\n"
    "  TP.DT that completes a session, one more record for the reassembled message (up to\n"
    "  1785 bytes), id = priority 6 + PGN + source (+ destination), decoded with the DBC\n"
    "  message its PGN matches (so DBC messages longer than 8 bytes decode); JSONL adds\n"
    "  \"tp\":{\"pgn\",\"sa\",\"da\",\"size\",\"bam\"}. A session that ends otherwise\n"
    "  (Aborted, TimedOut, Replaced, ProtocolError, Refused; Incomplete at the end of the\n"
    "  log or --limit) is a record with \"tp\" and \"tp_end\":{\"outcome\",\"reason\",\n"
    "  \"received\",\"packets\",\"start\"} at the time it ended (timeouts: the deadline).\n"
    "  DM1/DM2 (single frame or reassembled, with or without a DBC message) add\n"
    "  \"dm1\":{\"type\":\"DM1\",\"lamps\":{..},\"dtcs\":[{\"spn\",\"fmi\",\"oc\",\"cm\"}]}.\n"
    "  CSV: a reassembled message is its signal rows; DM1/DM2 add rows lamp.malfunction,\n"
    "  lamp.redStop, lamp.amberWarning, lamp.protect (2-bit state) and dtcN.spn, dtcN.fmi,\n"
    "  dtcN.oc, dtcN.cm per DTC (msg: DBC name or DM1/DM2); tp_end is one row with msg\n"
    "  'tp_end', signal '<Outcome>: <reason>, R of P packets', raw and physical empty.\n"
    "  --stats counts reassembled messages and session ends by outcome.\n"
    "--match j1939 (default): exact ID first, then for every 29-bit ID the message with\n"
    "  the same J1939 PGN (priority and source address ignored; PDU1 destination: own,\n"
    "  else global). j1939-tagged: PGN fallback only for VFrameFormat J1939PG messages.\n"
    "  exact: only the exact (ID, IDE).\n"
    "Error frames are skipped; remote requests are listed without signals.\n"
    "Malformed log lines are reported as 'file:line:col: error: reason' (the first 20,\n"
    "then only a count), skipped, and make the exit status 1 at the end.\n"
    "DBC errors are printed and nothing is decoded.\n"
    "\n"
    "Examples:\n"
    "  vcu dbc decode vehicle.dbc drive.log > drive.jsonl\n"
    "  vcu dbc decode --format csv --match exact powertrain.dbc body.dbc drive.asc\n"
    "  candump -L can0 | vcu dbc decode vehicle.dbc -\n"
    "Exit: 0 decoded, 1 DBC errors, unreadable log, malformed lines or write error,\n"
    "2 usage error.\n";

DecodeFormat decodeFormat(const std::string& name) {
  return name == "csv" ? DecodeFormat::Csv : DecodeFormat::Jsonl;
}

dbc::MatchMode matchMode(const std::string& name) {
  if (name == "exact") return dbc::MatchMode::Exact;
  if (name == "j1939-tagged") return dbc::MatchMode::J1939Tagged;
  return dbc::MatchMode::J1939;
}

void addCheck(CLI::App& dbc, CommandContext& context) {
  auto options = std::make_shared<CheckOptions>();
  CLI::App* check = dbc.add_subcommand("check", CHECK_DESCRIPTION);
  check->footer(CHECK_FOOTER);
  check->add_option("FILE", options->files, "DBC files")->required()->type_name("");
  check->add_flag("-q,--quiet", options->quiet, "do not print warnings (they are still counted)");
  check->callback([options, &context] { context.exitCode = runCheck(*options, context.streams); });
}

void addInfo(CLI::App& dbc, CommandContext& context) {
  auto options = std::make_shared<InfoOptions>();
  CLI::App* info = dbc.add_subcommand("info", INFO_DESCRIPTION);
  info->footer(INFO_FOOTER);
  info->add_option("FILE", options->file, "DBC file")->required()->type_name("");
  info->add_option("-m,--message", options->message, "only this message: name, long name or ID (0x.. or decimal)")
      ->option_text("NAME");
  info->callback([options, &context] { context.exitCode = runInfo(*options, context.streams); });
}

void addDecode(CLI::App& dbc, CommandContext& context) {
  auto options = std::make_shared<DecodeOptions>();
  struct Arguments {
    std::vector<std::string> files;
    std::string format{"jsonl"};
    std::string match{"j1939"};
  };
  auto arguments = std::make_shared<Arguments>();
  CLI::App* decode = dbc.add_subcommand("decode", DECODE_DESCRIPTION);
  decode->footer(DECODE_FOOTER);
  decode->add_option("FILES", arguments->files, "DBC... LOG: one or more DBC files, then the log")
      ->required()
      ->expected(2, -1)
      ->type_name("");
  decode->add_option("-f,--format", arguments->format, "output format (default jsonl)")
      ->check(CLI::IsMember({"jsonl", "csv"}))
      ->option_text("jsonl|csv");
  decode->add_option("--match", arguments->match, "how frames find their message (default j1939)")
      ->check(CLI::IsMember({"exact", "j1939", "j1939-tagged"}))
      ->option_text("exact|j1939|j1939-tagged");
  decode->add_option("-n,--limit", options->limit, "stop after N frames (0: no limit)")
      ->check(nonNegativeNumber("N"))
      ->option_text("N");
  decode->add_flag("--stats", options->stats, "print frame counts on stderr at the end");
  decode->callback([options, arguments, &context] {
    options->logFile = arguments->files.back();
    options->dbcFiles.assign(arguments->files.begin(), arguments->files.end() - 1);
    options->format = decodeFormat(arguments->format);
    options->match = matchMode(arguments->match);
    context.exitCode = runDecode(*options, context.streams);
  });
}

}  // namespace

void registerDbcCommands(CLI::App& app, CommandContext& context) {
  CLI::App* dbc = app.add_subcommand("dbc", "DBC files: check them, list their contents, decode CAN logs with them");
  addCheck(*dbc, context);
  addInfo(*dbc, context);
  addDecode(*dbc, context);
}

}  // namespace openvcu::cli
