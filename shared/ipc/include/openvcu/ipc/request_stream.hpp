#pragma once
// The "req" topic of a bus: J1939 Requests for this node, parsed by can-rx, answered by
// can-tx (topics.hpp, RequestSample). Same transport and rules as frame_stream.hpp.
//
//   auto publisherResult = ipc::RequestPublisher::create("hhea", "vehicle");      // can-rx
//   ipc::RequestSample sample{};
//   sample.bus = 0; sample.pgn = 65254; sample.requester = 0xF3; sample.global = false;
//   if (!publisherResult->publish(sample)) ++publishFailures;
//
//   auto subscriberResult = ipc::RequestSubscriber::create("hhea", "vehicle");    // can-tx
//   loop.addSubscriber(*subscriberResult, [&] { while (auto maybeSample = subscriberResult->take()) answer(*maybeSample); });

#include <memory>
#include <optional>
#include <string>

#include "openvcu/core/result.hpp"
#include "openvcu/ipc/frame_stream.hpp"
#include "openvcu/ipc/topics.hpp"

namespace openvcu::ipc {

/// Publishes RequestSamples on ("openvcu", "<instance>.<bus>", "req"). Movable; a
/// moved-from publisher is empty and must only be destroyed or assigned to.
/// @note restricted thread-safe: one thread at a time. publish() allocates nothing.
class RequestPublisher {
 public:
  /// Offers the topic. Fails when the Runtime is not initialised or a name is invalid.
  static Result<RequestPublisher> create(const std::string& instance, const std::string& bus);

  RequestPublisher(RequestPublisher&& other) noexcept;
  RequestPublisher& operator=(RequestPublisher&& other) noexcept;
  RequestPublisher(const RequestPublisher&) = delete;
  RequestPublisher& operator=(const RequestPublisher&) = delete;
  ~RequestPublisher();

  /// Copies `sample` into shared memory, stamps it and publishes it. false when no chunk
  /// could be loaned (mempool exhausted).
  bool publish(const RequestSample& sample) noexcept;
  /// true when at least one subscriber is connected.
  [[nodiscard]] bool hasSubscribers() const noexcept;
  [[nodiscard]] const FrameTopic& topic() const noexcept;

 private:
  explicit RequestPublisher(std::unique_ptr<FramePublisherImpl> impl) noexcept;
  std::unique_ptr<FramePublisherImpl> m_impl;
};

/// Receives the RequestSamples of one bus's "req" topic. Wait on it like a FrameSubscriber
/// (Waiter::attach, service::Loop::addSubscriber).
/// @note restricted thread-safe: one thread at a time. take() is real-time friendly.
class RequestSubscriber : public SampleSubscriber {
 public:
  static Result<RequestSubscriber> create(const std::string& instance, const std::string& bus,
                                          FrameSubscriberOptions options = {});

  RequestSubscriber(RequestSubscriber&& other) noexcept = default;
  RequestSubscriber& operator=(RequestSubscriber&& other) noexcept = default;
  ~RequestSubscriber() = default;

  /// The oldest queued request, or empty when none is queued.
  std::optional<RequestSample> take() noexcept;

 private:
  explicit RequestSubscriber(std::unique_ptr<FrameSubscriberImpl> impl) noexcept;
};

}  // namespace openvcu::ipc
