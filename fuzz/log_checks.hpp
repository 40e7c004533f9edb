#pragma once
// What fuzz_candump and fuzz_asc check on every record a can::LogReader returns.

#include <cstddef>
#include <cstdint>
#include <streambuf>

#include "fuzz_require.hpp"
#include "openvcu/can/log_reader.hpp"

namespace openvcu::fuzz {

/// Reads the fuzzer's bytes in place, without copying them into a string.
class ByteStreamBuf : public std::streambuf {
 public:
  ByteStreamBuf(const std::uint8_t* data, std::size_t size) {
    char* begin = const_cast<char*>(reinterpret_cast<const char*>(data));  // read-only use
    setg(begin, begin, begin + size);
  }
};

inline bool isValidFdLength(std::size_t length) {
  return length <= 8 || length == 12 || length == 16 || length == 20 || length == 24 || length == 32 ||
         length == 48 || length == 64;
}

/// Frame invariants the reader promises for every record.
inline void checkInvariants(const can::LogRecord& record) {
  using namespace openvcu::can;
  const Frame& frame = record.frame;
  require(frame.length <= MAX_DATA_LENGTH);
  require(frame.fd() ? isValidFdLength(frame.length) : frame.length <= CLASSIC_DATA_LENGTH);
  require(frame.extended() || (frame.flags & FLAG_ERROR) != 0 ? frame.id <= EXTENDED_ID_MASK
                                                              : frame.id <= STANDARD_ID_MASK);
  require(frame.fd() || (frame.flags & (FLAG_BRS | FLAG_ESI)) == 0);
  require(!(frame.fd() && (frame.flags & (FLAG_RTR | FLAG_ERROR)) != 0));
  require(record.line > 0);
  require(record.direction == 0 || record.direction == 'R' || record.direction == 'T');
  for (std::size_t i = frame.length; i < MAX_DATA_LENGTH; ++i) require(frame.data[i] == 0);
}

}  // namespace openvcu::fuzz
