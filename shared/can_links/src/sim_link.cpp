#include "openvcu/can_links/sim_link.hpp"

#include <ctime>

#include "openvcu/can/event_queue.hpp"
#include "openvcu/ipc/frame_stream.hpp"

namespace openvcu::can {
namespace {

std::int64_t clockNs(clockid_t clock) noexcept {
  timespec now{};
  clock_gettime(clock, &now);
  return static_cast<std::int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
}

class SimLink final : public Link {
 public:
  SimLink(std::string name, ipc::FramePublisher publisher, ipc::FrameSubscriber subscriber, LinkOptions options)
      : m_name(std::move(name)),
        m_publisher(std::move(publisher)),
        m_subscriber(std::move(subscriber)),
        m_options(std::move(options)),
        m_ownSender(m_publisher.senderId()) {}

  [[nodiscard]] LinkKind kind() const noexcept override { return LinkKind::Sim; }
  [[nodiscard]] const std::string& name() const noexcept override { return m_name; }
  // ipc::FrameSubscriber is a can::WaitSource: service::Loop::addLink waits on it
  [[nodiscard]] WaitHandle waitHandle() noexcept override { return WaitHandle{-1, &m_subscriber}; }

  std::size_t receive(std::span<ReceivedFrame> out) noexcept override {
    if (m_subscriber.hasLostFrames()) {
      // The subscriber queue overflowed: frames were lost before we read them. The
      // per-sender sequence gap below counts how many.
      m_events.push(BusEvent{BusEventKind::RxOverflow, clockNs(CLOCK_MONOTONIC), 0, 0, 0});
    }
    std::size_t count = 0;
    while (count < out.size()) {
      const std::optional<ipc::FrameSample> maybeSample = m_subscriber.take();
      if (!maybeSample) break;
      const ipc::FrameSample& sample = *maybeSample;
      if (sample.senderId == m_ownSender) continue;
      countGap(sample);
      if (!passes(m_options.filters, sample.frame)) {
        ++m_stats.filteredOut;
        continue;
      }
      out[count].frame = sample.frame;
      out[count].monotonicNs = sample.monotonicNs;
      ++count;
    }
    m_stats.framesReceived += count;
    return count;
  }

  SendStatus send(const Frame& frame) noexcept override {
    const SendStatus verdict = check(frame);
    if (verdict != SendStatus::Sent) {
      ++m_stats.sendFailures;
      return verdict;
    }
    std::optional<ipc::FrameLoan> maybeLoan = m_publisher.loan();
    if (!maybeLoan) {
      ++m_stats.sendFailures;
      return SendStatus::Busy;
    }
    ipc::FrameSample& sample = maybeLoan->sample();
    sample.frame = frame;
    sample.frame.timestampNs = clockNs(CLOCK_REALTIME);
    sample.monotonicNs = clockNs(CLOCK_MONOTONIC);
    if (!m_publisher.publish(std::move(*maybeLoan))) {
      ++m_stats.sendFailures;
      return SendStatus::Busy;
    }
    ++m_stats.framesSent;
    return SendStatus::Sent;
  }

  std::optional<BusEvent> nextEvent() noexcept override { return m_events.pop(); }
  [[nodiscard]] bool up() const noexcept override { return true; }
  [[nodiscard]] LinkStats stats() const noexcept override { return m_stats; }

 private:
  /// A sim bus carries what a real one of its kind could.
  [[nodiscard]] SendStatus check(const Frame& frame) const noexcept {
    if ((frame.flags & FLAG_ERROR) != 0) return SendStatus::Invalid;
    const std::uint32_t idMask = frame.extended() ? EXTENDED_ID_MASK : STANDARD_ID_MASK;
    if ((frame.id & ~idMask) != 0) return SendStatus::Invalid;
    if (frame.fd()) {
      if (!m_options.fd || (frame.flags & FLAG_RTR) != 0) return SendStatus::Invalid;
      if (frame.length > MAX_DATA_LENGTH || roundUpFdLength(frame.length) != frame.length) return SendStatus::Invalid;
    } else if (frame.length > CLASSIC_DATA_LENGTH || (frame.flags & (FLAG_BRS | FLAG_ESI)) != 0) {
      return SendStatus::Invalid;
    }
    return SendStatus::Sent;
  }

  /// Sequence gaps per sender: frames the queue dropped. A small fixed table of senders.
  void countGap(const ipc::FrameSample& sample) noexcept {
    for (Peer& peer : m_peers) {
      if (peer.senderId == sample.senderId) {
        if (sample.sequence > peer.lastSequence + 1) m_stats.receiveDropped += sample.sequence - peer.lastSequence - 1;
        peer.lastSequence = sample.sequence;
        return;
      }
    }
    Peer& slot = m_peers[m_nextPeer];
    m_nextPeer = (m_nextPeer + 1) % m_peers.size();
    slot = Peer{sample.senderId, sample.sequence};
  }

  struct Peer {
    std::uint32_t senderId{};
    std::uint64_t lastSequence{};
  };

  std::string m_name;
  ipc::FramePublisher m_publisher;
  ipc::FrameSubscriber m_subscriber;
  LinkOptions m_options;
  std::uint32_t m_ownSender;
  LinkStats m_stats{};
  detail::EventQueue m_events;
  std::array<Peer, 32> m_peers{};
  std::size_t m_nextPeer{};
};

}  // namespace

Result<std::unique_ptr<Link>> openSimLink(const std::string& busName, const LinkOptions& options) {
  const std::string name = "sim:" + busName;
  if (!ipc::isValidName(busName)) {
    return Error{name + ": a simulated bus name is 1..32 letters, digits, '-' or '_'"};
  }
  const ipc::FrameTopic topic{"sim", busName, ipc::FrameStream::SimWire};
  auto publisherResult = ipc::FramePublisher::create(topic);
  if (!publisherResult) return Error{name + ": " + publisherResult.error().message};
  ipc::FrameSubscriberOptions subscriberOptions;
  subscriberOptions.queueCapacity = 256;
  auto subscriberResult = ipc::FrameSubscriber::create(topic, subscriberOptions);
  if (!subscriberResult) return Error{name + ": " + subscriberResult.error().message};
  return std::unique_ptr<Link>(
      new SimLink(name, std::move(*publisherResult), std::move(*subscriberResult), options));
}

}  // namespace openvcu::can
