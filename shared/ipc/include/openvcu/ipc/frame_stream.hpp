#pragma once
// Publishing and subscribing to frame streams (iceoryx, zero copy) without seeing iceoryx.
//
//   auto publisherResult = ipc::FramePublisher::create({"hhea", "vehicle", ipc::FrameStream::Received});
//   if (!publisherResult) return publisherResult.error();
//   ipc::FrameSample sample{};
//   sample.frame = frameFromTheBus;
//   if (!publisherResult->publish(sample)) ++m_publishFailures;   // per-frame path: noexcept, bool
//
//   auto subscriberResult = ipc::FrameSubscriber::create({"hhea", "vehicle", ipc::FrameStream::Received});
//   while (auto maybeSample = subscriberResult->take()) handle(*maybeSample);
//
// Wait for data with ipc::Waiter (waiter.hpp). Publishers and subscribers on the same topic
// find each other through RouDi within ~100 ms of being created, in any start order;
// samples published before a subscriber is connected are not delivered to it.

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>

#include "openvcu/can/link.hpp"
#include "openvcu/core/result.hpp"
#include "openvcu/ipc/topics.hpp"

namespace openvcu::ipc {

class Waiter;
struct FramePublisherImpl;   // private (src/), holds the iceoryx port
struct FrameSubscriberImpl;  // private (src/), holds the iceoryx port

struct FramePublisherOptions {
  /// false (default): a full subscriber queue drops its oldest sample; a slow reader
  /// never slows the publisher. true: publish() blocks while a subscriber that asked for
  /// FrameSubscriberOptions::blockPublisher has a full queue (lossless; for recorders and
  /// tests, never for can-rx or can-tx on a vehicle).
  bool waitForSlowSubscribers{false};
};

class FramePublisher;

/// A sample loaned from shared memory, written in place and handed to
/// FramePublisher::publish(FrameLoan&&) (zero copy). Returned to the pool unpublished
/// when destroyed. Must not outlive its publisher.
/// @note restricted thread-safe: one thread at a time.
class FrameLoan {
 public:
  FrameLoan(FrameLoan&& other) noexcept;
  FrameLoan& operator=(FrameLoan&& other) noexcept;
  FrameLoan(const FrameLoan&) = delete;
  FrameLoan& operator=(const FrameLoan&) = delete;
  ~FrameLoan();

  [[nodiscard]] FrameSample& sample() noexcept { return *m_sample; }
  FrameSample* operator->() noexcept { return m_sample; }
  FrameSample& operator*() noexcept { return *m_sample; }

 private:
  friend class FramePublisher;
  FrameLoan(FramePublisherImpl* owner, FrameSample* sample) noexcept : m_owner(owner), m_sample(sample) {}
  void reset() noexcept;

  FramePublisherImpl* m_owner{nullptr};
  FrameSample* m_sample{nullptr};
};

/// Publishes FrameSamples on one topic. Movable (loans stay valid: the port does not
/// move); a moved-from publisher is empty and must only be destroyed or assigned to.
/// @note restricted thread-safe: one thread at a time. publish() is real-time friendly:
///       no allocation, no system call unless a subscriber waits (then one futex wake).
class FramePublisher {
 public:
  /// Offers the topic. Fails when the Runtime is not initialised or a name is invalid.
  static Result<FramePublisher> create(const FrameTopic& topic, FramePublisherOptions options = {});

  FramePublisher(FramePublisher&& other) noexcept;
  FramePublisher& operator=(FramePublisher&& other) noexcept;
  FramePublisher(const FramePublisher&) = delete;
  FramePublisher& operator=(const FramePublisher&) = delete;
  ~FramePublisher();

  /// Copies `sample` into a shared-memory chunk, stamps it (see FrameSample) and
  /// publishes it. false when no chunk could be loaned (mempool exhausted).
  bool publish(const FrameSample& sample) noexcept;

  /// Loans a zero-initialised sample to fill in place; empty when the mempool is
  /// exhausted or 8 loans are already outstanding.
  std::optional<FrameLoan> loan() noexcept;

  /// Stamps and publishes a loaned sample; the loan is consumed. false for an empty loan
  /// or one from another publisher (it is then released).
  bool publish(FrameLoan&& loan) noexcept;

  /// true when at least one subscriber is connected.
  [[nodiscard]] bool hasSubscribers() const noexcept;

  /// Polls hasSubscribers() every millisecond until true or `timeout` passed. For
  /// one-shot publishers (`vcu send`) and tests; services just publish.
  bool waitForSubscribers(std::chrono::milliseconds timeout) const noexcept;

  /// Stamped into every sample: fnv1a32 of "<runtime name>#<n>", n counting the
  /// publishers this process created. Lets a subscriber drop its own process's frames.
  [[nodiscard]] std::uint32_t senderId() const noexcept;

  /// Sequence number the next sample will carry (1 for the first).
  [[nodiscard]] std::uint64_t nextSequence() const noexcept;

  [[nodiscard]] const FrameTopic& topic() const noexcept;

 private:
  explicit FramePublisher(std::unique_ptr<FramePublisherImpl> impl) noexcept;
  std::unique_ptr<FramePublisherImpl> m_impl;
};

struct FrameSubscriberOptions {
  /// Samples held until take()n; 1..256 (iceoryx 2.0.3 limit). When full, the oldest is
  /// dropped (hasLostFrames() reports it) unless blockPublisher is set.
  std::uint32_t queueCapacity{256};
  /// true: a publisher created with waitForSlowSubscribers blocks instead of dropping
  /// when this queue is full. Other publishers still drop.
  bool blockPublisher{false};
};

/// What Waiter and service::Loop wait on: a subscriber of one topic, whatever its sample
/// type (FrameSubscriber: FrameSample; RequestSubscriber, request_stream.hpp: RequestSample).
/// Movable; a moved-from subscriber is empty.
/// @note restricted thread-safe: one thread at a time.
class SampleSubscriber : public can::WaitSource {
 public:
  SampleSubscriber(SampleSubscriber&& other) noexcept;
  SampleSubscriber& operator=(SampleSubscriber&& other) noexcept;
  SampleSubscriber(const SampleSubscriber&) = delete;
  SampleSubscriber& operator=(const SampleSubscriber&) = delete;

  /// true when at least one sample is queued.
  [[nodiscard]] bool hasData() const noexcept;

  /// true when samples were dropped because the queue was full since the last call
  /// (then resets). Sequence gaps per senderId tell which ones.
  bool hasLostFrames() noexcept;

  /// Samples dropped by take() because their size did not match the sample type (a peer
  /// built from another version of topics.hpp).
  [[nodiscard]] std::uint64_t rejectedSamples() const noexcept;

  [[nodiscard]] const FrameTopic& topic() const noexcept;

 protected:
  explicit SampleSubscriber(std::unique_ptr<FrameSubscriberImpl> impl) noexcept;
  ~SampleSubscriber() override;
  /// Copies the oldest queued sample of exactly `size` bytes into `out`; samples of
  /// another size are released and counted (rejectedSamples). false when none is queued.
  bool takeInto(void* out, std::size_t size) noexcept;
  /// Opens the port of `topic` (checked) for a subclass's create().
  static Result<std::unique_ptr<FrameSubscriberImpl>> open(const FrameTopic& topic, FrameSubscriberOptions options);

 private:
  friend class Waiter;
  std::unique_ptr<FrameSubscriberImpl> m_impl;
};

/// Receives FrameSamples of one topic from every publisher on it. Movable; a moved-from
/// subscriber is empty.
/// @note restricted thread-safe: one thread at a time. take() is real-time friendly.
class FrameSubscriber : public SampleSubscriber {
 public:
  static Result<FrameSubscriber> create(const FrameTopic& topic, FrameSubscriberOptions options = {});

  FrameSubscriber(FrameSubscriber&& other) noexcept = default;
  FrameSubscriber& operator=(FrameSubscriber&& other) noexcept = default;
  ~FrameSubscriber() = default;

  /// The oldest queued sample, or empty when none is queued ("no frame" is not an error).
  /// Samples from one publisher arrive in publish order.
  std::optional<FrameSample> take() noexcept;

 private:
  explicit FrameSubscriber(std::unique_ptr<FrameSubscriberImpl> impl) noexcept;
};

}  // namespace openvcu::ipc
