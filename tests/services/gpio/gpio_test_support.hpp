#pragma once
// The HHEA configuration, a private signal table and a fake-clock controller on the
// simulated chip, for the vcu-gpio unit tests.

#include <doctest/doctest.h>
#include <unistd.h>

#include <atomic>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "chip.hpp"
#include "controller.hpp"
#include "openvcu/config/catalog.hpp"
#include "vehicle_fixture.hpp"

namespace gpiotest {

using namespace openvcu;

inline const std::string HHEA = std::string(OPENVCU_SOURCE_DIR) + "/config/hhea/vehicle.json";
inline constexpr std::int64_t SECOND = 1'000'000'000;
inline constexpr std::int64_t MS = 1'000'000;
inline constexpr signals::WriterId FSM = 3;

struct Fixture : openvcu::testing::VehicleTable {
  std::unique_ptr<gpio::Chip> chip;
  std::unique_ptr<gpio::Controller> sut;
  std::vector<std::string> log;
  /// Writers the controller watches (empty: none, as a vehicle without schedule "writers").
  std::vector<schedule::WatchedWriter> writers;
  /// What the controller reported about them: "lost fsm", "back fsm".
  std::vector<std::string> writerChanges;

  Fixture() : VehicleTable(HHEA, uniqueInstance()) {}
  static std::string uniqueInstance() {
    static std::atomic<int> counter{0};
    return "gpiounit-" + std::to_string(::getpid()) + "-" + std::to_string(counter.fetch_add(1));
  }
  Fixture(const Fixture&) = delete;
  Fixture& operator=(const Fixture&) = delete;

  signals::SignalIndex key(const std::string& name) const {
    const auto index = catalog.indexOf(name);
    REQUIRE_MESSAGE(index, name);
    return *index;
  }
  std::size_t line(const std::string& name) const {
    for (std::size_t i = 0; i < vehicle.gpio.lines.size(); ++i) {
      if (vehicle.gpio.lines[i].name == name) return i;
    }
    FAIL("no line " << name);
    return 0;
  }

  /// A controller on the sim chip (or on `ownChip`), started at `now`.
  void start(std::int64_t now, std::unique_ptr<gpio::Chip> ownChip = nullptr) {
    if (ownChip) {
      chip = std::move(ownChip);
    } else {
      auto chipResult = gpio::openSimChip(vehicle.gpio, *table, catalog);
      REQUIRE_MESSAGE(chipResult, (chipResult ? "" : chipResult.error().toString()));
      chip = std::move(*chipResult);
    }
    auto created = gpio::Controller::create(
        vehicle.gpio, catalog, *table, *chip, [this](bool, const std::string& text) { log.push_back(text); }, writers,
        [this](const schedule::WatchedWriter& writer, bool lost) {
          writerChanges.push_back((lost ? "lost " : "back ") + writer.service);
        });
    REQUIRE_MESSAGE(created, (created ? "" : created.error().toString()));
    sut = std::move(*created);
    const Status started = sut->start(now);
    REQUIRE_MESSAGE(started, (started ? "" : started.error().toString()));
  }

  void command(const std::string& name, double value, std::int64_t at) {
    table->writeCommand(key(name), value, at, FSM);
  }
  double bus(const std::string& name) const {
    const auto value = table->readBus(key(name));
    REQUIRE(value);
    return value->value;
  }
  bool logged(const std::string& part) const {
    for (const std::string& line : log) {
      if (line.find(part) != std::string::npos) return true;
    }
    return false;
  }
};

}  // namespace gpiotest
