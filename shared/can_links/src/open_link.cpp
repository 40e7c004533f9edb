#include "openvcu/can_links/open_link.hpp"

#include "openvcu/can/replay_link.hpp"
#include "openvcu/can_links/sim_link.hpp"
#include "openvcu/can/socketcan_link.hpp"

namespace openvcu::can {

Result<std::unique_ptr<Link>> openLink(LinkKind kind, const std::string& target, const LinkOptions& options) {
  switch (kind) {
    case LinkKind::SocketCan:
      return openSocketCanLink(target, options);
    case LinkKind::Sim:
      return openSimLink(target, options);
    case LinkKind::Replay:
      return openReplayLink(target, options);
  }
  return Error{"unknown link kind"};
}

}  // namespace openvcu::can
