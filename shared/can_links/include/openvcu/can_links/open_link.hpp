#pragma once
// Opens a link of any kind from the configuration's "socketcan:IFACE", "sim:NAME" or
// "replay:FILE" (library openvcu::can_links, namespace openvcu::can). Services call this
// and nothing else.
//
//   auto linkResult = can::openLink(can::LinkKind::Sim, "vehicle", options);
//   if (!linkResult) return linkResult.error();   // "sim:vehicle: ..."

#include <memory>
#include <string>

#include "openvcu/can/link.hpp"
#include "openvcu/core/result.hpp"

namespace openvcu::can {

/// `target`: the interface, the simulated bus name, or the log file. A sim link needs an
/// initialised ipc::Runtime. Errors name the link ("socketcan:can0: ...").
[[nodiscard]] Result<std::unique_ptr<Link>> openLink(LinkKind kind, const std::string& target,
                                                     const LinkOptions& options);

}  // namespace openvcu::can
