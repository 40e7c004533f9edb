#include "can_rx_app.hpp"

#include "openvcu/service/app_impl.hpp"

#include <array>
#include <deque>
#include <optional>

#include <climits>

#include "openvcu/core/clock.hpp"
#include "openvcu/ipc/frame_stream.hpp"
#include "openvcu/ipc/request_stream.hpp"
#include "openvcu/service/bus_ports.hpp"
#include "receiver.hpp"

namespace openvcu::canrx {
namespace {

constexpr std::size_t BATCH = 64;
/// Under sustained traffic the loop's batch window grows from the receive file's
/// batchWindowUs up to this many times it (1 ms -> 4 ms by default): fewer wake-ups, at
/// most this window of added latency (services/can-rx/README.md).
constexpr std::int64_t MAX_WINDOW_FACTOR = 4;
/// A drain that read more frames than this (an eighth of the sim link's 256-sample queue)
/// skips the next window and resets it: the queue must keep room for a sender's burst
/// while the loop sleeps (at 32,000 frames/s the window then stays at 1-2 ms).
constexpr std::size_t QUEUE_HIGH = 32;

can::LinkOptions linkOptions(const config::BusConfig& bus, std::vector<can::IdFilter> filters) {
  can::LinkOptions options = bus.linkOptions();
  if (bus.filter == config::BusFilter::Dbc) options.filters = std::move(filters);
  return options;
}

void fill(ipc::FrameSample& sample, const can::Frame& frame, std::int64_t monotonicNs, std::size_t bus) noexcept {
  sample.frame = frame;
  sample.monotonicNs = monotonicNs;
  sample.hardwareNs = frame.timestampNs;
  sample.busIndex = static_cast<std::uint16_t>(bus);
}

}  // namespace

/// One bus: its link and streams (service::BusPorts, Receiver role) and their counters.
struct BusIo : service::BusPorts {
  std::uint64_t publishFailures{};
  std::uint64_t forwardFailures{};
  std::uint64_t transmitFailures{};
};

struct CanRxAppImpl final : ReceiverOutputs {
  service::Service& runtime;
  std::deque<BusIo> buses;  // deque: stable addresses for the loop's callbacks
  std::optional<Receiver> receiver;
  std::optional<service::Loop::DeadlineId> deadline;  ///< the loop's one-shot at the receiver's next deadline
  std::int64_t armedNs{INT64_MAX};
  std::int64_t nextWindowNs{};
  std::array<can::ReceivedFrame, BATCH> batch{};

  explicit CanRxAppImpl(service::Service& service) : runtime(service) {}
  ~CanRxAppImpl() override {
    if (deadline) runtime.loop().removeDeadline(*deadline);
  }

  /// Moves the loop's deadline to the receiver's next deadline when that is earlier than
  /// the armed one (frames only move deadlines later, so it is re-armed on each tick). A
  /// loop deadline is a value, not a timer: setting it makes no system call.
  void arm(bool force) noexcept {
    const std::int64_t next = receiver->nextDeadlineNs();
    if (!force && next >= armedNs) return;
    runtime.loop().setDeadline(*deadline, service::MonotonicTime{std::chrono::nanoseconds{next}});
    armedNs = next;
  }

  // ---- ReceiverOutputs --------------------------------------------------------------------

  static bool publish(std::optional<ipc::FramePublisher>& publisher, const can::Frame& frame,
                      std::int64_t monotonicNs, std::size_t bus) noexcept {
    if (!publisher) return false;
    // Nobody listening (no trace view, recorder or can-tx): iceoryx would drop the sample;
    // skipping the loan saves most of the per-frame cost.
    if (!publisher->hasSubscribers()) return true;
    std::optional<ipc::FrameLoan> maybeLoan = publisher->loan();
    if (!maybeLoan) return false;
    fill(maybeLoan->sample(), frame, monotonicNs, bus);
    return publisher->publish(std::move(*maybeLoan));
  }

  void received(std::size_t bus, const can::ReceivedFrame& frame) noexcept override {
    if (!publish(buses[bus].received, frame.frame, frame.monotonicNs, bus)) ++buses[bus].publishFailures;
  }
  void request(std::size_t bus, const j1939::Request& request, std::int64_t monotonicNs) noexcept override {
    ipc::RequestPublisher& publisher = *buses[bus].requestsOut;
    if (!publisher.hasSubscribers()) return;  // no can-tx: iceoryx would drop it
    ipc::RequestSample sample{};
    sample.monotonicNs = monotonicNs;
    sample.pgn = request.pgn;
    sample.bus = static_cast<std::uint16_t>(bus);
    sample.requester = request.requester;
    sample.global = request.global;
    if (!publisher.publish(sample)) ++buses[bus].publishFailures;
  }
  void network(std::size_t bus, const can::ReceivedFrame& frame) noexcept override {
    if (!publish(buses[bus].networkOut, frame.frame, frame.monotonicNs, bus)) ++buses[bus].publishFailures;
  }
  void forward(std::size_t toBus, const can::Frame& frame) noexcept override {
    if (!publish(buses[toBus].sendRequestsOut, frame, clock::monotonicNs(), toBus)) ++buses[toBus].forwardFailures;
  }
  bool transmit(std::size_t bus, const can::Frame& frame) noexcept override {
    BusIo& io = buses[bus];
    if (io.link->send(frame) != can::SendStatus::Sent) {
      ++io.transmitFailures;
      return false;
    }
    (void)publish(io.sent, frame, clock::monotonicNs(), bus);
    return true;
  }
  void fault(const ipc::FaultEvent& event) override {
    runtime.events().publish(event);
    const std::string text = (event.active ? "fault raised: " : "fault cleared: ") + event.name + ": " + event.text;
    if (event.active) {
      runtime.log().warning(text);
    } else {
      runtime.log().info(text);
    }
  }

  void dm1(const ipc::NodeDm1& message) override {
    ipc::NodeDm1 stamped = message;
    stamped.service = runtime.program();
    stamped.instance = runtime.instance();
    runtime.events().publish(stamped);
  }

  // ---- the loop ---------------------------------------------------------------------------

  void drain(std::size_t bus) noexcept {
    can::Link& link = *buses[bus].link;
    std::size_t total = 0;
    for (;;) {
      const std::size_t count = link.receive(batch);
      for (std::size_t i = 0; i < count; ++i) receiver->onFrame(bus, batch[i]);
      total += count;
      if (count < batch.size()) break;
    }
    if (total > QUEUE_HIGH) runtime.loop().skipNextBatchWindow();
    arm(false);
    while (const std::optional<can::BusEvent> maybeEvent = link.nextEvent()) {
      receiver->onBusEvent(bus, *maybeEvent);
      logBusEvent(bus, *maybeEvent);
    }
  }

  /// State changes are logged; the frequent error classes are only counted.
  void logBusEvent(std::size_t bus, const can::BusEvent& event) noexcept {
    switch (event.kind) {
      case can::BusEventKind::ProtocolError:
      case can::BusEventKind::NoAck:
      case can::BusEventKind::RxOverflow:
      case can::BusEventKind::TxTimeout:
        return;
      default:
        break;
    }
    try {
      runtime.log().info("bus " + runtime.config().buses[bus].name + " (" + buses[bus].link->name() +
                         "): " + std::string(can::busEventName(event.kind)));
    } catch (...) {
    }
  }

  void onTick() noexcept {
    const std::int64_t now = clock::monotonicNs();
    receiver->onTick(now);
    if (now >= nextWindowNs) {
      receiver->rollPeriodWindow();
      nextWindowNs = now + 1'000'000'000;
    }
    arm(true);
  }

  Status open() {
    const config::VehicleConfig& vehicle = runtime.config();
    auto receiveResult = loadReceiveConfig(vehicle);
    if (!receiveResult) return receiveResult.error();
    const std::int64_t start = clock::monotonicNs();
    auto receiverResult =
        Receiver::create(vehicle, std::move(*receiveResult), runtime.catalog(), runtime.table(), *this, start);
    if (!receiverResult) return receiverResult.error();
    receiver.emplace(std::move(*receiverResult));

    const std::string& instance = runtime.instance();
    for (std::size_t b = 0; b < vehicle.buses.size(); ++b) {
      const config::BusConfig& bus = vehicle.buses[b];
      auto portsResult =
          service::openBusPorts(instance, bus, linkOptions(bus, receiver->filters(b)), service::BusRole::Receiver);
      if (!portsResult) return portsResult.error();
      static_cast<service::BusPorts&>(buses.emplace_back()) = std::move(*portsResult);
    }
    for (std::size_t b = 0; b < buses.size(); ++b) {
      if (Status added = runtime.loop().addLink(*buses[b].link, [this, b] { drain(b); }); !added) return added.error();
    }
    auto deadlineResult = runtime.loop().addDeadline([this] { onTick(); });
    if (!deadlineResult) return deadlineResult.error();
    deadline = *deadlineResult;
    arm(true);
    const std::chrono::microseconds window{receiver->batchWindowUs()};
    runtime.loop().setBatchWindow(window, window * MAX_WINDOW_FACTOR);
    registerCounters();
    return {};
  }

  void registerCounters() {
    const config::VehicleConfig& vehicle = runtime.config();
    for (std::size_t b = 0; b < buses.size(); ++b) {
      const std::string prefix = vehicle.buses[b].name + ".";
      auto add = [&](const char* name, auto read) {
        runtime.heartbeat().addStatSource(prefix + name, [this, b, read] {
          return static_cast<std::int64_t>(read(receiver->counters(b), buses[b]));
        });
      };
      add("frames", [](const BusCounters& c, const BusIo&) { return c.frames; });
      add("decoded", [](const BusCounters& c, const BusIo&) { return c.decoded; });
      add("own_frames", [](const BusCounters& c, const BusIo&) { return c.ownFrames; });
      add("unknown_ids", [](const BusCounters& c, const BusIo&) { return c.unknownIds; });
      add("decode_errors", [](const BusCounters& c, const BusIo&) { return c.decodeErrors; });
      add("out_of_range", [](const BusCounters& c, const BusIo&) { return c.outOfRange; });
      add("timeouts", [](const BusCounters& c, const BusIo&) { return c.timeouts; });
      add("requests", [](const BusCounters& c, const BusIo&) { return c.requests; });
      add("address_claims", [](const BusCounters& c, const BusIo&) { return c.addressClaims; });
      add("own_address_changes", [](const BusCounters& c, const BusIo&) { return c.ownAddressChanges; });
      add("tp_sessions", [](const BusCounters& c, const BusIo&) { return c.tpSessions; });
      add("tp_completed", [](const BusCounters& c, const BusIo&) { return c.tpCompleted; });
      add("tp_aborted", [](const BusCounters& c, const BusIo&) { return c.tpAborted; });
      add("dm1", [](const BusCounters& c, const BusIo&) { return c.dm1Messages; });
      add("safety_failures", [](const BusCounters& c, const BusIo&) { return c.safetyFailures; });
      add("forwarded", [](const BusCounters& c, const BusIo&) { return c.forwarded; });
      add("bus_errors", [](const BusCounters& c, const BusIo&) { return c.busErrors; });
      add("load_permille", [](const BusCounters& c, const BusIo&) { return c.loadPermille; });
      add("dropped", [](const BusCounters&, const BusIo& io) { return io.link->stats().receiveDropped; });
      add("publish_failures", [](const BusCounters&, const BusIo& io) { return io.publishFailures; });
      add("forward_failures", [](const BusCounters&, const BusIo& io) { return io.forwardFailures; });
      add("transmit_failures", [](const BusCounters&, const BusIo& io) { return io.transmitFailures; });
    }
    for (const std::size_t messageIndex : receiver->trackedMessages()) {
      const std::string prefix = "rx." + vehicle.database.messages[messageIndex].name + ".";
      auto add = [&](const char* name, auto read) {
        runtime.heartbeat().addStatSource(prefix + name, [this, messageIndex, read] {
          return static_cast<std::int64_t>(read(receiver->messageCounters(messageIndex)));
        });
      };
      add("frames", [](const MessageCounters& c) { return c.frames; });
      add("cycle_us", [](const MessageCounters& c) { return c.dbcCycleNs / 1000; });
      add("period_us", [](const MessageCounters& c) { return c.meanPeriodNs / 1000; });
      add("max_period_us", [](const MessageCounters& c) { return c.maxPeriodNs / 1000; });
      add("stale", [](const MessageCounters& c) { return c.stale ? 1 : 0; });
    }
  }
};

}  // namespace openvcu::canrx

template class openvcu::service::App<openvcu::canrx::CanRxAppImpl>;
