#pragma once
// The signal catalog of a configuration: what every process of one instance agrees on,
// so that they all compute the same shared-table layout.
//
// Order (deterministic): for each bus in file order, its messages in the bus' list
// order ("all" = DBC order), each message's decodable signals in DBC order, keyed
// "Transmitter.Message.Signal" (the BO_ transmitter as written); then the internal
// signals: the declared ones ("internal.<name>") in file order, then the built-in ones:
// the FSM's state and timers, one heartbeat per service, the health of each bus (BUS_HEALTH_FIELDS)
// and the DM1 summary of each addressed node (DM1_FIELDS).
//
// Ownership (SignalInfo::direction, owner, reported), decided here and nowhere else:
//   - a bus signal is Transmitted and owned by can-tx when this VCU's node is among its
//     message's transmitters (sentBy), else Received and owned by can-rx;
//   - a declared internal signal is owned by can-tx in the send-group namespace
//     "internal.tx." (SEND_GROUP_NAMESPACE), by vcu-gpio when an input line is bound to it,
//     else by vcu-fsm; one claimed by two services is refused, naming the key and both;
//   - the built-in statuses (reported: no command sets them) belong to their writer:
//     "internal.fsm.*" vcu-fsm, "internal.service.<name>.heartbeat" that service,
//     "internal.bus.*" and "internal.dm1.*" can-rx, "internal.gpio.<line>" vcu-gpio;
//     "internal.gpio.sim.<line>" (a simulated input's level) is vcu-gpio's and commandable.

#include "openvcu/config/services.hpp"
#include "openvcu/config/vehicle.hpp"
#include "openvcu/core/result.hpp"
#include "openvcu/signals/catalog.hpp"

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace openvcu::config {

inline constexpr std::string_view INTERNAL_PREFIX = "internal.";

// The services of a stack (each has a heartbeat counter "internal.service.<name>.heartbeat")
// and their writer ids: config::SERVICES in services.hpp.

/// Slots "internal.fsm.timer.<i>" in which vcu-fsm keeps its running `for` timers.
inline constexpr std::uint32_t FSM_TIMER_SLOTS = 32;

/// The J1939 source address of a DBC node (its NmStationAddress attribute), or empty.
std::optional<std::uint8_t> nodeAddress(const dbc::Database& database, const dbc::Node& node);

/// Per-bus health slots, written by can-rx: "internal.bus.<bus>.<BUS_HEALTH_FIELDS[i]>".
inline constexpr std::array<std::string_view, 2> BUS_HEALTH_FIELDS = {"load", "state"};
/// Per-node DM1 slots, for every DBC node with a source address except this VCU:
/// "internal.dm1.<Node>.<DM1_FIELDS[i]>" (can-rx writes them on the bus plane).
inline constexpr std::array<std::string_view, 7> DM1_FIELDS = {
    "activeDtcs", "protectLamp", "amberWarningLamp", "redStopLamp", "malfunctionLamp", "firstSpn", "firstFmi"};

/// Declared internal signals named "internal.tx.<name>" are send groups: can-tx owns them.
inline constexpr std::string_view SEND_GROUP_NAMESPACE = "internal.tx.";

/// true when `node` is among the transmitters of `message` (BO_ and BO_TX_BU_): this is
/// what makes a message the VCU's to send.
bool sentBy(const dbc::Message& message, std::string_view node);

/// Transmitted when the configuration's node sends `message`, else Received.
signals::SignalDirection directionOf(const VehicleConfig& config, const dbc::Message& message);

/// Table key of a DBC signal.
std::string signalKey(const dbc::Message& message, const dbc::Signal& signal);

/// The catalog of a loaded configuration, with each signal's direction and owner. Fails on
/// duplicate keys (e.g. an internal signal named like a built-in one), naming both, and on
/// a key two services would own, naming the key and both owners.
Result<signals::Catalog> buildCatalog(const VehicleConfig& config);

}  // namespace openvcu::config
