#pragma once
// Private: the iceoryx objects behind FramePublisher and FrameSubscriber, shared by
// frame_stream.cpp and waiter.cpp. Never included by a public header.

#include <atomic>
#include <cstdint>

#include "iceoryx_posh/popo/untyped_publisher.hpp"
#include "iceoryx_posh/popo/untyped_subscriber.hpp"
#include "openvcu/ipc/frame_stream.hpp"

namespace openvcu::ipc {

/// ("openvcu", "<instance>.<bus>", "rx"|"tx"|"send")
iox::capro::ServiceDescription serviceDescription(const FrameTopic& topic);

struct FramePublisherImpl {
  FramePublisherImpl(const FrameTopic& frameTopic, const iox::popo::PublisherOptions& options, std::uint32_t id);

  FrameTopic topic;
  iox::popo::UntypedPublisher port;
  std::uint64_t nextSequence{1};
  std::uint32_t senderId{};
  std::uint32_t busNameHash{};
};

struct FrameSubscriberImpl {
  FrameSubscriberImpl(const FrameTopic& frameTopic, const iox::popo::SubscriberOptions& options);

  FrameTopic topic;
  iox::popo::UntypedSubscriber port;
  std::uint64_t rejected{0};
};

}  // namespace openvcu::ipc
