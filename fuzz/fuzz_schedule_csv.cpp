// libFuzzer target: `vcu schedule import`, the thesis' schedule sheet as CSV
// (shared/schedule, openvcu/schedule/schedule_import.hpp), against the HHEA DBC, node and catalog.
// Invariants: no crash, hang or leak; a refused sheet has an error diagnostic; an
// imported one has none, and its "include" lists exactly its "messages".
#include "fuzz_support.hpp"

#include <vector>

#include "openvcu/schedule/schedule_import.hpp"

using namespace openvcu;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const fuzz::Hhea& hhea = fuzz::hhea();
  schedule::ImportOptions options;
  options.node = hhea.vehicle.node;
  options.catalog = &hhea.catalog;
  std::vector<Error> diagnostics;
  auto importResult =
      schedule::importScheduleCsv(fuzz::asText(data, size), "fuzz.csv", hhea.vehicle.database, options, &diagnostics);
  bool anyError = false;
  for (const Error& diagnostic : diagnostics) anyError = anyError || diagnostic.severity == Severity::Error;
  fuzz::require(importResult.ok() != anyError);
  if (importResult) {
    const auto& schedule = *importResult;
    fuzz::require(schedule.contains("include") && schedule.contains("messages"));
    fuzz::require(schedule["include"].size() == schedule["messages"].size());
    (void)schedule.dump();
  }
  return 0;
}
