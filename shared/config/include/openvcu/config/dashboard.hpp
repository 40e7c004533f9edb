#pragma once
// The HMI dashboard file: dashboard.json beside vehicle.json, which vcu-hmi loads for its
// Vehicle and Dashboard tabs and `vcu check` checks. Every signal key it names must be in
// the vehicle's catalog. Reference: services/hmi/README.md.
//
//   {"dials": {"voltage": "VIC.HVESSD1_PGN61584.HS_ULvl"}, "items": [{"key": "internal.relay.Cl15"}]}
//   -> DashboardConfig{.voltageKey = "VIC.HVESSD1_PGN61584.HS_ULvl", .items = {{.key = "internal.relay.Cl15",
//      .label = "Cl15", .unit = the catalog's, .format = "%.1f"}}}, the other fields at their defaults

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "openvcu/core/result.hpp"
#include "openvcu/signals/catalog.hpp"

namespace openvcu::config {

/// One tile of the dashboard grid.
struct DashboardItem {
  std::string key;
  std::string label;   ///< default: the last component of the key
  std::string unit;    ///< default: the catalog's unit
  std::string format;  ///< printf for the number, default "%.1f"
};

/// A dial's scale.
struct DialRange {
  double minimum{};
  double maximum{};
};

/// The dashboard file: {"dials": {"voltage": DIAL, "current": DIAL, "power": DIAL}, where
/// DIAL is a KEY or {"key": KEY, "min": NUMBER, "max": NUMBER} ("power": "" or no "key":
/// voltage x current),
/// "header": {"soc": KEY, "soh": KEY, "charger": KEY}, "status": [KEY, ...],
/// "items": [{"key":..., "label":..., "unit":..., "format":...}], "staleAfterMs": 2000}.
/// Every key is the vehicle's: nothing in the HMI names a signal of one vehicle.
struct DashboardConfig {
  std::string voltageKey;
  std::string currentKey;
  std::string powerKey;               ///< empty: power = voltage x current
  DialRange voltageRange{0, 1000};    ///< V
  DialRange currentRange{-400, 400};  ///< A
  DialRange powerRange{-300, 300};    ///< kW
  std::string socKey;                 ///< header; empty: not shown
  std::string sohKey;
  std::string chargerKey;
  std::vector<std::string> statusKeys;  ///< the Vehicle tab's status table
  std::vector<DashboardItem> items;
  std::int64_t staleAfterMs{2000};
};

/// Parses and checks a dashboard file against the catalog: unknown keys are refused with
/// "<file>: /items/3/key: unknown signal 'X' (did you mean 'Y'?)". Never throws.
Result<DashboardConfig> loadDashboardConfig(const std::string& path, const signals::Catalog& catalog);
/// The same from JSON text (`source` names it in errors).
/// @note Allocate (and load reads the file): for loading, not for a display-rate path.
Result<DashboardConfig> parseDashboardConfig(std::string_view text, const std::string& source,
                                             const signals::Catalog& catalog);

/// dashboard.json in the folder of `vehiclePath`, where vcu-hmi, `vcu top` and `vcu check`
/// look for it; empty when there is no such file. "config/hhea/vehicle.json" ->
/// "config/hhea/dashboard.json".
[[nodiscard]] std::string dashboardBeside(const std::string& vehiclePath);

/// True when `format` is one printf number conversion (%f %e %g with flags, width,
/// precision; "%%" allowed) and nothing that reads memory (%s, %n), under 32 characters:
/// what a dashboard item's "format" may be. "%.1f" -> true, "%s" -> false.
/// @note noexcept, allocation-free.
[[nodiscard]] bool isSafeNumberFormat(std::string_view format) noexcept;

}  // namespace openvcu::config
