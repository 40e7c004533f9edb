// libFuzzer target for openvcu::can::LogReader (candump and Vector ASC) and the candump -L
// writer. Arbitrary bytes go through the reader in every format mode; the run fails
// (abort) when a record breaks the Frame invariants or when reader(writer(frame)) does
// not give the same frame back. Needs only openvcu::can (and openvcu::core).
//
//   clang++ -std=c++20 -g -O1 -fsanitize=fuzzer,address,undefined fuzz/fuzz_candump.cpp ... && ./fuzz_candump

#include <cstddef>
#include <cstdint>
#include <istream>
#include <string>

#include "log_checks.hpp"
#include "openvcu/can/log_writer.hpp"

namespace {

using namespace openvcu::can;

using openvcu::fuzz::ByteStreamBuf;
using openvcu::fuzz::checkInvariants;
using openvcu::fuzz::require;

/// Microseconds rounded towards minus infinity: what a candump -L line keeps.
std::int64_t floorMicros(std::int64_t ns) {
  return ns >= 0 ? ns / 1000 : -((-(ns + 1)) / 1000) - 1;
}

void checkRoundTrip(const LogRecord& record) {
  const std::string line = formatCandumpL(record.frame, record.channel, record.direction);
  ByteStreamBuf buffer(reinterpret_cast<const std::uint8_t*>(line.data()), line.size());
  std::istream input(&buffer);
  LogReader reader(input, "round-trip", LogFormat::Candump);
  const auto maybeAgain = reader.next();
  if (!maybeAgain) {
    // Times beyond year 2262 cannot be written back; anything else must read back.
    require(record.frame.timestampNs / 1'000'000'000 >= 9'223'372'035 ||
            record.frame.timestampNs / 1'000'000'000 <= -9'223'372'035);
    return;
  }
  const Frame& a = record.frame;
  const Frame& b = maybeAgain->frame;
  require(a.id == b.id && a.flags == b.flags && a.length == b.length && a.data == b.data);
  require(floorMicros(a.timestampNs) * 1000 == b.timestampNs);
  require(maybeAgain->channel == record.channel && maybeAgain->direction == record.direction);
}

void run(const std::uint8_t* data, std::size_t size, LogFormat format) {
  ByteStreamBuf buffer(data, size);
  std::istream input(&buffer);
  LogReader reader(input, "fuzz", format);
  std::uint64_t previousLine = 0;
  while (const auto maybeRecord = reader.next()) {
    checkInvariants(*maybeRecord);
    require(maybeRecord->line > previousLine);
    previousLine = maybeRecord->line;
    checkRoundTrip(*maybeRecord);
  }
  if (reader.errorCount() > 0) require(reader.lastError().has_value());
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  run(data, size, LogFormat::Auto);
  run(data, size, LogFormat::Candump);
  run(data, size, LogFormat::VectorAsc);
  return 0;
}
