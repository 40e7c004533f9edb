#include "openvcu/service/bus_ports.hpp"

#include "openvcu/can_links/open_link.hpp"

namespace openvcu::service {
namespace {

template <typename Port, typename Create>
Status openPort(std::optional<Port>& slot, const config::BusConfig& bus, Create create) {
  auto portResult = create();
  if (!portResult) return Error{"bus '" + bus.name + "': " + portResult.error().message};
  slot.emplace(std::move(*portResult));
  return {};
}

}  // namespace

Result<BusPorts> openBusPorts(const std::string& instance, const config::BusConfig& bus,
                              const can::LinkOptions& options, BusRole role) {
  BusPorts ports;
  auto linkResult = can::openLink(bus.link.kind, bus.link.target, options);
  if (!linkResult) return Error{"bus '" + bus.name + "': " + linkResult.error().message};
  ports.link = std::move(*linkResult);
  auto publisher = [&](ipc::FrameStream stream) {
    return [&, stream] { return ipc::FramePublisher::create({instance, bus.name, stream}); };
  };
  if (role == BusRole::Receiver) {
    if (Status opened = openPort(ports.received, bus, publisher(ipc::FrameStream::Received)); !opened) return opened.error();
    if (Status opened = openPort(ports.sent, bus, publisher(ipc::FrameStream::Sent)); !opened) return opened.error();
    if (Status opened = openPort(ports.requestsOut, bus, [&] { return ipc::RequestPublisher::create(instance, bus.name); });
        !opened)
      return opened.error();
    if (Status opened = openPort(ports.sendRequestsOut, bus, publisher(ipc::FrameStream::SendRequest)); !opened)
      return opened.error();
    if (Status opened = openPort(ports.networkOut, bus, publisher(ipc::FrameStream::Network)); !opened)
      return opened.error();
    return ports;
  }
  if (Status opened = openPort(ports.sent, bus, publisher(ipc::FrameStream::Sent)); !opened) return opened.error();
  if (Status opened = openPort(ports.sendRequestsIn, bus, [&] {
        return ipc::FrameSubscriber::create({instance, bus.name, ipc::FrameStream::SendRequest});
      });
      !opened)
    return opened.error();
  if (Status opened =
          openPort(ports.requestsIn, bus, [&] { return ipc::RequestSubscriber::create(instance, bus.name); });
      !opened)
    return opened.error();
  if (Status opened = openPort(ports.networkIn, bus, [&] {
        return ipc::FrameSubscriber::create({instance, bus.name, ipc::FrameStream::Network});
      });
      !opened)
    return opened.error();
  return ports;
}

}  // namespace openvcu::service
