// libFuzzer target: the Vector ASC reader alone (openvcu::can::LogReader in VectorAsc
// mode, docs/design/can-logs.md); fuzz_candump runs the same reader in every mode with the
// candump round trip. Invariants: no crash, hang, leak or UB; every record keeps the Frame
// invariants (log_checks.hpp) with growing line numbers; errors counted have a last error.
#include <cstddef>
#include <cstdint>
#include <istream>

#include "log_checks.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace openvcu::can;
  openvcu::fuzz::ByteStreamBuf buffer(data, size);
  std::istream input(&buffer);
  LogReader reader(input, "fuzz.asc", LogFormat::VectorAsc);
  std::uint64_t previousLine = 0;
  while (const auto maybeRecord = reader.next()) {
    openvcu::fuzz::checkInvariants(*maybeRecord);
    openvcu::fuzz::require(maybeRecord->line > previousLine);
    previousLine = maybeRecord->line;
  }
  if (reader.errorCount() > 0) openvcu::fuzz::require(reader.lastError().has_value());
  return 0;
}
