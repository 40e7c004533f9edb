#pragma once
// Vector ASC (CANalyzer/CANoe ASCII log) line parser, private to openvcu::can.

#include "scan.hpp"

namespace openvcu::can::detail {

/// Parses ASC lines one at a time; keeps the header state (number base, absolute or
/// relative timestamps, measurement start date) between lines.
///   "date Sam Sep 30 15:06:13.191 2017"            -> start of measurement (read as UTC)
///   "   0.001234 1  18FEF100x       Rx   d 8 01 02 03 04 05 06 07 08  Length = ..."
///   "  30.005021 CANFD   1 Rx  300  Name  1 0 8  8 11 c2 03 04 05 06 07 08  102203 133 303000 ..."
///   "   2.501000 1 ErrorFrame", "   2.510001 2 100 Tx r 8"
/// Non-frame events ("Start of measurement", "CAN 1 Status:...", "1 Statistic: ...",
/// J1939TP and other decoded lines, TxRq) are skipped without an error.
class AscParser {
 public:
  /// `record.frame` must be value-initialised by the caller.
  LineResult parseLine(std::string_view line, LogRecord& record, LineError& error) noexcept;

 private:
  LineResult parseHeader(Scanner& s, LineError& error) noexcept;
  LineResult parseClassic(Scanner& s, std::string_view channel, LogRecord& record, LineError& error) noexcept;
  LineResult parseCanFd(Scanner& s, LogRecord& record, LineError& error) noexcept;
  LineResult parseBytes(Scanner& s, std::size_t count, Frame& frame, LineError& error) const noexcept;

  unsigned m_base{16};             ///< "base hex" (default) or "base dec"
  bool m_relative{false};          ///< "timestamps relative": each time is a delta to the previous event
  bool m_startFromTrigger{false};  ///< the Begin Triggerblock date wins over the "date" header
  std::int64_t m_startNs{0};       ///< measurement start, ns since 1970 (0 when unknown)
  std::int64_t m_previousNs{0};    ///< time of the previous event since the start
};

}  // namespace openvcu::can::detail
