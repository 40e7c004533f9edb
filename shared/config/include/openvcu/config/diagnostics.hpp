#pragma once
// The VCU's own diagnostics ("diagnostics" in vehicle.json; HHEA: config/hhea/diagnostics.json):
// which FSM states or internal signals raise which J1939-73 DTC with which lamps, whether
// DM3/DM11 clears are accepted, the DM1 period, the identification answers (SOFT, ECUID,
// CI) and where the occurrence counts are kept. Reference: docs/config.md, "diagnostics.json";
// design: docs/design/j1939-diagnostics.md.
//
//   {"dtcs": [{"name": "battery fault", "fsmState": "Battery Fault", "spn": 520192, "fmi": 12,
//              "lamps": ["red"]},
//             {"name": "contactor line", "signal": "internal.fault.Contactor",
//              "activeWhen": {"eq": 1}, "spn": 520196, "fmi": 31, "lamps": ["red"],
//              "flash": {"red": "fast"}}],
//    "dm3": "refuse", "dm11": "refuse", "dm1PeriodMs": 1000,
//    "identification": {"software": ["openvcu"], "ecu": {"partNumber": "..."},
//                       "component": {"make": "..."}},
//    "countsFile": "dtc_counts.json"}
//
// Checked, each error with the file and JSON path: unknown keys, SPN <= 524287, FMI <= 31,
// SPN 0 with FMI 0 (means "none"), the same SPN and FMI twice, names given twice, exactly one
// of "fsmState" / "signal", a state the FSM does not have, a signal key the catalog does not
// have, identification fields with '*' or over 200 bytes. Warned: "dm3" or "dm11" "accept"
// (a clear request carries only a source address, so any node on the bus could clear).

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "openvcu/config/vehicle.hpp"
#include "openvcu/core/error.hpp"
#include "openvcu/core/result.hpp"
#include "openvcu/j1939/diagnostic_state.hpp"
#include "openvcu/j1939/dm_encode.hpp"
#include "openvcu/signals/catalog.hpp"

namespace openvcu::config {

/// What makes a DTC active.
enum class DtcSource : std::uint8_t {
  FsmState,  ///< the FSM is in `fsmState`
  Signal,    ///< the table value of `signal` compares true with `activeWhen`
};

/// "activeWhen": {"eq" | "ne" | "gt" | "lt": value}.
enum class DtcCompare : std::uint8_t { Eq, Ne, Gt, Lt };

struct DtcConfig {
  std::string name;
  std::string path;  ///< its JSON path ("/dtcs/3"), for messages
  DtcSource source{DtcSource::FsmState};
  std::string fsmState;                ///< DtcSource::FsmState
  std::string signal;                  ///< DtcSource::Signal: the table key ("internal.fault.Contactor")
  DtcCompare compare{DtcCompare::Ne};  ///< without "activeWhen": value != 0
  double value{0.0};                   ///< a number, or a value-table text resolved through the catalog
  j1939::DtcDefinition definition;     ///< SPN, FMI, lamps
  std::string comment;

  /// Whether `signalValue` makes this (signal) DTC active.
  [[nodiscard]] bool activeFor(double signalValue) const noexcept;
};

/// A request to clear diagnostic data from the bus (DM3, DM11).
enum class ClearPolicy : std::uint8_t { Refuse, Accept };

struct IdentificationConfig {
  std::vector<std::string> software;  ///< SOFT fields; the service appends the build version
  std::string partNumber, serialNumber, location, type, manufacturer, hardwareId;  ///< ECUID
  std::string make, model, componentSerialNumber, unitNumber;                      ///< CI

  [[nodiscard]] j1939::EcuIdentification ecu() const noexcept {
    return {partNumber, serialNumber, location, type, manufacturer, hardwareId};
  }
  [[nodiscard]] j1939::ComponentIdentification component() const noexcept {
    return {make, model, componentSerialNumber, unitNumber};
  }
};

inline constexpr std::string_view DEFAULT_DTC_COUNTS_FILE = "dtc_counts.json";

struct DiagnosticsConfig {
  std::string file;
  std::vector<DtcConfig> dtcs;
  ClearPolicy dm3{ClearPolicy::Refuse};  ///< default: refuse (any node could erase the history)
  ClearPolicy dm11{ClearPolicy::Refuse};
  std::int64_t dm1PeriodNs{j1939::DM1_PERIOD_NS};
  IdentificationConfig identification;
  /// Where the occurrence counts persist: "countsFile" resolved against the folder of the
  /// diagnostics file (as can-tx's schedule overlay sits beside schedule.json); default
  /// dtc_counts.json there.
  std::string countsFile;

  /// The DTC definitions in file order, for j1939::DiagnosticState::create().
  [[nodiscard]] std::vector<j1939::DtcDefinition> definitions() const;
};

/// Loads vehicle.diagnosticsFile (empty: no DTCs, the defaults). `catalog` resolves and
/// checks signal keys; `fsmStates`, when given, are the FSM's state names that "fsmState"
/// must name (nullptr: not checked here; `vcu check` checks it with the loaded FSM). Every
/// diagnostic (errors and warnings) is appended to *diagnostics when given; the result is
/// the config or the first error.
Result<DiagnosticsConfig> loadDiagnosticsConfig(const VehicleConfig& vehicle, const signals::Catalog& catalog,
                                                const std::vector<std::string>* fsmStates = nullptr,
                                                std::vector<Error>* diagnostics = nullptr);

/// Occurrence counts read back at start.
struct DtcCountsLoad {
  std::vector<j1939::Dtc> counts;  ///< SPN, FMI and occurrenceCount; empty when missing or rejected
  /// Set when the file existed but was bad: it was renamed to PATH.rejected (the message
  /// says so, or why the rename failed) and the counts start at 0.
  std::optional<Error> rejected;
};

/// Reads the counts file; a missing file is no counts and no error.
///   {"format": 1, "counts": [{"spn": 520192, "fmi": 12, "count": 3}]}
DtcCountsLoad loadDtcCounts(const std::string& path);

/// Writes the counts atomically (temporary file, fsync, rename, fsync of the folder).
Status saveDtcCounts(const std::string& path, std::span<const j1939::Dtc> counts);

}  // namespace openvcu::config
