#include "openvcu/core/clock.hpp"
#include "openvcu/ipc/frame_stream.hpp"
#include "openvcu/ipc/request_stream.hpp"

#include <time.h>

#include <cstring>
#include <new>
#include <thread>

#include "iceoryx_posh/mepoo/chunk_header.hpp"
#include "iox_ports.hpp"
#include "openvcu/ipc/runtime.hpp"

namespace openvcu::ipc {

namespace {

constexpr auto SAMPLE_SIZE = static_cast<std::uint32_t>(sizeof(FrameSample));
constexpr auto SAMPLE_ALIGNMENT = static_cast<std::uint32_t>(alignof(FrameSample));

Status checkTopic(const FrameTopic& topic) {
  if (!Runtime::initialized()) {
    return Error{"cannot open frame stream " + topic.toString() + ": call ipc::Runtime::init first"};
  }
  if (!isValidName(topic.instance)) {
    return Error{"invalid instance name '" + topic.instance + "': use 1..32 characters of [A-Za-z0-9_-]"};
  }
  if (!isValidName(topic.bus)) {
    return Error{"invalid bus name '" + topic.bus + "': use 1..32 characters of [A-Za-z0-9_-]"};
  }
  return {};
}

void stamp(FramePublisherImpl& publisher, FrameSample& sample) noexcept {
  sample.sequence = publisher.nextSequence++;
  sample.senderId = publisher.senderId;
  sample.busNameHash = publisher.busNameHash;
  if (sample.monotonicNs == 0) sample.monotonicNs = clock::monotonicNs();
}

std::atomic<std::uint32_t> g_publisherCount{0};

}  // namespace

iox::capro::ServiceDescription serviceDescription(const FrameTopic& topic) {
  const std::string instance = topic.instanceString();
  const std::string_view event = eventName(topic.stream);
  return iox::capro::ServiceDescription(
      iox::capro::IdString_t(iox::cxx::TruncateToCapacity, FRAME_TOPIC_SERVICE.data(), FRAME_TOPIC_SERVICE.size()),
      iox::capro::IdString_t(iox::cxx::TruncateToCapacity, instance.data(), instance.size()),
      iox::capro::IdString_t(iox::cxx::TruncateToCapacity, event.data(), event.size()));
}

FramePublisherImpl::FramePublisherImpl(const FrameTopic& frameTopic, const iox::popo::PublisherOptions& options,
                                       std::uint32_t id)
    : topic(frameTopic),
      port(serviceDescription(frameTopic), options),
      senderId(id),
      busNameHash(fnv1a32(frameTopic.bus)) {}

FrameSubscriberImpl::FrameSubscriberImpl(const FrameTopic& frameTopic, const iox::popo::SubscriberOptions& options)
    : topic(frameTopic), port(serviceDescription(frameTopic), options) {}

// ---- FrameLoan ----------------------------------------------------------------------

FrameLoan::FrameLoan(FrameLoan&& other) noexcept : m_owner(other.m_owner), m_sample(other.m_sample) {
  other.m_owner = nullptr;
  other.m_sample = nullptr;
}

FrameLoan& FrameLoan::operator=(FrameLoan&& other) noexcept {
  if (this != &other) {
    reset();
    m_owner = other.m_owner;
    m_sample = other.m_sample;
    other.m_owner = nullptr;
    other.m_sample = nullptr;
  }
  return *this;
}

FrameLoan::~FrameLoan() {
  reset();
}

void FrameLoan::reset() noexcept {
  if (m_owner != nullptr && m_sample != nullptr) m_owner->port.release(m_sample);
  m_owner = nullptr;
  m_sample = nullptr;
}

// ---- FramePublisher -----------------------------------------------------------------

Result<FramePublisher> FramePublisher::create(const FrameTopic& topic, FramePublisherOptions options) {
  if (auto check = checkTopic(topic); !check) return check.error();
  iox::popo::PublisherOptions portOptions;
  portOptions.subscriberTooSlowPolicy = options.waitForSlowSubscribers
                                            ? iox::popo::ConsumerTooSlowPolicy::WAIT_FOR_CONSUMER
                                            : iox::popo::ConsumerTooSlowPolicy::DISCARD_OLDEST_DATA;
  const std::uint32_t index = g_publisherCount.fetch_add(1) + 1;
  const std::uint32_t id = fnv1a32(Runtime::name() + "#" + std::to_string(index));
  return FramePublisher(std::make_unique<FramePublisherImpl>(topic, portOptions, id));
}

FramePublisher::FramePublisher(std::unique_ptr<FramePublisherImpl> impl) noexcept : m_impl(std::move(impl)) {}
FramePublisher::FramePublisher(FramePublisher&& other) noexcept = default;
FramePublisher& FramePublisher::operator=(FramePublisher&& other) noexcept = default;
FramePublisher::~FramePublisher() = default;

bool FramePublisher::publish(const FrameSample& sample) noexcept {
  auto loanResult = m_impl->port.loan(SAMPLE_SIZE, SAMPLE_ALIGNMENT);
  if (loanResult.has_error()) return false;
  void* payload = loanResult.value();
  auto* chunk = new (payload) FrameSample(sample);
  stamp(*m_impl, *chunk);
  m_impl->port.publish(payload);
  return true;
}

std::optional<FrameLoan> FramePublisher::loan() noexcept {
  auto loanResult = m_impl->port.loan(SAMPLE_SIZE, SAMPLE_ALIGNMENT);
  if (loanResult.has_error()) return std::nullopt;
  auto* chunk = new (loanResult.value()) FrameSample{};
  return FrameLoan(m_impl.get(), chunk);
}

bool FramePublisher::publish(FrameLoan&& loan) noexcept {
  FrameLoan consumed(std::move(loan));
  if (consumed.m_sample == nullptr || consumed.m_owner != m_impl.get()) return false;  // ~consumed releases
  stamp(*m_impl, *consumed.m_sample);
  m_impl->port.publish(consumed.m_sample);
  consumed.m_owner = nullptr;
  consumed.m_sample = nullptr;
  return true;
}

bool FramePublisher::hasSubscribers() const noexcept {
  return m_impl->port.hasSubscribers();
}

bool FramePublisher::waitForSubscribers(std::chrono::milliseconds timeout) const noexcept {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!hasSubscribers()) {
    if (std::chrono::steady_clock::now() >= deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds{1});
  }
  return true;
}

std::uint32_t FramePublisher::senderId() const noexcept {
  return m_impl->senderId;
}
std::uint64_t FramePublisher::nextSequence() const noexcept {
  return m_impl->nextSequence;
}
const FrameTopic& FramePublisher::topic() const noexcept {
  return m_impl->topic;
}

// ---- SampleSubscriber and FrameSubscriber --------------------------------------------

Result<std::unique_ptr<FrameSubscriberImpl>> SampleSubscriber::open(const FrameTopic& topic,
                                                                    FrameSubscriberOptions options) {
  if (auto check = checkTopic(topic); !check) return check.error();
  if (options.queueCapacity == 0 || options.queueCapacity > iox::MAX_SUBSCRIBER_QUEUE_CAPACITY) {
    return Error{"frame subscriber " + topic.toString() + ": queue capacity " + std::to_string(options.queueCapacity) +
                 " outside 1.." + std::to_string(iox::MAX_SUBSCRIBER_QUEUE_CAPACITY)};
  }
  iox::popo::SubscriberOptions portOptions;
  portOptions.queueCapacity = options.queueCapacity;
  portOptions.queueFullPolicy = options.blockPublisher ? iox::popo::QueueFullPolicy::BLOCK_PRODUCER
                                                       : iox::popo::QueueFullPolicy::DISCARD_OLDEST_DATA;
  return std::make_unique<FrameSubscriberImpl>(topic, portOptions);
}

SampleSubscriber::SampleSubscriber(std::unique_ptr<FrameSubscriberImpl> impl) noexcept : m_impl(std::move(impl)) {}
SampleSubscriber::SampleSubscriber(SampleSubscriber&& other) noexcept = default;
SampleSubscriber& SampleSubscriber::operator=(SampleSubscriber&& other) noexcept = default;
SampleSubscriber::~SampleSubscriber() = default;

bool SampleSubscriber::takeInto(void* out, std::size_t size) noexcept {
  while (true) {
    auto takeResult = m_impl->port.take();
    if (takeResult.has_error()) return false;
    const void* payload = takeResult.value();
    const auto* header = iox::mepoo::ChunkHeader::fromUserPayload(payload);
    if (header == nullptr || header->userPayloadSize() != size) {
      ++m_impl->rejected;  // another layout version: never read it as this sample type
      m_impl->port.release(payload);
      continue;
    }
    std::memcpy(out, payload, size);
    m_impl->port.release(payload);
    return true;
  }
}

bool SampleSubscriber::hasData() const noexcept {
  return m_impl->port.hasData();
}
bool SampleSubscriber::hasLostFrames() noexcept {
  return m_impl->port.hasMissedData();
}
std::uint64_t SampleSubscriber::rejectedSamples() const noexcept {
  return m_impl->rejected;
}
const FrameTopic& SampleSubscriber::topic() const noexcept {
  return m_impl->topic;
}

FrameSubscriber::FrameSubscriber(std::unique_ptr<FrameSubscriberImpl> impl) noexcept
    : SampleSubscriber(std::move(impl)) {}

Result<FrameSubscriber> FrameSubscriber::create(const FrameTopic& topic, FrameSubscriberOptions options) {
  auto impl = open(topic, options);
  if (!impl) return impl.error();
  return FrameSubscriber(std::move(*impl));
}

std::optional<FrameSample> FrameSubscriber::take() noexcept {
  FrameSample sample;
  if (!takeInto(&sample, sizeof(sample))) return std::nullopt;
  return sample;
}

// ---- RequestPublisher and RequestSubscriber ------------------------------------------

Result<RequestPublisher> RequestPublisher::create(const std::string& instance, const std::string& bus) {
  const FrameTopic topic{instance, bus, FrameStream::Request};
  if (auto check = checkTopic(topic); !check) return check.error();
  iox::popo::PublisherOptions portOptions;
  portOptions.subscriberTooSlowPolicy = iox::popo::ConsumerTooSlowPolicy::DISCARD_OLDEST_DATA;
  const std::uint32_t index = g_publisherCount.fetch_add(1) + 1;
  const std::uint32_t id = fnv1a32(Runtime::name() + "#" + std::to_string(index));
  return RequestPublisher(std::make_unique<FramePublisherImpl>(topic, portOptions, id));
}

RequestPublisher::RequestPublisher(std::unique_ptr<FramePublisherImpl> impl) noexcept : m_impl(std::move(impl)) {}
RequestPublisher::RequestPublisher(RequestPublisher&& other) noexcept = default;
RequestPublisher& RequestPublisher::operator=(RequestPublisher&& other) noexcept = default;
RequestPublisher::~RequestPublisher() = default;

bool RequestPublisher::publish(const RequestSample& sample) noexcept {
  auto loanResult = m_impl->port.loan(static_cast<std::uint32_t>(sizeof(RequestSample)),
                                      static_cast<std::uint32_t>(alignof(RequestSample)));
  if (loanResult.has_error()) return false;
  void* payload = loanResult.value();
  auto* chunk = new (payload) RequestSample(sample);
  chunk->sequence = m_impl->nextSequence++;
  chunk->senderId = m_impl->senderId;
  chunk->busNameHash = m_impl->busNameHash;
  if (chunk->monotonicNs == 0) chunk->monotonicNs = clock::monotonicNs();
  m_impl->port.publish(payload);
  return true;
}

bool RequestPublisher::hasSubscribers() const noexcept {
  return m_impl->port.hasSubscribers();
}
const FrameTopic& RequestPublisher::topic() const noexcept {
  return m_impl->topic;
}

RequestSubscriber::RequestSubscriber(std::unique_ptr<FrameSubscriberImpl> impl) noexcept
    : SampleSubscriber(std::move(impl)) {}

Result<RequestSubscriber> RequestSubscriber::create(const std::string& instance, const std::string& bus,
                                                    FrameSubscriberOptions options) {
  auto impl = open(FrameTopic{instance, bus, FrameStream::Request}, options);
  if (!impl) return impl.error();
  return RequestSubscriber(std::move(*impl));
}

std::optional<RequestSample> RequestSubscriber::take() noexcept {
  RequestSample sample;
  if (!takeInto(&sample, sizeof(sample))) return std::nullopt;
  return sample;
}

}  // namespace openvcu::ipc
