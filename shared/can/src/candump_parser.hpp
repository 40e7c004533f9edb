#pragma once
// candump (linux-can/can-utils) line parser, private to openvcu::can.

#include "scan.hpp"

namespace openvcu::can::detail {

/// Parses one non-blank, non-comment candump line into `record` (frame, channel, time,
/// direction; the caller sets `record.line`). Accepts, per line:
///   -L:      "(1436509052.249713) can0 18FEF100#0102030405060708 R"
///            "(...) can0 123##1DEADBEEF", "(...) can0 123#R5", "(...) can0 20000004#0004..."
///   console: "(2015-07-10 08:17:32.249713)  can0  RX B -  123  [12]  00 11 ... 'ascii'"
///            "  can0  123   [2]  remote request", "  can0  20000004   [8]  ...  ERRORFRAME"
/// `record.frame` must be value-initialised by the caller.
LineResult parseCandumpLine(std::string_view line, LogRecord& record, LineError& error) noexcept;

}  // namespace openvcu::can::detail
