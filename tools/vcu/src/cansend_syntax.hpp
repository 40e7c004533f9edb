#pragma once
// The frame syntax of can-utils' cansend ("ID#DATA"), parsed into a can::Frame for
// `vcu send`. Pure: no bus, no allocation on success.
//
//   "123#DEADBEEF"     -> standard ID 0x123, 4 bytes DE AD BE EF
//   "18FEF121#0102"    -> extended ID 0x18FEF121 (8 digits are always extended), 2 bytes
//   "123#11.22.33"     -> a '.' may stand before each byte: 3 bytes 11 22 33
//   "123#" / "123#R"   -> no data / remote request of length 0; "123#R3" -> length 3
//   "123##1DEADBEEF"   -> CAN FD, flags nibble 1 (BRS 0x1, ESI 0x2), 4 bytes
//   "123##0112233445566778899" -> CAN FD, 9 bytes given, padded with zeros to 12
//   "12G#00"           -> Error "not a hexadecimal digit at column 3"
//
// cansend's rules (can-utils lib.c parse_canframe), kept as they are: an ID of exactly 3
// hex digits is standard, of exactly 8 digits extended; hex digits in either case; 'R' or
// 'r' for a remote request, optionally followed by one length digit 0..8; "##" and one
// hex flags digit for CAN FD (0x4 is FDF, implied; 0x8 is unused: both ignored); up to
// 8 (classic) or 64 (FD) bytes of two digits each; an odd digit count is an error; a CAN
// FD length between the FD sizes is rounded up with zero bytes.
// Stricter than cansend, where it silently drops input or hands the kernel an invalid
// frame (each of these is an error here):
//   - text after the last byte: a 9th classic byte, a 65th FD byte, anything after "R" or
//     "R<digit>" (cansend ignores it);
//   - a '.' with no byte after it ("123#11.22.", "123#."; cansend drops it);
//   - a standard ID above 0x7FF, an 8-digit ID above 0x1FFFFFFF (cansend sends bit 29
//     as an error frame and bits 30/31 as flags);
//   - the raw DLC suffix "_9".."_F" of an 8-byte classic frame (can::Frame has no field
//     for it) and CAN XL's 5-digit IDs (not supported by openvcu's links).
//
// Errors carry the 1-based column of the offending character in the message ("... at
// column 3") and in Error::location.column (file empty, line 0).

#include <string_view>

#include "openvcu/can/frame.hpp"
#include "openvcu/core/result.hpp"

namespace openvcu::cli {

/// Parses one cansend frame argument. The frame's timestamp is 0.
/// @note thread-safe; allocates only to build an error.
[[nodiscard]] Result<can::Frame> parseCansendFrame(std::string_view text);

}  // namespace openvcu::cli
