// `vcu init DIR --dbc FILE... --node NAME [--force]`: a checked vehicle folder from DBC files.
// The plan (buses, what the node sends and receives) is built here; init_vehicle.cpp,
// init_schedule.cpp and init_fsm.cpp write the files. Everything is staged in a hidden
// folder inside DIR, checked with `vcu check`'s loaders, then renamed into place.
#include "init_command.hpp"

#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "check_commands.hpp"
#include "dbc_loading.hpp"
#include "diagnostics.hpp"
#include "init_plan.hpp"
#include "openvcu/config/catalog.hpp"
#include "openvcu/config/vehicle.hpp"
#include "openvcu/core/text.hpp"

namespace openvcu::cli {
namespace {

namespace fs = std::filesystem;

constexpr const char* DESCRIPTION = "Write a checked vehicle folder for one node of a DBC";
constexpr const char* FOOTER =
    "Writes DIR/vehicle.json, schedule.json, receive.json, fsm.json, dashboard.json,\n"
    "gpio.json and simulation.json for the VCU node NAME of the DBC files, and copies the DBC\n"
    "files into DIR (the folder is self-contained: move it, commit it, edit its DBC).\n"
    "One bus per DBC file (BusType \"CAN FD\" -> fd, Baudrate / BaudrateCANFD -> bit rates,\n"
    "else 500 kbit/s), each on the simulated bus sim:NAME. Guessed values carry a \"comment\".\n"
    "The files are checked with the loaders `vcu check` uses before any is written; an\n"
    "existing file is never replaced without --force, and a refusal leaves DIR unchanged.\n"
    "\n"
    "Example:\n"
    "  vcu init tractor --dbc tractor.dbc --node VCU\n"
    "  vcu check --config tractor/vehicle.json && ./run.sh --config tractor/vehicle.json\n"
    "Exit: 0 written, 1 errors (DBC, unknown node, existing files, a failed write), 2 usage.\n";

/// The files written besides the DBC copies, with their writers.
struct Output {
  const char* name;
  init::OrderedJson (*write)(const init::Plan&);
};
constexpr Output OUTPUTS[] = {{"vehicle.json", init::vehicleJson},      {"schedule.json", init::scheduleJson},
                              {"receive.json", init::receiveJson},      {"fsm.json", init::fsmJson},
                              {"dashboard.json", init::dashboardJson},  {"gpio.json", init::gpioJson},
                              {"simulation.json", init::simulationJson}};

/// `text` reduced to [A-Za-z0-9_-] (others -> '_'), 1-32 characters; "vehicle" when empty.
std::string safeName(const std::string& text) {
  std::string name;
  for (const char c : text) {
    if (name.size() == 32) break;
    name += (std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_') ? c : '_';
  }
  return name.empty() ? "vehicle" : name;
}

std::optional<double> numberAttribute(const dbc::Database& database, std::string_view name) {
  const auto value = database.attribute(database.networkAttributes, name, dbc::ObjectType::Network);
  if (!value || value->kind != dbc::AttributeValue::Kind::Number || !(value->number > 0)) return std::nullopt;
  return value->number;
}

/// A bit rate attribute in bit/s: values under 10000 are taken as kbit/s (some tools write 500).
std::optional<std::uint32_t> bitRate(const dbc::Database& database, std::string_view name) {
  const auto value = numberAttribute(database, name);
  if (!value) return std::nullopt;
  const double bits = *value < 10000 ? *value * 1000 : *value;
  if (bits < 10000 || bits > 16'000'000) return std::nullopt;
  return static_cast<std::uint32_t>(bits);
}

init::PlannedBus planBus(const std::string& path, const dbc::Database& file, std::size_t files) {
  init::PlannedBus bus;
  bus.dbcName = fs::path(path).filename().string();
  bus.name = files == 1 ? "vehicle" : safeName(fs::path(path).stem().string());
  bus.allMessages = files == 1;
  if (!bus.allMessages) {
    for (const dbc::Message& message : file.messages) {
      if (!message.pseudo) bus.messages.push_back(message.name);
    }
  }
  const auto busType = file.attributeText(file.networkAttributes, "BusType", dbc::ObjectType::Network);
  bus.fd = busType && (*busType == "CAN FD" || *busType == "CANFD");
  std::string from;
  if (const auto rate = bitRate(file, "Baudrate")) {
    bus.bitrate = *rate;
    from = "bit rate from the DBC's Baudrate";
  } else {
    from = "bit rate guessed (the DBC has no Baudrate attribute): set your bus' rate";
  }
  if (bus.fd) {
    bus.dataBitrate = bitRate(file, "BaudrateCANFD");
    from += bus.dataBitrate ? "; CAN FD (BusType), data rate from BaudrateCANFD"
                            : "; CAN FD (BusType), data rate guessed 2 Mbit/s (no BaudrateCANFD)";
  } else {
    from += busType ? "; BusType " + *busType : "; classic CAN (no BusType)";
  }
  bus.comment = "the network of " + bus.dbcName + ": " + from + ". On the vehicle: \"link\": \"socketcan:can0\"";
  return bus;
}

/// Names the DBC's nodes for an unknown --node.
Error unknownNode(const std::string& node, const dbc::Database& database) {
  if (database.nodes.empty()) {
    return Error{"node '" + node +
                 "' is not in the DBC: it declares no nodes (BU_ is empty); add the VCU to BU_ "
                 "and make it the transmitter (BO_) of the messages it sends"};
  }
  std::vector<std::string> names;
  std::string list;
  for (const dbc::Node& candidate : database.nodes) {
    names.push_back(candidate.name);
    list += (list.empty() ? "" : ", ") + candidate.name;
  }
  std::string message = "node '" + node + "' is not in the DBC";
  if (auto suggestion = text::didYouMean(node, names)) message += "; did you mean '" + *suggestion + "'?";
  return Error{message + " (nodes: " + list + ")"};
}

/// A unique staging folder inside `dir` (renames into dir stay on one file system).
std::optional<fs::path> makeStaging(const fs::path& dir, std::error_code& error) {
  for (int attempt = 0; attempt < 100; ++attempt) {
    const fs::path candidate = dir / (".vcu-init-" + std::to_string(::getpid()) + "-" + std::to_string(attempt));
    if (fs::create_directory(candidate, error)) return candidate;
    if (error) return std::nullopt;
  }
  error = std::make_error_code(std::errc::file_exists);
  return std::nullopt;
}

bool writeText(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << text;
  out.flush();
  return static_cast<bool>(out);
}

struct Staged {
  std::string name;
  fs::path from;
};

}  // namespace

ExitCode runInit(const InitOptions& options, Streams streams) {
  // 1. The DBC files: every diagnostic with file:line:col, merged as vehicle.json will merge them.
  auto database = loadDatabase(options.dbcFiles, streams.err, false);
  if (!database) return ExitCode::Failure;
  std::vector<dbc::Database> files;
  for (const std::string& path : options.dbcFiles) {
    auto parsed = parseFile(path);
    if (!parsed) {
      report(streams.err, parsed.error());
      return ExitCode::Failure;
    }
    files.push_back(std::move(parsed->database));
  }
  for (std::size_t i = 0; i < options.dbcFiles.size(); ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      if (fs::path(options.dbcFiles[i]).filename() == fs::path(options.dbcFiles[j]).filename()) {
        reportError(streams.err, "two DBC files are named '" + fs::path(options.dbcFiles[i]).filename().string() +
                                     "': they are copied into DIR under their names; rename one");
        return ExitCode::Failure;
      }
    }
  }
  if (!options.instance.empty() && !config::validInstanceName(options.instance)) {
    reportError(streams.err, "--instance '" + options.instance + "' must be 1-32 letters, digits, '-' or '_'");
    return ExitCode::Usage;
  }
  if (database->findNode(options.node) == nullptr) {
    report(streams.err, unknownNode(options.node, *database));
    return ExitCode::Failure;
  }

  // 2. The plan.
  init::Plan plan;
  plan.node = options.node;
  std::error_code error;
  const fs::path dir = fs::path(options.dir).lexically_normal();
  fs::path absolute = fs::absolute(dir, error).lexically_normal();
  if (absolute.filename().empty()) absolute = absolute.parent_path();  // "tractor/" or "."
  plan.instance = options.instance.empty() ? safeName(absolute.filename().string()) : options.instance;
  plan.database = std::move(*database);
  for (std::size_t i = 0; i < files.size(); ++i)
    plan.buses.push_back(planBus(options.dbcFiles[i], files[i], files.size()));
  for (std::size_t m = 0; m < plan.database.messages.size(); ++m) {
    const dbc::Message& message = plan.database.messages[m];
    if (message.pseudo) continue;
    if (!config::sentBy(message, plan.node)) {
      plan.received.push_back(m);
      continue;
    }
    if (init::isSafetyHeader(message)) {
      plan.shms.push_back(m);
      continue;
    }
    init::PlannedTx tx;
    tx.message = m;
    tx.cycleMs = message.cycleTimeMs;
    tx.safety = init::markedAsSdm(message) && tx.cycleMs && *tx.cycleMs * 1000ULL > init::SAFETY_DELTA_US;
    tx.bus = init::busOf(plan, message.name);
    plan.transmitted.push_back(tx);
  }
  init::fitBusLoad(plan);

  // 3. Refuse before writing anything: every target that exists, unless --force.
  std::vector<std::string> targets;
  for (const Output& output : OUTPUTS) targets.emplace_back(output.name);
  for (const init::PlannedBus& bus : plan.buses) targets.push_back(bus.dbcName);
  if (fs::exists(dir, error) && !fs::is_directory(dir, error)) {
    reportError(streams.err, "'" + dir.string() + "' exists and is not a folder");
    return ExitCode::Failure;
  }
  if (!options.force) {
    std::vector<std::string> existing;
    for (const std::string& name : targets) {
      if (fs::exists(dir / name, error)) existing.push_back((dir / name).string());
    }
    if (!existing.empty()) {
      std::string list;
      for (const std::string& path : existing) list += (list.empty() ? "" : ", ") + path;
      reportError(streams.err, "refusing to overwrite " + list + " (--force replaces them); nothing written");
      return ExitCode::Failure;
    }
  }

  // 4. Stage every file, check the staged folder with `vcu check`'s loaders, then rename.
  const bool created = !fs::exists(dir, error);
  fs::create_directories(dir, error);
  if (error) {
    reportError(streams.err, "cannot create '" + dir.string() + "': " + error.message());
    return ExitCode::Failure;
  }
  const auto staging = makeStaging(dir, error);
  if (!staging) {
    reportError(streams.err, "cannot create a staging folder in '" + dir.string() + "': " + error.message());
    if (created) fs::remove(dir, error);
    return ExitCode::Failure;
  }
  const auto cleanUp = [&] { fs::remove_all(*staging, error); };
  // on a failure: the staging folder goes, and DIR too when this run created it (empty then)
  const auto abandon = [&] {
    cleanUp();
    if (created) fs::remove(dir, error);
  };
  std::vector<Staged> staged;
  bool written = true;
  for (const Output& output : OUTPUTS) {
    const fs::path path = *staging / output.name;
    written = written && writeText(path, output.write(plan).dump(2) + "\n");
    staged.push_back({output.name, path});
  }
  for (std::size_t i = 0; i < plan.buses.size(); ++i) {
    const fs::path path = *staging / plan.buses[i].dbcName;
    fs::copy_file(options.dbcFiles[i], path, error);
    written = written && !error;
    staged.push_back({plan.buses[i].dbcName, path});
  }
  if (!written) {
    reportError(streams.err, "cannot write into '" + staging->string() + "'; nothing written");
    abandon();
    return ExitCode::Failure;
  }
  StringSink checkOut;
  StringSink checkErr;
  VehicleCheckOptions check;
  check.stack.configPath = (*staging / "vehicle.json").string();
  const ExitCode checked = runCheck(check, Streams{checkOut, checkErr});
  if (checked != ExitCode::Ok) {
    streams.err.write(checkErr.text());
    reportError(streams.err,
                "the generated folder does not pass `vcu check` (a vcu init bug for this DBC; please "
                "report it with the DBC); nothing written");
    abandon();
    return ExitCode::Failure;
  }
  for (const Staged& file : staged) {
    fs::rename(file.from, dir / file.name, error);
    if (error) {
      reportError(streams.err, "cannot move '" + file.name + "' into '" + dir.string() + "': " + error.message() +
                                   " (the files before it were written)");
      cleanUp();
      return ExitCode::Failure;
    }
  }
  cleanUp();

  // 5. What was written and what to do next.
  std::string text;
  for (const Staged& file : staged) text += "wrote " + (dir / file.name).string() + "\n";
  std::size_t cyclic = 0;
  for (const init::PlannedTx& tx : plan.transmitted) cyclic += tx.cycleMs ? 1 : 0;
  text += "node " + plan.node + ": " + std::to_string(plan.transmitted.size()) + " transmitted messages (" +
          std::to_string(cyclic) + " cyclic), " + std::to_string(plan.received.size()) + " received\n";
  for (const std::string& note : plan.busLoadNotes) text += note + "\n";
  std::size_t warnings = 0;
  for (std::size_t at = checkErr.text().find(": warning: "); at != std::string::npos;
       at = checkErr.text().find(": warning: ", at + 1)) {
    ++warnings;
  }
  if (warnings != 0) text += "vcu check: 0 errors, " + std::to_string(warnings) + " warnings (run it to see them)\n";
  const std::string vehicle = (dir / "vehicle.json").string();
  text += "next:\n  vcu check --config " + vehicle + "\n  ./run.sh --config " + vehicle +
          "\n  (then edit fsm.json, schedule.json and gpio.json by hand: docs/bring-up.md)\n";
  streams.out.write(text);
  return ExitCode::Ok;
}

void registerInitCommand(CLI::App& app, CommandContext& context) {
  auto options = std::make_shared<InitOptions>();
  CLI::App* command = app.add_subcommand("init", DESCRIPTION);
  command->footer(FOOTER);
  command->add_option("DIR", options->dir, "the vehicle folder to write (created if missing)")->required();
  command->add_option("--dbc", options->dbcFiles, "the DBC files (one bus each)")
      ->required()
      ->expected(1, -1)
      ->option_text("FILE...");
  command->add_option("--node", options->node, "the VCU's node name in the DBC (BU_)")->required()->option_text("NAME");
  command->add_option("--instance", options->instance, "the stack's instance name (default: DIR's name)")
      ->option_text("NAME");
  command->add_flag("--force", options->force, "replace existing files");
  command->callback([options, &context] { context.exitCode = runInit(*options, context.streams); });
}

}  // namespace openvcu::cli
