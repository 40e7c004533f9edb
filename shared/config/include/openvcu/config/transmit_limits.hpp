#pragma once
// Limits of what the VCU transmits, defined once for every reader of a transmit schedule:
// vcu-can-tx (schedule.json, its overlay, runtime ScheduleCycle/ScheduleAdd), `vcu schedule
// import` and `vcu schedule cycle|add`, and the HMI's ECU setup. Reference: docs/config.md.
//
//   checkCycleMs(0.5)  -> "the cycle must be a whole number of ms from 1 to 3600000, not 0.5"
//   checkCycleMs(20)   -> empty
//   cyclicBusLoad({{0x18FEF121, true, 8, 10'000'000}}, bus at 500 kbit/s) -> 0.0296 (2.96 %)

#include <cstdint>
#include <optional>
#include <span>
#include <string>

namespace openvcu::config {

struct BusConfig;

/// The shortest cycle, ms. Cycles are whole milliseconds: the schedule, its overlay and the
/// commands all carry ms, and can-tx's timer wakes per frame, so a finer period would be a
/// promise it cannot keep. One ms is the floor rather than J1939-71's usual 10 ms because
/// proprietary messages (inverter set-points) do run at 1-5 ms; what a too-fast schedule
/// really costs, bus time, is judged by the bus-load check below, not by this floor.
inline constexpr std::uint32_t MIN_CYCLE_MS = 1;
/// The longest cycle, ms (one hour; the DBC attribute GenMsgCycleTime's usual maximum).
inline constexpr std::uint32_t MAX_CYCLE_MS = 3'600'000;

/// Empty when `cycleMs` is a whole number from MIN_CYCLE_MS to MAX_CYCLE_MS, else the
/// reason, naming the value (NaN and infinity included).
[[nodiscard]] std::optional<std::string> checkCycleMs(double cycleMs);

/// The most of a bus' time the VCU's own cyclic frames may take: 50 %. The VCU is one node
/// of several on the bus; the others' frames, error frames and retransmissions need the
/// rest, and J1939 buses are laid out to stay well under 70-80 % in total.
inline constexpr double MAX_CYCLIC_BUS_LOAD = 0.5;

/// One cyclic frame of a schedule, for the bus-load check. A frame longer than 8 bytes goes
/// out as CAN FD with bit-rate switch (as vcu-can-tx sends it).
struct CyclicFrame {
  std::uint32_t canId{};
  bool extended{};
  std::uint8_t length{};
  std::int64_t cycleNs{};  ///< > 0
};

/// The share of `bus`' time the frames take (0.25 = 25 %): per frame its exact wire time
/// (can::wireTimeNs at the bus' bit rates) divided by its cycle, summed. The payload is
/// counted as all zero bytes, the most stuff bits a payload can cause (one per 4 data bits),
/// so the result is an upper bound for the data field. Frames with a cycle <= 0 are skipped.
/// @note thread-safe, allocation-free.
[[nodiscard]] double cyclicBusLoad(std::span<const CyclicFrame> frames, const BusConfig& bus) noexcept;

}  // namespace openvcu::config
