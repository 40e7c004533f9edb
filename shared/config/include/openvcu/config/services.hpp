#pragma once
// The services of a stack, defined once: the short name (which names the heartbeat slot
// "internal.service.<name>.heartbeat", the program "vcu-<name>" and the command socket) and
// the writer id each one stamps on its signal-table writes. Services take their writer id
// from here (writerOf), `vcu signal get` names the writer of a value (serviceOfWriter), and
// service::Service refuses to start a known service with another writer id.
//
//   config::writerOf(config::ServiceId::Fsm)  -> 3
//   config::serviceOfWriter(3)                -> "fsm"

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string_view>

#include "openvcu/signals/table.hpp"

namespace openvcu::config {

enum class ServiceId : std::uint8_t { CanRx, CanTx, Fsm, Gpio, Hmi, EcuSim, Web, Telemetry, Watchdog };

struct ServiceEntry {
  ServiceId id;
  std::string_view name;   ///< "can-rx"
  signals::WriterId writer;  ///< stamped on its command, override and bus-plane writes
  /// The name: lets `for (std::string_view name : SERVICES)` read the names.
  constexpr operator std::string_view() const noexcept { return name; }  // NOLINT(google-explicit-constructor)
};

/// Writer ids start at 1 (0 is "never written"); ids from 200 are free for tools and tests
/// (the integration fixture service uses 240).
inline constexpr std::array<ServiceEntry, 9> SERVICES = {{
    {ServiceId::CanRx, "can-rx", 1},
    {ServiceId::CanTx, "can-tx", 2},
    {ServiceId::Fsm, "fsm", 3},
    {ServiceId::Gpio, "gpio", 4},
    {ServiceId::Hmi, "hmi", 5},
    {ServiceId::EcuSim, "ecu-sim", 6},
    {ServiceId::Web, "web", 7},  ///< writes nothing but its heartbeat slot
    {ServiceId::Telemetry, "telemetry", 8},  ///< writes nothing but its heartbeat slot
    {ServiceId::Watchdog, "watchdog", 9},  ///< writes nothing but its heartbeat slot
}};

constexpr const ServiceEntry& serviceEntry(ServiceId id) noexcept { return SERVICES[static_cast<std::size_t>(id)]; }
constexpr signals::WriterId writerOf(ServiceId id) noexcept { return serviceEntry(id).writer; }

/// The service that writes with `writer`, empty for an id no service uses.
constexpr std::optional<std::string_view> serviceOfWriter(signals::WriterId writer) noexcept {
  for (const ServiceEntry& entry : SERVICES) {
    if (entry.writer == writer) return entry.name;
  }
  return std::nullopt;
}

/// The entry of the service named `name` ("fsm"), empty for another name.
constexpr const ServiceEntry* findService(std::string_view name) noexcept {
  for (const ServiceEntry& entry : SERVICES) {
    if (entry.name == name) return &entry;
  }
  return nullptr;
}

}  // namespace openvcu::config
