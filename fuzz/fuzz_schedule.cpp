// libFuzzer target: can-tx's schedule file (schedule.json, docs/design/can-tx.md) through
// loadSchedule on the HHEA vehicle and catalog, and the same bytes as a runtime overlay
// (loadOverlay; applied to HHEA's own schedule when it loads).
// Invariants: no crash, hang or leak; a refused file names an error.
#include "fuzz_support.hpp"

#include "openvcu/schedule/schedule_config.hpp"

using namespace openvcu;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const fuzz::Hhea& hhea = fuzz::hhea();
  static const auto hheaSchedule = schedule::loadSchedule(hhea.vehicle, hhea.catalog);
  fuzz::require(hheaSchedule.ok());

  static config::VehicleConfig vehicle = hhea.vehicle;  // copied once: the DBC model is large
  vehicle.scheduleFile = fuzz::scratch().write("schedule.json", data, size);
  auto scheduleResult = schedule::loadSchedule(vehicle, hhea.catalog);
  if (!scheduleResult) fuzz::require(!scheduleResult.error().message.empty());

  auto overlayResult = schedule::loadOverlay(vehicle.scheduleFile);
  if (overlayResult) {
    auto applied = schedule::applyOverlay(*hheaSchedule, *overlayResult, hhea.vehicle, hhea.catalog);
    if (!applied) fuzz::require(!applied.error().message.empty());
  }
  return 0;
}
