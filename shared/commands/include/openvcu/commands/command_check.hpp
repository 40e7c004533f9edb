#pragma once
// A command as JSON text (vcu-web's POST /api/command body, vcu-telemetry's remote command),
// checked here before anything is sent, then turned into the ipc::CommandRequest the HMI and
// `vcu` send too (docs/design/web.md, docs/design/telemetry.md). The owning service still
// decides (the FSM stays the authority); what is checked here is only what makes a request
// meaningless: the kind, the key, the value.
//
//   parseCommand(R"({"kind":"operator","key":"internal.operator.StartStop","value":"Start"})", catalog, database)
//   -> CommandRequest{kind = OperatorSwitch, key = "internal.operator.StartStop", value = 1}
//   parseCommand(R"({"kind":"set","key":"X"})", ...) -> Error "/key: unknown signal 'X'"

#include <string>
#include <string_view>

#include "openvcu/core/result.hpp"
#include "openvcu/dbc/model.hpp"
#include "openvcu/ipc/events.hpp"
#include "openvcu/signals/catalog.hpp"

namespace openvcu::commands {

/// The operator switches' keys (the HMI's Vehicle tab) and the FSM's reset switch among them.
inline constexpr std::string_view OPERATOR_PREFIX = "internal.operator.";
inline constexpr std::string_view FAULT_RESET_KEY = "internal.operator.FaultReset";

/// The kinds a sender may use: "operator", "set", "clear", "faultReset" (SetSignal internal.operator.FaultReset = 1,
/// as the HMI resets), "scheduleEnable", "scheduleCycle".
/// An error is "<JSON path>: <reason>"; the request's id, deadline and issuer are left to the sender.
/// @note thread-safe (reads the catalog and database only); allocates.
Result<ipc::CommandRequest> parseCommand(std::string_view body, const signals::Catalog& catalog,
                                         const dbc::Database& database);

/// One line for the command log: "operator internal.operator.StartStop = 1".
[[nodiscard]] std::string describeCommand(const ipc::CommandRequest& request);

}  // namespace openvcu::commands
