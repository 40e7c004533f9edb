// libFuzzer target: `vcu send`'s cansend frame syntax (tools/vcu/src/cansend_syntax.hpp).
// Invariants: no crash or UB; an error carries a column inside the text (+1 for "at the
// end"); a parsed frame keeps the Frame invariants (ID in range, classic <= 8 bytes, FD
// lengths on the FD sizes, BRS/ESI only on FD, RTR only on classic, bytes past the length
// zero) and, written back in cansend syntax, parses to the same frame.
#include "fuzz_support.hpp"

#include <cstdio>
#include <string>

#include "cansend_syntax.hpp"

using namespace openvcu;

namespace {

bool isFdLength(std::size_t length) {
  return length <= 8 || length == 12 || length == 16 || length == 20 || length == 24 || length == 32 ||
         length == 48 || length == 64;
}

/// The frame in cansend syntax: "123#DEADBEEF", "18FEF121#R3", "123##1DEADBEEF".
std::string format(const can::Frame& frame) {
  char buffer[16];
  std::snprintf(buffer, sizeof buffer, frame.extended() ? "%08X" : "%03X", frame.id);
  std::string text = buffer;
  if (frame.fd()) {
    const unsigned flags = ((frame.flags & can::FLAG_BRS) != 0 ? 1u : 0u) | ((frame.flags & can::FLAG_ESI) != 0 ? 2u : 0u);
    std::snprintf(buffer, sizeof buffer, "##%X", flags);
    text += buffer;
  } else if ((frame.flags & can::FLAG_RTR) != 0) {
    text += "#R";
    if (frame.length > 0) text += static_cast<char>('0' + frame.length);
    return text;
  } else {
    text += '#';
  }
  for (std::size_t i = 0; i < frame.length; ++i) {
    std::snprintf(buffer, sizeof buffer, "%02X", frame.data[i]);
    text += buffer;
  }
  return text;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text = fuzz::asText(data, size);
  auto frameResult = cli::parseCansendFrame(text);
  if (!frameResult) {
    fuzz::require(!frameResult.error().message.empty());
    fuzz::require(frameResult.error().location.column <= text.size() + 1);
    return 0;
  }
  const can::Frame& frame = *frameResult;
  fuzz::require(frame.id <= (frame.extended() ? can::EXTENDED_ID_MASK : can::STANDARD_ID_MASK));
  fuzz::require(frame.length <= (frame.fd() ? can::MAX_DATA_LENGTH : can::CLASSIC_DATA_LENGTH));
  fuzz::require(!frame.fd() || isFdLength(frame.length));
  fuzz::require(frame.fd() || (frame.flags & (can::FLAG_BRS | can::FLAG_ESI)) == 0);
  fuzz::require(!(frame.fd() && (frame.flags & can::FLAG_RTR) != 0));
  fuzz::require((frame.flags & can::FLAG_ERROR) == 0);
  for (std::size_t i = frame.length; i < can::MAX_DATA_LENGTH; ++i) fuzz::require(frame.data[i] == 0);

  const std::string again = format(frame);
  auto againResult = cli::parseCansendFrame(again);
  fuzz::require(againResult.ok());
  fuzz::require(againResult->id == frame.id && againResult->flags == frame.flags &&
                againResult->length == frame.length && againResult->data == frame.data);
  return 0;
}
