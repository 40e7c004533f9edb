#pragma once
// A CAN link: one bus as a service sees it, whatever is underneath.
//   socketcan:IFACE  Linux raw CAN / CAN FD socket (socketcan_link.hpp)
//   sim:NAME         the virtual bus over iceoryx (shared/can_links: sim_link.hpp)
//   replay:FILE      a recorded log played with its original timing (replay_link.hpp)
// A service opens every configured bus with openLink() (shared/can_links: open_link.hpp)
// and only ever uses this interface:
//
//   auto linkResult = can::openLink(can::LinkKind::Sim, "vehicle", options);
//   can::Link& link = **linkResult;
//   loop.addLink(link, [&] { drain(link); });    // service::Loop waits on link.waitHandle()
//   std::array<can::ReceivedFrame, 64> batch;
//   while (const std::size_t n = link.receive(batch)) { ...; if (n < batch.size()) break; }
//   while (auto maybeEvent = link.nextEvent()) report(*maybeEvent);
//   if (link.send(frame) != can::SendStatus::Sent) ++sendFailures;
//
// The wait handle of a link never changes while the link exists (a socketcan link that
// loses its interface keeps the same epoll fd and reopens behind it), so a service
// registers it once. Design: docs/design/can-links.md.

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "openvcu/can/frame.hpp"

namespace openvcu::can {

enum class LinkKind : std::uint8_t { SocketCan, Sim, Replay };

/// "socketcan", "sim", "replay".
[[nodiscard]] std::string_view linkKindName(LinkKind kind) noexcept;

/// One acceptance filter, SocketCAN semantics: a frame passes when
/// (frame.id & mask) == (id & mask) and its ID kind (11/29 bit) equals `extended`.
struct IdFilter {
  std::uint32_t id{};
  std::uint32_t mask{};
  bool extended{};
  bool operator==(const IdFilter&) const = default;
};

/// true when `filters` is empty or one of them accepts `frame`. Error frames always pass;
/// remote (RTR) frames pass only when there are no filters (as the socketcan backend does).
[[nodiscard]] bool passes(std::span<const IdFilter> filters, const Frame& frame) noexcept;

/// Settings of one link, from the bus configuration. Each backend reads what concerns it.
struct LinkOptions {
  std::uint32_t bitrate{500000};       ///< nominal (arbitration) bit rate, bit/s
  std::uint32_t dataBitrate{2000000};  ///< CAN FD data-phase bit rate, bit/s
  bool fd{false};                      ///< the bus carries CAN FD frames
  /// Receive only frames these accept (empty: everything). socketcan: kernel filters;
  /// sim and replay apply them in user space, so every backend behaves alike.
  std::vector<IdFilter> filters;
  /// socketcan: report error frames as bus events.
  bool errorFrames{true};
  /// socketcan: how often to try to reopen an interface that went away.
  std::chrono::milliseconds reopenInterval{500};
  /// replay: 1.0 = original timing, 2.0 = twice as fast; 0 = as fast as possible.
  double replaySpeed{1.0};
  /// replay: start again from the top at the end of the log.
  bool replayLoop{false};
  /// replay: only records of this log channel ("can0", ASC "1"); empty: all of them.
  std::string replayChannel;
};

/// A frame read from a link.
struct ReceivedFrame {
  /// frame.timestampNs: the kernel or hardware receive stamp (CLOCK_REALTIME ns) on
  /// socketcan, the sender's CLOCK_REALTIME at send on sim, the logged time on replay.
  Frame frame{};
  /// CLOCK_MONOTONIC ns: when it was received (socketcan), sent (sim) or due (replay).
  std::int64_t monotonicNs{};
};

/// Something that happened to the bus or the link, not a frame.
enum class BusEventKind : std::uint8_t {
  LinkUp,           ///< the link (re)opened: frames flow
  LinkDown,         ///< the interface went away or down; the link retries by itself
  ErrorWarning,     ///< controller error counters reached the warning level (96)
  ErrorPassive,     ///< controller error passive (127)
  BusOff,           ///< controller bus-off
  Restarted,        ///< controller restarted after bus-off
  ErrorActive,      ///< controller back to error active
  RxOverflow,       ///< frames lost: controller or socket receive overflow
  TxTimeout,        ///< a frame could not be sent in time
  ProtocolError,    ///< bit, form or stuff error seen on the bus
  NoAck,            ///< no node acknowledged a sent frame
  TransceiverError, ///< the transceiver reported a fault
  ReplayFinished,   ///< replay: the end of the log (and not looping)
  ReplayRestarted,  ///< replay: looping back to the start
};

/// "LinkUp", "BusOff", ...
[[nodiscard]] std::string_view busEventName(BusEventKind kind) noexcept;

struct BusEvent {
  BusEventKind kind{BusEventKind::LinkUp};
  std::int64_t monotonicNs{};
  std::uint32_t detail{};    ///< backend specific: SocketCAN error class bits, errno, ...
  std::uint8_t txErrors{};   ///< controller TX error counter when known
  std::uint8_t rxErrors{};   ///< controller RX error counter when known
};

/// Counters of one link since it was opened.
struct LinkStats {
  std::uint64_t framesReceived{};  ///< delivered by receive()
  std::uint64_t framesSent{};      ///< accepted by send()
  std::uint64_t sendFailures{};    ///< send() returned anything but Sent
  std::uint64_t errorFrames{};     ///< error frames seen (socketcan)
  std::uint64_t receiveDropped{};  ///< frames lost before receive(): socket/queue overflow
  std::uint64_t filteredOut{};     ///< frames the filters rejected in user space
  std::uint64_t reopenings{};      ///< times the link came back after going down
};

enum class SendStatus : std::uint8_t {
  Sent,          ///< handed to the bus (socketcan: the kernel queue)
  Busy,          ///< transmit queue full: try again later (the frame was not sent)
  Down,          ///< the link is down
  Invalid,       ///< the frame cannot go on this bus (FD frame on a classic bus, length > 8, ...)
  NotSupported,  ///< the link cannot send (replay)
};

/// "Sent", "Busy", "Down", "Invalid", "NotSupported".
[[nodiscard]] std::string_view sendStatusName(SendStatus status) noexcept;

/// Something to wait on that is not a file descriptor: the iceoryx subscriber behind a sim
/// link (ipc::SampleSubscriber is one). shared/can knows only this interface; the waiters
/// that know the implementations (ipc::Waiter::attach(WaitHandle), service::Loop::addLink)
/// take a WaitHandle whole, so no service looks inside it.
class WaitSource {
 public:
  virtual ~WaitSource() = default;

 protected:
  WaitSource() = default;
  WaitSource(const WaitSource&) = default;
  WaitSource(WaitSource&&) noexcept = default;
  WaitSource& operator=(const WaitSource&) = default;
  WaitSource& operator=(WaitSource&&) noexcept = default;
};

/// How to wait for a link: exactly one of the two is set.
struct WaitHandle {
  int fd{-1};                   ///< readable when receive() has something to do
  WaitSource* source{nullptr};  ///< has data when receive() has something to do (sim links)
};

/// One bus. Not copyable, not movable (held by unique_ptr).
/// @note restricted thread-safe: one thread at a time. receive() and send() are
///       noexcept, allocation-free and never block.
class Link {
 public:
  Link() = default;
  Link(const Link&) = delete;
  Link& operator=(const Link&) = delete;
  virtual ~Link() = default;

  [[nodiscard]] virtual LinkKind kind() const noexcept = 0;
  /// "socketcan:can0", "sim:vehicle", "replay:/path/drive.log".
  [[nodiscard]] virtual const std::string& name() const noexcept = 0;
  /// Constant for the life of the link.
  [[nodiscard]] virtual WaitHandle waitHandle() noexcept = 0;
  /// Does whatever is pending (reads frames, timers, reopening) without blocking and
  /// writes up to out.size() frames into `out`; returns how many. When it returns
  /// out.size() there may be more: call again. Never blocks.
  virtual std::size_t receive(std::span<ReceivedFrame> out) noexcept = 0;
  /// Sends one frame without blocking.
  virtual SendStatus send(const Frame& frame) noexcept = 0;
  /// The oldest bus event not yet taken, or empty. Events are queued by receive().
  virtual std::optional<BusEvent> nextEvent() noexcept = 0;
  /// true while frames can flow (replay: until the end of a non-looping log).
  [[nodiscard]] virtual bool up() const noexcept = 0;
  [[nodiscard]] virtual LinkStats stats() const noexcept = 0;
};

}  // namespace openvcu::can
