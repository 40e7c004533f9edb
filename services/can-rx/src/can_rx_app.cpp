#include "can_rx_app.hpp"

#include "openvcu/service/app_impl.hpp"

#include <array>
#include <deque>
#include <optional>

#include <sys/timerfd.h>
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cstring>

#include "openvcu/core/clock.hpp"
#include "openvcu/ipc/frame_stream.hpp"
#include "openvcu/ipc/request_stream.hpp"
#include "openvcu/service/bus_ports.hpp"
#include "receiver.hpp"

namespace openvcu::canrx {
namespace {

constexpr std::size_t BATCH = 64;

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
  int deadlineFd{-1};           ///< timerfd, one shot at the receiver's next deadline
  std::int64_t armedNs{INT64_MAX};
  std::int64_t nextWindowNs{};
  std::array<can::ReceivedFrame, BATCH> batch{};

  explicit CanRxAppImpl(service::Service& service) : runtime(service) {}
  ~CanRxAppImpl() override {
    if (deadlineFd >= 0) {
      runtime.loop().removeFd(deadlineFd);
      ::close(deadlineFd);
    }
  }

  /// Arms the deadline timer when the receiver's next deadline is earlier than the armed
  /// one (frames only move deadlines later, so the timer is re-armed on each tick).
  void arm(bool force) noexcept {
    const std::int64_t next = receiver->nextDeadlineNs();
    if (!force && next >= armedNs) return;
    itimerspec spec{};
    spec.it_value.tv_sec = static_cast<time_t>(next / 1'000'000'000);
    spec.it_value.tv_nsec = static_cast<long>(next % 1'000'000'000);
    if (spec.it_value.tv_sec == 0 && spec.it_value.tv_nsec == 0) spec.it_value.tv_nsec = 1;
    if (::timerfd_settime(deadlineFd, TFD_TIMER_ABSTIME, &spec, nullptr) == 0) armedNs = next;
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

  // ---- the loop ---------------------------------------------------------------------------

  void drain(std::size_t bus) noexcept {
    can::Link& link = *buses[bus].link;
    for (;;) {
      const std::size_t count = link.receive(batch);
      for (std::size_t i = 0; i < count; ++i) receiver->onFrame(bus, batch[i]);
      if (count < batch.size()) break;
    }
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
    std::uint64_t expirations = 0;
    [[maybe_unused]] const auto got = ::read(deadlineFd, &expirations, sizeof expirations);
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
    deadlineFd = ::timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC);
    if (deadlineFd < 0) return Error{std::string("timerfd_create: ") + std::strerror(errno)};
    if (Status added = runtime.loop().addFd(deadlineFd, [this] { onTick(); }); !added) return added.error();
    arm(true);
    runtime.loop().setBatchWindow(std::chrono::microseconds{receiver->batchWindowUs()});
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
