#pragma once
// A three-signal catalog for the dashboard's tests (the file's checks in shared/config and
// the HMI's display logic): a DBC signal with a unit, a relay and a fault with value texts.

#include <doctest/doctest.h>

#include <utility>
#include <vector>

#include "openvcu/signals/catalog.hpp"

namespace openvcu::testing {

/// The DBC signal of the catalog: the VIC's fast-update SOC in %, 0..100.
inline signals::SignalInfo socSignalInfo() {
  signals::SignalInfo soc;
  soc.key = "VIC.HVESSD2_PGN61585.HS_FastUpdSOC";
  soc.unit = "%";
  soc.minimum = 0;
  soc.maximum = 100;
  return soc;
}

inline signals::Catalog dashboardCatalog() {
  std::vector<signals::SignalInfo> infos;
  infos.push_back(socSignalInfo());
  signals::SignalInfo relay;
  relay.key = "internal.relay.Cl15";
  relay.minimum = 0;
  relay.maximum = 1;
  relay.kind = signals::SignalKind::Internal;
  relay.valueTexts = {{0, "Off"}, {1, "On"}};
  infos.push_back(relay);
  signals::SignalInfo contactor;
  contactor.key = "internal.fault.Contactor";
  contactor.kind = signals::SignalKind::Internal;
  contactor.valueTexts = {{0, "Normal"}, {1, "Fault"}};
  infos.push_back(contactor);
  auto catalog = signals::Catalog::create(std::move(infos));
  REQUIRE(catalog);
  return std::move(*catalog);
}

}  // namespace openvcu::testing
