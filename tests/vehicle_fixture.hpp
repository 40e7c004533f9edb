#pragma once
// What the service unit tests start from: a loaded configuration, its catalog and, when
// asked for, a fresh signal table under a test's own instance name (removed again at the end).
//
//   struct Fixture : openvcu::testing::VehicleTable {
//     Fixture() : VehicleTable(HHEA_CONFIG, "txunit-" + std::to_string(::getpid())) {}
//   };

#include <doctest/doctest.h>

#include <optional>
#include <string>
#include <utility>

#include "openvcu/config/catalog.hpp"
#include "openvcu/config/vehicle.hpp"
#include "openvcu/signals/table.hpp"

namespace openvcu::testing {

struct VehicleTable {
  config::VehicleConfig vehicle;
  signals::Catalog catalog;
  std::optional<signals::SignalTable> table;
  std::string instance;  ///< the table's name; empty: no table

  explicit VehicleTable(const std::string& configPath, std::string tableInstance = {})
      : instance(std::move(tableInstance)) {
    auto vehicleResult = config::loadVehicleConfig(configPath);
    REQUIRE_MESSAGE(vehicleResult, (vehicleResult ? "" : vehicleResult.error().toString()));
    vehicle = std::move(*vehicleResult);
    auto catalogResult = config::buildCatalog(vehicle);
    REQUIRE_MESSAGE(catalogResult, (catalogResult ? "" : catalogResult.error().toString()));
    catalog = std::move(*catalogResult);
    if (instance.empty()) return;
    (void)signals::SignalTable::remove(instance);
    auto tableResult = signals::SignalTable::open(catalog, instance);
    REQUIRE_MESSAGE(tableResult, (tableResult ? "" : tableResult.error().toString()));
    table.emplace(std::move(*tableResult));
  }
  ~VehicleTable() {
    if (!instance.empty()) (void)signals::SignalTable::remove(instance);
  }
  VehicleTable(const VehicleTable&) = delete;
  VehicleTable& operator=(const VehicleTable&) = delete;
};

}  // namespace openvcu::testing
