#pragma once
// Shared by the openvcu::service tests: a small catalog with the shapes the command checks
// care about (a value table, a unit and range, min == max, a bus signal).

#include <doctest/doctest.h>

#include <string>
#include <vector>

#include "openvcu/signals/catalog.hpp"

namespace openvcu::service::testing {

inline signals::SignalInfo signal(std::string key, double minimum, double maximum, std::string unit = {},
                                  signals::SignalKind kind = signals::SignalKind::Internal) {
  signals::SignalInfo info;
  info.key = std::move(key);
  info.minimum = minimum;
  info.maximum = maximum;
  info.unit = std::move(unit);
  info.kind = kind;
  return info;
}

/// internal.operator.Start [0, 1] {0 Stop, 1 Start}; internal.test.level [0, 100] %;
/// internal.test.free [0, 0]; internal.service.fixture.heartbeat; VCU.Command.Enable (bus).
inline signals::Catalog makeCatalog() {
  std::vector<signals::SignalInfo> infos;
  infos.push_back(signal("internal.operator.Start", 0, 1));
  infos.back().valueTexts = {{0, "Stop"}, {1, "Start"}};
  infos.push_back(signal("internal.test.level", 0, 100, "%"));
  infos.push_back(signal("internal.test.free", 0, 0));
  infos.push_back(signal("internal.service.fixture.heartbeat", 0, 1.8e19));
  infos.push_back(signal("VCU.Command.Enable", 0, 3, "", signals::SignalKind::Bus));
  auto catalogResult = signals::Catalog::create(std::move(infos));
  REQUIRE(catalogResult.ok());
  return std::move(catalogResult).value();
}

}  // namespace openvcu::service::testing
