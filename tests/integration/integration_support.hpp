#pragma once
// What every integration case needs: the sandbox check, iox-roudi plus the fixture service
// started through the harness, and `vcu` run against the integration configuration.

#include <doctest/doctest.h>

#include "skip.hpp"

#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "harness.hpp"
#include "openvcu/config/catalog.hpp"
#include "openvcu/signals/table.hpp"

namespace openvcu::integration {

inline const std::string VCU = VCU_BINARY;
inline const std::string FIXTURE = FIXTURE_SERVICE;
inline const std::string CONFIG = INTEGRATION_CONFIG;
/// The instance of tests/data/integration/vehicle.json.
inline constexpr const char* INSTANCE = "itest";
/// The fixture's writer id (fixture_service.cpp), shown by `vcu signal get/watch`.
inline constexpr const char* FIXTURE_WRITER_TEXT = "writer 240";

/// The fixture service's start specification (the same for a restart).
inline harness::ProcessSpec fixtureSpec() {
  return harness::ProcessSpec{.name = "fixture", .argv = {FIXTURE, "--config", CONFIG}, .notifyReadiness = true};
}

/// `vcu <arguments> --config CONFIG`.
inline harness::CommandResult vcu(harness::Harness& sut, std::vector<std::string> arguments) {
  std::vector<std::string> argv{VCU};
  argv.insert(argv.end(), arguments.begin(), arguments.end());
  argv.emplace_back("--config");
  argv.push_back(CONFIG);
  return sut.run(argv);
}

/// iox-roudi and a ready fixture service, or a failed REQUIRE.
inline harness::Process& startStack(harness::Harness& sut) {
  const auto roudi = sut.startRoudi();
  REQUIRE_STATUS(roudi);
  auto fixture = sut.start(fixtureSpec());
  REQUIRE_STATUS(fixture);
  return **fixture;
}

inline bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

/// Copies every file of config/hhea into `folder` (the sandbox's /tmp/hhea): the tests run
/// on the embedded default and may then change their copy. Returns folder/vehicle.json.
inline std::filesystem::path copyHheaConfig(const std::filesystem::path& folder) {
  namespace fs = std::filesystem;
  fs::create_directories(folder);
  for (const auto& entry : fs::directory_iterator(fs::path(OPENVCU_SOURCE_DIR) / "config" / "hhea")) {
    if (entry.is_regular_file()) {
      fs::copy_file(entry.path(), folder / entry.path().filename(), fs::copy_options::overwrite_existing);
    }
  }
  return folder / "vehicle.json";
}

/// Waits (table change futex, no fixed sleep) until the bus plane of `slot` holds `value`;
/// returns that bus value, or empty on timeout.
inline std::optional<signals::BusValue> waitForBus(const signals::SignalTable& table, signals::SignalIndex slot,
                                                   double value, std::chrono::nanoseconds timeout) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  std::uint32_t epoch = table.changeEpoch();
  for (;;) {
    const auto read = table.readBus(slot);
    if (read && read->updates > 0 && read->value == value) return read;
    const auto left = end - std::chrono::steady_clock::now();
    if (left <= std::chrono::nanoseconds::zero()) return std::nullopt;
    epoch = table.waitForChange(epoch, std::chrono::duration_cast<std::chrono::nanoseconds>(left));
  }
}

/// The index of state `name` in the HHEA machine (internal.fsm.state is the file-order index).
inline double hheaStateIndex(const std::string& name) {
  std::ifstream in(std::filesystem::path(OPENVCU_SOURCE_DIR) / "config" / "hhea" / "fsm.json");
  const nlohmann::json machine = nlohmann::json::parse(in);
  for (std::size_t i = 0; i < machine["states"].size(); ++i) {
    if (machine["states"][i]["name"] == name) return static_cast<double>(i);
  }
  FAIL("no state " << name);
  return -1;
}

/// A stack on a configuration file, seen from the test: the configuration and its catalog
/// (loaded at construction), the signal table (openTable(), once a service created it), and
/// `vcu` commands against it.
struct ConfiguredStack {
  harness::Harness sut;
  std::filesystem::path config;
  std::optional<config::VehicleConfig> vehicle;
  std::optional<signals::Catalog> catalog;
  std::optional<signals::SignalTable> table;

  explicit ConfiguredStack(std::filesystem::path configPath) : config(std::move(configPath)) {
    auto loaded = config::loadVehicleConfig(config.string());
    REQUIRE_STATUS(loaded);
    vehicle.emplace(std::move(*loaded));
    auto built = config::buildCatalog(*vehicle);
    REQUIRE_STATUS(built);
    catalog.emplace(std::move(*built));
  }

  void openTable() {
    auto opened = signals::SignalTable::open(*catalog, vehicle->instance);
    REQUIRE_STATUS(opened);
    table.emplace(std::move(*opened));
  }
  /// A service binary with --config, readiness awaited, output captured.
  harness::Process& startService(const std::string& name, const std::string& binary) {
    auto process = sut.start(harness::ProcessSpec{
        .name = name, .argv = {binary, "--config", config.string()}, .notifyReadiness = true, .captureOutput = true});
    REQUIRE_STATUS(process);
    return **process;
  }
  harness::CommandResult vcu(std::vector<std::string> arguments) {
    std::vector<std::string> argv{VCU};
    argv.insert(argv.end(), arguments.begin(), arguments.end());
    argv.emplace_back("--config");
    argv.push_back(config.string());
    return sut.run(argv);
  }
  /// `vcu signal set KEY VALUE`, which must be accepted.
  void set(const std::string& key, const std::string& value) {
    const auto result = vcu({"signal", "set", key, value});
    REQUIRE_MESSAGE(contains(result.out, "accepted"), result.describe());
  }
  [[nodiscard]] signals::SignalIndex index(const std::string& key) const {
    const auto found = catalog->indexOf(key);
    REQUIRE_MESSAGE(found, key);
    return *found;
  }
};

}  // namespace openvcu::integration

/// Every case starts with this: outside the sandbox it skips with a message.
#define SKIP_UNLESS_ISOLATED() \
  do {                          \
    if (!openvcu::harness::isolated()) OPENVCU_SKIP(openvcu::harness::NOT_ISOLATED); \
  } while (false)

// The names every integration case uses.
namespace harness = openvcu::harness;
namespace fs = std::filesystem;
using namespace openvcu;
using namespace openvcu::integration;
using namespace std::chrono_literals;
