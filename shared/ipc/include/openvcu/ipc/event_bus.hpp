#pragma once
// The event plane (LCM) without seeing LCM: typed publish and subscribe of the structs in
// events.hpp on the channels of one stack instance.
//
//   auto busResult = ipc::EventBus::open(ipc::DEFAULT_EVENT_URL, "hhea");
//   if (!busResult) { std::cerr << busResult.error().toString() << '\n'; return 1; }
//   ipc::EventBus& events = *busResult;
//   events.onFsmTransition([&](const ipc::FsmTransition& transition) { ... });
//   events.publish(ipc::Heartbeat{.service = "vcu-fsm", ...});
//   // in the main loop: poll/epoll/Waiter on events.fileno(), then events.handle(0ms)
//
// URLs: "udpm://239.255.76.67:7667?ttl=0" (default, this host only), "memq://" (in-process,
// for unit tests), "file://LOG?speed=0" (replay). "tcpq://" (a hub) is refused: its hub
// relays events from any host that reaches it.
//
// Events come from this host only: on udpm, open() attaches a kernel socket filter
// (host_filter.hpp) to LCM's receive socket, so a datagram from another host (multicast
// on the LAN, unicast to the host's address) never reaches a subscription; open() fails
// rather than receive without it. lcm-spy and lcm-logger (plain LCM) still see everything.

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "openvcu/core/result.hpp"
#include "openvcu/ipc/events.hpp"

namespace openvcu::ipc {

struct EventBusImpl;

/// Identifies one subscription for EventBus::unsubscribe.
struct Subscription {
  std::uint64_t id{};
};

enum class HandleResult : std::uint8_t {
  Handled,  ///< one message was dispatched (to zero or more callbacks)
  Timeout,  ///< nothing arrived in time
  Failed,   ///< LCM reported an error (the URL's transport broke)
};

/// A connection to the LCM event plane for one stack instance. Movable.
/// @note publish() may be called from any thread (LCM serialises sends). subscribe,
///       unsubscribe and handle from one thread; callbacks run inside handle(), on that
///       thread. Not real-time: encoding allocates. Never throws.
/// true when `data` fits the layout of `kind`'s LCM type (every string length and array
/// count within the message): what EventBus checks before lcm-gen's decoder sees a message
/// (lcm-gen 1.3 trusts those fields: SIGSEGV or 64 GiB allocations otherwise). For tools and
/// fuzzers that decode events themselves.
[[nodiscard]] bool fitsEventLayout(EventKind kind, const void* data, std::size_t size) noexcept;

/// An encoded fsm_transition_t / fault_event_t (with its fingerprint) -> the plain struct;
/// empty when it does not fit the layout or decode (event_log.hpp reads logs with these).
[[nodiscard]] std::optional<FsmTransition> decodeFsmTransition(const void* data, std::size_t size);
[[nodiscard]] std::optional<FaultEvent> decodeFaultEvent(const void* data, std::size_t size);
/// A FaultEvent -> an encoded fault_event_t (with its fingerprint); empty when it cannot be
/// encoded. For tools that write datagrams or logs themselves.
[[nodiscard]] std::vector<std::uint8_t> encodeFaultEvent(const FaultEvent& fault);

class EventBus {
 public:
  /// Connects to `url` (empty: DEFAULT_EVENT_URL). `instance` names the channels
  /// (isValidName). For udpm the host needs a multicast route (e.g. on lo); without one
  /// LCM's self test fails and the error says so. For udpm the receive socket accepts
  /// datagrams from this host only (see above); an Error when that filter cannot be put on
  /// (no /proc/self/fd, the socket not found, setsockopt refused). Errors for tcpq URLs.
  /// Takes one local round trip more than LCM's own start (a marker on LCM_SELF_TEST).
  static Result<EventBus> open(std::string_view url, std::string_view instance);

  EventBus(EventBus&& other) noexcept;
  EventBus& operator=(EventBus&& other) noexcept;
  EventBus(const EventBus&) = delete;
  EventBus& operator=(const EventBus&) = delete;
  ~EventBus();

  /// Commands are not events: they go over command sockets (command_socket.hpp); decided
  /// acks are published here for people and recorders.
  /// Encode and send on this instance's channel. false on failure (counted in
  /// publishFailures()). A 0 timestampNs is replaced by the current CLOCK_REALTIME.
  bool publish(const CommandAck& message) noexcept;
  bool publish(const FsmTransition& message) noexcept;
  bool publish(const FaultEvent& message) noexcept;
  bool publish(const LogRecord& message) noexcept;
  bool publish(const Heartbeat& message) noexcept;
  bool publish(const SignalSnapshot& message) noexcept;
  /// Sent as parts of one datagram each (events.hpp); `part` and `parts` are set here.
  bool publish(const Stats& message) noexcept;
  bool publish(const TxSchedule& message) noexcept;
  bool publish(const J1939Network& message) noexcept;
  bool publish(const NodeDm1& message) noexcept;

  /// Calls `callback` from handle() for each message on this instance's channel.
  /// A message that does not decode is dropped and counted (decodeErrors()); an exception
  /// leaving a callback is caught and counted (callbackErrors()).
  Result<Subscription> onAck(std::function<void(const CommandAck&)> callback);
  Result<Subscription> onFsmTransition(std::function<void(const FsmTransition&)> callback);
  Result<Subscription> onFault(std::function<void(const FaultEvent&)> callback);
  Result<Subscription> onLog(std::function<void(const LogRecord&)> callback);
  Result<Subscription> onHeartbeat(std::function<void(const Heartbeat&)> callback);
  Result<Subscription> onSnapshot(std::function<void(const SignalSnapshot&)> callback);
  /// Called once per part (Stats::part of Stats::parts).
  Result<Subscription> onStats(std::function<void(const Stats&)> callback);
  Result<Subscription> onSchedule(std::function<void(const TxSchedule&)> callback);
  Result<Subscription> onJ1939Network(std::function<void(const J1939Network&)> callback);
  Result<Subscription> onNodeDm1(std::function<void(const NodeDm1&)> callback);
  void unsubscribe(Subscription subscription) noexcept;

  /// Readable when a message waits: for poll/epoll or Waiter::attachFd. -1 on failure.
  [[nodiscard]] int fileno() const noexcept;

  /// Dispatches at most one waiting message, waiting up to `timeout` for one (0: do not
  /// wait). Callbacks run inside.
  HandleResult handle(std::chrono::milliseconds timeout) noexcept;

  /// Dispatches everything already waiting without blocking; returns how many.
  std::size_t handleAll() noexcept;

  [[nodiscard]] const std::string& instance() const noexcept;
  [[nodiscard]] const std::string& url() const noexcept;
  /// This instance's channel for `kind`.
  [[nodiscard]] std::string channel(EventKind kind) const;

  [[nodiscard]] std::uint64_t publishFailures() const noexcept;
  [[nodiscard]] std::uint64_t decodeErrors() const noexcept;
  [[nodiscard]] std::uint64_t callbackErrors() const noexcept;

 private:
  explicit EventBus(std::unique_ptr<EventBusImpl> impl) noexcept;
  std::unique_ptr<EventBusImpl> m_impl;
};

}  // namespace openvcu::ipc
