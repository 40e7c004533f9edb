#pragma once
// Frame faults on what the simulated vehicle sends (`vcu inject`, the SimFault key
// KIND.TARGET[=PARAM]): every frame the nodes send passes send(), which drops, replays,
// corrupts, re-addresses or delays the frames of the targets of the active faults; step()
// sends the delayed frames when due, a hostile Address Claimed once, and a babbling node's
// priority-0 frames at the asked share of the bus's bit rate. A bus off cuts a bus both ways:
// nothing the nodes send goes out on it, and the app gives nothing received on it to the
// models (cut()). A thread-free engine on explicit time; the app wires it between the
// models and the links.
//
//   auto request = parseFrameFault("delay.VIC=300");      // Result<FrameFaultRequest>
//   faults.apply(*request, true, bus.transmitted("VIC"), nowNs);   // refusal reason or empty
//   faults.send(busIndex, frame, nowNs, out);             // each frame the nodes send
//   faults.step(nowNs, out);                              // delayed, claim, babble frames
//   sleep until min(..., faults.nextDueNs())

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "openvcu/can/frame.hpp"
#include "openvcu/core/result.hpp"
#include "openvcu/j1939/name.hpp"
#include "virtual_bus.hpp"

namespace openvcu::ecusim {

enum class FrameFaultKind : std::uint8_t { Silent, Delay, Corrupt, Replay, Spoof, Claim, Babble, BusOff };

/// One frame fault as asked: "corrupt.PDU_Tx_1=FF01" -> {Corrupt, "PDU_Tx_1", "FF01"}.
struct FrameFaultRequest {
  FrameFaultKind kind{};
  std::string target;      ///< a DBC message or node; the address (claim); the bus (babble, busoff)
  std::string parameter;   ///< as given; empty when there is none
  std::int64_t delayNs{};  ///< delay, replay (the age)
  std::array<std::uint8_t, can::MAX_DATA_LENGTH> mask{};  ///< corrupt: XORed from byte 0
  std::size_t maskLength{};
  std::uint8_t address{};  ///< spoof, claim
  double load{};           ///< babble: 0..1
  /// "delay.VIC": the fault's identity (what `off` names) and its LCM fault name after "sim.".
  [[nodiscard]] std::string name() const;
};

/// Parses KIND.TARGET[=PARAM]; empty when the key is no frame fault (KIND is not one of
/// silent, delay, corrupt, replay, spoof, claim, babble, busoff), an Error naming the bad part
/// otherwise (a parameter missing or out of range).
[[nodiscard]] std::optional<Result<FrameFaultRequest>> parseFrameFault(std::string_view key, bool on);

/// A bus as the faults see it.
struct FaultBus {
  std::string name;
  std::uint32_t bitrate{};
  std::uint32_t dataBitrate{};
  std::optional<j1939::Name> vcuName;  ///< the VCU's NAME here (claim); none: no j1939 object
};

/// The priority-0 identifier of the babbling node: PGN 0xEF00 (Proprietary A, 61184) to
/// global from 0xFD (253).
inline constexpr std::uint32_t BABBLE_CAN_ID = 0x00EFFFFDu;

/// @note restricted thread-safe: apply, send, step on one thread (the simulation's); the
///       counters are atomics any thread may read (heartbeat). Allocation-free per frame
///       (apply allocates the fault's target list).
class FrameFaults {
 public:
  /// The history (for replay) and the delay line are allocated here.
  explicit FrameFaults(std::vector<FaultBus> buses);

  /// Starts (`on`) or ends the fault; `targets` are the frames of the request's target
  /// (VirtualBus::transmitted; unused for claim and babble). Returns the refusal reason: an
  /// unknown bus, no VCU NAME to outrank, no frame of that age to replay, too many faults.
  std::optional<std::string> apply(const FrameFaultRequest& request, bool on, std::vector<FrameTarget> targets,
                                   std::int64_t nowNs);

  /// One frame a node sends at `nowNs`: passed on to `out(busIndex, frame)` changed, later
  /// (delay) or not at all (silent), and kept in the history.
  template <typename Out>
  void send(std::size_t busIndex, const can::Frame& frame, std::int64_t nowNs, Out&& out) noexcept;
  /// Sends what is due: delayed frames, a claim, babble frames (at most BABBLE_BURST a call).
  template <typename Out>
  void step(std::int64_t nowNs, Out&& out) noexcept;
  [[nodiscard]] std::int64_t nextDueNs() const noexcept;
  [[nodiscard]] std::size_t active() const noexcept { return m_faults.size(); }
  /// true while a bus off cuts bus `busIndex`: the app drops what it receives there (counted
  /// in `dropped`), and nothing is sent on it.
  [[nodiscard]] bool cut(std::size_t busIndex) const noexcept {
    return m_cutBuses != 0 && std::any_of(m_faults.begin(), m_faults.end(), [&](const Fault& fault) {
             return fault.request.kind == FrameFaultKind::BusOff && fault.bus == busIndex;
           });
  }

  static constexpr std::size_t MAX_FAULTS = 32;
  static constexpr std::size_t HISTORY = 16384;    ///< frames kept for replay (about 10 s of HHEA)
  static constexpr std::size_t DELAY_LINE = 4096;  ///< frames held back at once; more are dropped
  static constexpr std::size_t BABBLE_BURST = 64;

  // Counters (heartbeat: inject_*).
  std::atomic<std::int64_t> dropped{};  ///< silenced frames, delayed ones beyond DELAY_LINE, both ways of a bus off
  std::atomic<std::int64_t> delayed{};
  std::atomic<std::int64_t> corrupted{};
  std::atomic<std::int64_t> replayed{};
  std::atomic<std::int64_t> spoofed{};
  std::atomic<std::int64_t> claims{};
  std::atomic<std::int64_t> babbleFrames{};

 private:
  struct Fault {
    FrameFaultRequest request;
    std::string name;
    std::vector<FrameTarget> targets;
    std::vector<can::Frame> replayFrames;  ///< by target: the frame captured at apply
    std::size_t bus{};                     ///< babble, busoff
    std::int64_t periodNs{};               ///< babble
    std::int64_t nextNs{NEVER};            ///< babble
    bool claimPending{};
  };
  struct Recorded {
    std::int64_t atNs{};
    std::size_t bus{};
    std::uint32_t id{};  ///< as the node sent it (before spoofing)
    can::Frame frame;    ///< as it went out
  };
  struct Held {
    std::int64_t dueNs{};
    std::size_t bus{};
    std::uint32_t id{};
    can::Frame frame;
  };

  [[nodiscard]] static std::optional<std::size_t> targetIndex(const Fault& fault, std::size_t bus,
                                                              const can::Frame& frame) noexcept;
  template <typename Out>
  void emit(std::size_t bus, std::uint32_t id, const can::Frame& frame, std::int64_t nowNs, Out&& out) noexcept;

  std::vector<FaultBus> m_buses;
  std::vector<Fault> m_faults;      ///< capacity MAX_FAULTS
  std::vector<Recorded> m_history;  ///< ring of HISTORY
  std::size_t m_historyNext{};
  std::size_t m_historyCount{};
  std::vector<Held> m_held;  ///< capacity DELAY_LINE, in send order
  std::uint64_t m_babbleCounter{};
  std::size_t m_cutBuses{};  ///< bus off faults active
};

template <typename Out>
void FrameFaults::emit(std::size_t bus, std::uint32_t id, const can::Frame& frame, std::int64_t nowNs,
                       Out&& out) noexcept {
  Recorded& slot = m_history[m_historyNext];
  slot = Recorded{nowNs, bus, id, frame};
  m_historyNext = (m_historyNext + 1) % HISTORY;
  if (m_historyCount < HISTORY) ++m_historyCount;
  out(bus, frame);
}

template <typename Out>
void FrameFaults::send(std::size_t busIndex, const can::Frame& frame, std::int64_t nowNs, Out&& out) noexcept {
  if (m_faults.empty()) {
    emit(busIndex, frame.id, frame, nowNs, out);
    return;
  }
  if (cut(busIndex)) {
    dropped.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  can::Frame sent = frame;
  std::int64_t delayNs = 0;
  for (const Fault& fault : m_faults) {
    const auto index = targetIndex(fault, busIndex, frame);
    if (!index) continue;
    switch (fault.request.kind) {
      case FrameFaultKind::Silent:
        dropped.fetch_add(1, std::memory_order_relaxed);
        return;
      case FrameFaultKind::Replay:
        sent = fault.replayFrames[*index];
        replayed.fetch_add(1, std::memory_order_relaxed);
        break;
      case FrameFaultKind::Corrupt:
        for (std::size_t i = 0; i < fault.request.maskLength && i < sent.length; ++i)
          sent.data[i] ^= fault.request.mask[i];
        corrupted.fetch_add(1, std::memory_order_relaxed);
        break;
      case FrameFaultKind::Spoof:
        sent.id = (sent.id & ~0xFFu) | fault.request.address;
        spoofed.fetch_add(1, std::memory_order_relaxed);
        break;
      case FrameFaultKind::Delay:
        delayNs = std::max(delayNs, fault.request.delayNs);
        break;
      case FrameFaultKind::Claim:
      case FrameFaultKind::Babble:
      case FrameFaultKind::BusOff:
        break;
    }
  }
  if (delayNs == 0) {
    emit(busIndex, frame.id, sent, nowNs, out);
    return;
  }
  if (m_held.size() == DELAY_LINE) {
    dropped.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  m_held.push_back(Held{nowNs + delayNs, busIndex, frame.id, sent});
  delayed.fetch_add(1, std::memory_order_relaxed);
}

template <typename Out>
void FrameFaults::step(std::int64_t nowNs, Out&& out) noexcept {
  if (!m_held.empty()) {
    std::size_t kept = 0;
    for (std::size_t i = 0; i < m_held.size(); ++i) {
      if (m_held[i].dueNs <= nowNs && cut(m_held[i].bus)) {
        dropped.fetch_add(1, std::memory_order_relaxed);
      } else if (m_held[i].dueNs <= nowNs) {
        emit(m_held[i].bus, m_held[i].id, m_held[i].frame, nowNs, out);
      } else {
        m_held[kept++] = m_held[i];
      }
    }
    m_held.resize(kept);
  }
  for (Fault& fault : m_faults) {
    if (fault.claimPending) {
      fault.claimPending = false;
      for (std::size_t b = 0; b < m_buses.size(); ++b) {
        if (!m_buses[b].vcuName || cut(b)) continue;
        const j1939::Name hostile = j1939::Name::fromValue(m_buses[b].vcuName->toValue() - 1);
        const j1939::NamePayload bytes = j1939::encodeName(hostile);
        can::Frame claim;
        claim.id = 0x18EEFF00u | fault.request.address;  // SAE J1939-81 Address Claimed, PGN 0xEE00 (60928)
        claim.flags = can::FLAG_EXTENDED;
        claim.length = static_cast<std::uint8_t>(bytes.size());
        std::copy(bytes.begin(), bytes.end(), claim.data.begin());
        out(b, claim);
        claims.fetch_add(1, std::memory_order_relaxed);
      }
    }
    if (fault.request.kind != FrameFaultKind::Babble) continue;
    for (std::size_t n = 0; n < BABBLE_BURST && fault.nextNs <= nowNs && !cut(fault.bus); ++n) {
      can::Frame babble;
      babble.id = BABBLE_CAN_ID;
      babble.flags = can::FLAG_EXTENDED;
      babble.length = 8;
      for (std::size_t i = 0; i < 8; ++i) babble.data[i] = static_cast<std::uint8_t>(m_babbleCounter >> (8 * i));
      ++m_babbleCounter;
      out(fault.bus, babble);
      babbleFrames.fetch_add(1, std::memory_order_relaxed);
      fault.nextNs += fault.periodNs;
    }
    if (fault.nextNs <= nowNs) fault.nextNs = nowNs + fault.periodNs;  // a backlog beyond the burst is skipped
  }
}

}  // namespace openvcu::ecusim
