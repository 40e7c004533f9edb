#pragma once
// The fault event names that services raise about another service, defined once: the
// producers build them here and the displays and tools that match on them parse them here.
//
//   service_silent.<service>  a service stopped beating: vcu-watchdog raises it, and the
//                             displays (HMI, vcu-web, `vcu top`) list it from the heartbeats
//                             they see while no event of that name is listed
//   writer_lost.<writer>      a watched writer's heartbeat went missing: vcu-can-tx and
//                             vcu-gpio raise it and command their safe values
//
// <service> and <writer> are the short names of config::SERVICES ("fsm", not "vcu-fsm").
//
//   faults::serviceSilent("fsm")                   -> "service_silent.fsm"
//   faults::writerLost("fsm")                      -> "writer_lost.fsm"
//   faults::parseServiceFault("writer_lost.fsm")   -> {WriterLost, "fsm", &SERVICES[Fsm]}
//   faults::parseServiceFault("service_silent.x")  -> {ServiceSilent, "x", nullptr}
//   faults::parseServiceFault("hv_lost")           -> empty

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "openvcu/config/services.hpp"

namespace openvcu::faults {

/// The prefix of a silent service's fault: "service_silent." + the service's short name.
inline constexpr std::string_view SERVICE_SILENT_PREFIX = "service_silent.";
/// The prefix of a lost writer's fault: "writer_lost." + the writer's short name.
inline constexpr std::string_view WRITER_LOST_PREFIX = "writer_lost.";

enum class ServiceFaultKind : std::uint8_t { ServiceSilent, WriterLost };

/// A parsed service fault name. `service` views the parsed name: it lives as long as that.
struct ServiceFault {
  ServiceFaultKind kind{};
  std::string_view service;                    ///< "fsm"
  const config::ServiceEntry* entry{nullptr};  ///< its config::SERVICES entry; nullptr for another name
};

/// "fsm" -> "service_silent.fsm". Any name is accepted (a display also names a program it
/// heard beat that config::SERVICES does not list); parseServiceFault tells them apart.
/// @note allocates: build it once per change of state, not per frame.
[[nodiscard]] std::string serviceSilent(std::string_view service);

/// "fsm" -> "writer_lost.fsm".
/// @note allocates: build it once per change of state, not per frame.
[[nodiscard]] std::string writerLost(std::string_view writer);

/// The kind and service of a service fault name; empty for any other name and for a prefix
/// with no service after it ("writer_lost.").
/// @note noexcept, allocation-free; thread-safe.
[[nodiscard]] std::optional<ServiceFault> parseServiceFault(std::string_view name) noexcept;

/// Whether `name` is a service fault name whose service is in config::SERVICES.
[[nodiscard]] bool namesKnownService(std::string_view name) noexcept;

}  // namespace openvcu::faults
