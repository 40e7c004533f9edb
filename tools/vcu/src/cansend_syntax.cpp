#include "cansend_syntax.hpp"

#include <array>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <string>

namespace openvcu::cli {
namespace {

constexpr char ID_DELIMITER = '#';       // can-utils lib.h CANID_DELIM
constexpr char DATA_SEPARATOR = '.';     // can-utils lib.h DATA_SEPERATOR (sic)
constexpr char RAW_DLC_DELIMITER = '_';  // can-utils lib.h CC_DLC_DELIM
constexpr std::size_t STANDARD_ID_DIGITS = 3;
constexpr std::size_t CAN_XL_ID_DIGITS = 5;  // can-utils: 2-digit VCID + 3-digit priority ID
constexpr std::size_t EXTENDED_ID_DIGITS = 8;
constexpr std::uint8_t FD_FLAG_BRS = 0x1;  // linux/can.h CANFD_BRS
constexpr std::uint8_t FD_FLAG_ESI = 0x2;  // linux/can.h CANFD_ESI
constexpr std::uint8_t MAX_REMOTE_LENGTH = 8;

constexpr const char* EXAMPLES = "e.g. 123#DEADBEEF or 18FEF121#0102";

std::optional<std::uint8_t> hexValue(char c) noexcept {
  if (c >= '0' && c <= '9') return static_cast<std::uint8_t>(c - '0');
  if (c >= 'A' && c <= 'F') return static_cast<std::uint8_t>(c - 'A' + 10);
  if (c >= 'a' && c <= 'f') return static_cast<std::uint8_t>(c - 'a' + 10);
  return std::nullopt;
}

/// "REASON at column N (HINT)" for the character at `index` (0-based).
Error errorAt(std::string_view reason, std::size_t index, std::string_view hint = {}) {
  const auto column = static_cast<std::uint32_t>(index + 1);
  std::string message = std::string(reason) + " at column " + std::to_string(column);
  if (!hint.empty()) message += " (" + std::string(hint) + ")";
  return Error{std::move(message), Location{{}, 0, column, {}}};
}

/// "0x7FF" or "0x18FEF121".
std::string hexText(std::uint32_t id, int digits) {
  std::array<char, 16> text{};
  std::snprintf(text.data(), text.size(), "0x%0*X", digits, static_cast<unsigned>(id));
  return text.data();
}

/// The ID before the first '#': 3 digits standard, 8 extended.
Result<can::Frame> parseId(std::string_view text, std::size_t idEnd) {
  const std::size_t checked = idEnd < EXTENDED_ID_DIGITS ? idEnd : EXTENDED_ID_DIGITS;
  std::uint32_t id = 0;
  for (std::size_t i = 0; i < checked; ++i) {
    const std::optional<std::uint8_t> digit = hexValue(text[i]);
    if (!digit) return errorAt("not a hexadecimal digit", i);
    id = (id << 4) | *digit;
  }
  if (idEnd == 0) return errorAt("no ID before '#'", 0, EXAMPLES);
  if (idEnd == CAN_XL_ID_DIGITS) return errorAt("a 5-digit ID is CAN XL, which is not supported", 0, EXAMPLES);
  if (idEnd != STANDARD_ID_DIGITS && idEnd != EXTENDED_ID_DIGITS) {
    return errorAt("an ID has 3 hex digits (standard) or 8 (extended), not " + std::to_string(idEnd), 0, EXAMPLES);
  }
  can::Frame frame{};
  frame.id = id;
  if (idEnd == STANDARD_ID_DIGITS) {
    if (id > can::STANDARD_ID_MASK) {
      return errorAt("standard ID " + hexText(id, 3) + " is above 0x7FF", 0,
                     "write 8 digits for an extended ID, e.g. 00000" + std::string(text.substr(0, 3)));
    }
  } else {
    if (id > can::EXTENDED_ID_MASK) return errorAt("extended ID " + hexText(id, 8) + " is above 0x1FFFFFFF", 0);
    frame.flags |= can::FLAG_EXTENDED;
  }
  return frame;
}

/// What may follow an 8-byte classic payload or "R8": cansend's raw DLC, not supported.
Error rawDlcError(std::size_t index) {
  return errorAt("the raw DLC suffix '_' is not supported", index, "openvcu frames carry no DLC above 8");
}

/// "R" or "R<length>" at `index`, the end of the text after it.
Result<can::Frame> parseRemote(std::string_view text, std::size_t index, can::Frame frame) {
  frame.flags |= can::FLAG_RTR;
  if (index < text.size()) {
    const std::optional<std::uint8_t> length = hexValue(text[index]);
    if (!length || *length > MAX_REMOTE_LENGTH) {
      return errorAt("a remote request takes one length digit 0..8", index, "e.g. 123#R or 123#R4");
    }
    frame.length = *length;
    ++index;
  }
  if (index < text.size()) {
    if (text[index] == RAW_DLC_DELIMITER && frame.length == MAX_REMOTE_LENGTH) return rawDlcError(index);
    return errorAt("unexpected text after the remote request", index);
  }
  return frame;
}

}  // namespace

Result<can::Frame> parseCansendFrame(std::string_view text) {
  const std::size_t idEnd = text.find(ID_DELIMITER);
  if (idEnd == std::string_view::npos) {
    return errorAt("no '#' between ID and data", text.size(), EXAMPLES);
  }
  Result<can::Frame> idResult = parseId(text, idEnd);
  if (!idResult) return idResult;
  can::Frame frame = *idResult;

  std::size_t index = idEnd + 1;
  if (index < text.size() && (text[index] == 'R' || text[index] == 'r')) return parseRemote(text, index + 1, frame);

  std::size_t maxLength = can::CLASSIC_DATA_LENGTH;
  if (index < text.size() && text[index] == ID_DELIMITER) {
    ++index;
    if (index >= text.size()) return errorAt("no CAN FD flags digit after '##'", index, "e.g. 123##1DEADBEEF");
    const std::optional<std::uint8_t> fdFlags = hexValue(text[index]);
    if (!fdFlags) return errorAt("not a hexadecimal digit", index, "the CAN FD flags after '##': 0..F");
    frame.flags |= can::FLAG_FD;
    if ((*fdFlags & FD_FLAG_BRS) != 0) frame.flags |= can::FLAG_BRS;
    if ((*fdFlags & FD_FLAG_ESI) != 0) frame.flags |= can::FLAG_ESI;
    maxLength = can::MAX_DATA_LENGTH;
    ++index;
  }

  std::size_t length = 0;
  const auto trailingSeparator = [&](std::size_t at) {
    return errorAt("a '.' with no byte after it", at, "remove the trailing '.'");
  };
  while (length < maxLength) {
    if (index < text.size() && text[index] == DATA_SEPARATOR) {
      if (index + 1 == text.size()) return trailingSeparator(index);
      ++index;
    }
    if (index >= text.size()) break;
    const std::optional<std::uint8_t> high = hexValue(text[index]);
    if (!high) return errorAt("not a hexadecimal digit", index);
    if (index + 1 >= text.size()) return errorAt("half a byte", index, "each byte is two hex digits");
    const std::optional<std::uint8_t> low = hexValue(text[index + 1]);
    if (!low) return errorAt("not a hexadecimal digit", index + 1);
    frame.data[length++] = static_cast<std::uint8_t>((*high << 4) | *low);
    index += 2;
  }
  if (index + 1 == text.size() && text[index] == DATA_SEPARATOR) return trailingSeparator(index);
  if (index < text.size()) {
    if (!frame.fd() && text[index] == RAW_DLC_DELIMITER) return rawDlcError(index);
    return errorAt("more than " + std::to_string(maxLength) + " data bytes", index,
                   frame.fd() ? "the CAN FD limit" : "classic CAN; CAN FD is ID##<flags><data>");
  }
  frame.length = frame.fd() ? can::roundUpFdLength(length) : static_cast<std::uint8_t>(length);
  return frame;
}

}  // namespace openvcu::cli
