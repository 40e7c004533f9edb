#pragma once
// vcu-telemetry's remote commands (docs/design/telemetry.md, "Remote commands"): a message on
// openvcu/<id>/cmd/<cmdId> checked on the vehicle, then sent through the same checked command
// path as the HMI and vcu-web (commands::parseCommand, commands::sendCommand); the owner's
// CommandAck, or the reason it was refused here, becomes the answer record
// "cmd/<cmdId>/answer\n{...}" for the disk queue. The broker's ACL has already decided who may
// publish to the topic (MQTT does not tell a subscriber who published).
//
// Checks, in order, each refusal answered and logged:
//   - a retained message is refused (it would run again at every reconnect);
//   - a payload that is not a JSON object (read by config::parseJson, the configuration
//     files' reader: a key given twice at any level is refused with its JSON path) with an
//     integer deadlineUnixMs, a deadline in the past or more than 10 s ahead;
//   - a cmdId received before within its deadline, also before a restart (ReplayGuard: the
//     cmdIds with their deadlines in the queue folder, synced before anything is sent), is
//     refused "replayed" and never sent again;
//   - the key (kind faultReset: internal.operator.FaultReset; schedule kinds: the message name)
//     not in telemetry.json's remoteCommands keys;
//   - commands::parseCommand's refusal (kind, key, value);
//   then the request goes out on a worker thread with issuer "vcu-telemetry/mqtt" and a deadline
//   at most 2 s ahead (and never after deadlineUnixMs); the owner decides.
//
//   openvcu/hhea-01/cmd/c-17
//   {"kind":"operator","key":"internal.operator.StartStop","value":"Start","deadlineUnixMs":1764259205000}
//   -> cmd/c-17/answer\n{"v":1,"seq":1238,"t":...,"cmdId":"c-17","accepted":true,"reason":"","responder":"vcu-fsm"}

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "engine.hpp"
#include "openvcu/commands/command_sender.hpp"
#include "openvcu/commands/worker.hpp"
#include "openvcu/core/result.hpp"
#include "openvcu/dbc/model.hpp"
#include "openvcu/ipc/events.hpp"
#include "openvcu/signals/catalog.hpp"
#include "replay_guard.hpp"
#include "sender.hpp"

namespace openvcu::telemetry {

/// The request's own deadline is at most this far ahead (and never after deadlineUnixMs).
inline constexpr std::int64_t MAX_REQUEST_WAIT_MS = 2'000;
/// Commands waiting for the worker beyond the one it sends; more are refused "busy".
inline constexpr std::size_t MAX_WAITING_COMMANDS = 8;
/// A larger payload is refused unread.
inline constexpr std::size_t MAX_COMMAND_PAYLOAD = 4096;
/// The issuer of every remote command (the owner's log and the event bus show it).
inline constexpr std::string_view REMOTE_ISSUER = "vcu-telemetry/mqtt";
/// The responder named in an answer refused before any owner saw the command.
inline constexpr std::string_view LOCAL_RESPONDER = "vcu-telemetry";

/// Sends one request and waits for its outcome (default: commands::sendCommand to the
/// instance); called on the handler's worker thread only.
using CommandSend = std::function<commands::CommandOutcome(const ipc::CommandRequest&, std::chrono::nanoseconds)>;

struct RemoteCommandsOptions {
  std::string vehicleId;          ///< the topics are openvcu/<vehicleId>/cmd/<cmdId>
  std::vector<std::string> keys;  ///< telemetry.json's remoteCommands keys
  std::string stateFolder;        ///< where the received cmdIds are remembered (the queue folder)
  const signals::Catalog* catalog{nullptr};
  const dbc::Database* database{nullptr};
  CommandSend send;
  std::function<void(const std::string&)> logInfo;     ///< called on the owner's thread
  std::function<void(const std::string&)> logWarning;  ///< called on the owner's thread
};

/// @note restricted thread-safe: create, onMessage, takeRecords and the destructor on one
///       thread (vcu-telemetry's loop); requests go out on a worker thread of its own, which
///       only hands the outcome back. The destructor waits for a request being sent.
class RemoteCommands {
 public:
  /// Error: a key that is neither a signal of this vehicle nor a DBC message, no catalog,
  /// database, send function or state folder, or a memory of received cmdIds that cannot be
  /// read or written (ReplayGuard::open); its damage is a warning in `warnings`.
  static Result<std::unique_ptr<RemoteCommands>> create(RemoteCommandsOptions options,
                                                        std::vector<Error>* warnings = nullptr);
  ~RemoteCommands();
  RemoteCommands(const RemoteCommands&) = delete;
  RemoteCommands& operator=(const RemoteCommands&) = delete;

  /// Checks one message from the broker (topic openvcu/<id>/cmd/<cmdId>); a refusal is
  /// answered at once, a command that passes goes to the worker. Never waits for an owner; a
  /// command that passes the deadline checks costs one write and fdatasync of the memory.
  void onMessage(const InboundMessage& message, const ClockPair& now);

  /// The answers ready since the last call as queue records "cmd/<cmdId>/answer\n{...}",
  /// numbered from `firstSequence`, stamped `now`; each is logged here.
  std::vector<std::string> takeRecords(std::uint64_t firstSequence, const ClockPair& now);

  /// Commands handed to the worker whose outcome has not been taken yet.
  [[nodiscard]] std::size_t inFlight() const noexcept { return m_inFlight; }

 private:
  struct Answer {
    std::string cmdId;
    bool accepted{false};
    std::string reason;
    std::string responder;
    std::string what;  ///< for the log: the command described, or empty
  };
  struct Finished {
    std::string cmdId;
    std::string what;
    commands::CommandOutcome outcome;
  };
  RemoteCommands(RemoteCommandsOptions options, ReplayGuard guard);
  void refuse(const std::string& cmdId, std::string reason);
  /// The refusal reason of a command (its JSON without deadlineUnixMs, naming `key`), or
  /// nothing with `request` filled in.
  std::optional<std::string> check(const std::string& key, const std::string& commandJson, std::int64_t deadlineUnixMs,
                                   const ClockPair& now, ipc::CommandRequest& request) const;

  RemoteCommandsOptions m_options;
  std::string m_topicPrefix;  ///< "openvcu/<id>/cmd/"
  // the owner's thread only
  std::vector<Answer> m_ready;
  ReplayGuard m_guard;  ///< the cmdIds received within their deadlines, on disk
  std::size_t m_inFlight{0};
  // written by the worker
  std::mutex m_mutex;
  std::vector<Finished> m_finished;
  // last: destroyed first, so a running request finishes before the members it uses go
  std::unique_ptr<commands::Worker> m_worker;
};

}  // namespace openvcu::telemetry
