#pragma once
// Commands travel over Unix sockets, never over the network (docs/design/security.md).
//
// Each service that answers commands listens on one SOCK_SEQPACKET socket,
// <root>/<instance>/<program>.sock (root: $OPENVCU_RUN_DIR, default /run/openvcu). The folder
// is 0750 and the socket 0660, owned by the stack's user and the command group (default
// `openvcu`; 0700/0600 when the group does not exist), so the kernel lets only root, the
// stack's user and the group's members connect; the listener checks the peer's credentials
// (SO_PEERCRED and its groups) once more. One message is one LCM-encoded
// command_request_t or command_ack_t (shared/ipc/lcm), at most MAX_COMMAND_BYTES.
//
// Connections are few (64 per service, 16 per user) and short: an issuer connects, sends,
// reads its answer and closes. A connection that owes no answer and has sent nothing for
// COMMAND_IDLE_TIMEOUT is closed; when a user's (or the service's) limit is reached, the
// oldest idle connection makes room for the new one. Only when every connection waits for an
// answer is the new one refused, with the reason, which the issuer reports as the answer.
//
// An issuer (CommandClient) connects to every socket of the instance, sends the request to
// each and takes the answer of the one service that owns the command; the others answer
// `owner = false`. It trusts only a folder owned by root, by itself or by the system user
// `openvcu` (STACK_USER: the Debian package's services run as that user, created by the
// package; docs/design/packaging.md), and believes only answers from a socket served by root
// or by the owner of the folder, on its own connection, to its own random request id: a
// forged answer has no way in.
//
//   auto clientResult = ipc::CommandClient::connect("hhea");
//   if (!clientResult) return fail(clientResult.error());            // no stack, no access
//   auto answer = clientResult->send(request, std::chrono::seconds(2));
//   if (!answer) return fail(answer.error());                         // nobody decided in time
//   std::cout << (answer->accepted ? "accepted" : "refused: " + answer->reason);

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "openvcu/core/result.hpp"
#include "openvcu/ipc/events.hpp"

namespace openvcu::ipc {

/// Where command sockets live unless $OPENVCU_RUN_DIR says otherwise.
inline constexpr std::string_view DEFAULT_COMMAND_ROOT = "/run/openvcu";
inline constexpr const char* COMMAND_ROOT_ENV = "OPENVCU_RUN_DIR";
/// The largest request or answer accepted on a command socket.
inline constexpr std::size_t MAX_COMMAND_BYTES = 8192;
/// A request whose deadline lies further ahead than this is refused.
inline constexpr std::int64_t MAX_COMMAND_HORIZON_NS = 30'000'000'000;
/// A connection that owes no answer and has sent no request for this long (since it was
/// accepted, since its last request or since its last answer) is closed by the listener,
/// without a message. Issuers connect and send at once, so only stuck clients meet it.
inline constexpr std::chrono::seconds COMMAND_IDLE_TIMEOUT{5};

/// $OPENVCU_RUN_DIR, else /run/openvcu.
[[nodiscard]] std::string commandRoot();
/// "<commandRoot()>/<instance>".
[[nodiscard]] std::string commandSocketDir(std::string_view instance);

/// LCM encoding of one request/answer (the .lcm files are the contract). Decoding returns
/// nothing for a message that is not exactly one well-formed value of the type.
[[nodiscard]] std::vector<std::uint8_t> encodeCommandRequest(const CommandRequest& request);
[[nodiscard]] std::optional<CommandRequest> decodeCommandRequest(const void* data, std::size_t size);
[[nodiscard]] std::vector<std::uint8_t> encodeCommandAck(const CommandAck& ack);
[[nodiscard]] std::optional<CommandAck> decodeCommandAck(const void* data, std::size_t size);

/// Who is at the other end of a Unix socket (SO_PEERCRED).
struct PeerCredentials {
  std::int32_t pid{};
  std::uint32_t uid{};
  std::uint32_t gid{};
};

/// The system user the installed stack runs as (package openvcu). A command folder it owns
/// is trusted like one owned by root: only root can create or rename that user.
inline constexpr const char* STACK_USER = "openvcu";

/// The user `name`'s id, or nothing when no such user exists.
[[nodiscard]] std::optional<std::uint32_t> userId(const std::string& name);

/// The group `name`'s id, or nothing when no such group exists.
[[nodiscard]] std::optional<std::uint32_t> groupId(const std::string& name);

/// Root, this process's own user, or a member of `group` (primary or supplementary group,
/// read from /proc/<pid>/status) may command.
[[nodiscard]] bool mayCommand(const PeerCredentials& peer, std::optional<std::uint32_t> group);

/// One request taken from a connection.
struct ReceivedCommand {
  std::uint64_t connection{};
  PeerCredentials peer;
  CommandRequest request;
};

struct CommandListenerImpl;

/// The server side of one service's command socket.
/// @note restricted thread-safe: everything on one thread (the service's loop).
class CommandListener {
 public:
  struct Options {
    std::string instance;              ///< isValidName
    std::string program;               ///< "vcu-fsm": the socket is <program>.sock
    std::string groupName{"openvcu"};  ///< the command group
    std::size_t maxConnections{64};    ///< open connections in all
    std::size_t maxConnectionsPerUser{16};
    /// Idle connections are closed after this (COMMAND_IDLE_TIMEOUT; tests may shorten it).
    std::chrono::nanoseconds idleTimeout{COMMAND_IDLE_TIMEOUT};
  };

  /// Creates the folder (0750, or 0700 without the group) and the socket (0660/0600).
  /// Fails when the folder is owned by another user or writable by others, or when a live
  /// process already serves this socket (the same service running twice).
  static Result<CommandListener> open(Options options);

  CommandListener(CommandListener&& other) noexcept;
  CommandListener& operator=(CommandListener&& other) noexcept;
  CommandListener(const CommandListener&) = delete;
  CommandListener& operator=(const CommandListener&) = delete;
  /// Closes every connection and removes the socket (when it is still this one's).
  ~CommandListener();

  /// Readable while a connection waits to be accepted, a request to be taken or an idle
  /// connection to be closed (a timerfd inside it: the service's loop needs no timer for it).
  [[nodiscard]] int fd() const noexcept;
  [[nodiscard]] const std::string& path() const noexcept;
  /// true when the command group exists (socket 0660) rather than owner-only (0600).
  [[nodiscard]] bool groupAccess() const noexcept;

  /// Accepts waiting connections and takes at most ONE request from each connection that has
  /// one, so a flood on one connection waits its turn behind the others. A peer that may not
  /// command is refused with an answer that says why. A connection beyond the limits closes
  /// the oldest idle connection (no answer owed, no request waiting) of its user, or, when
  /// the service's limit is reached, of the user holding the most; it is refused ("too many
  /// open command connections for uid N: its 16 all wait for answers ...") only when none is
  /// idle. Connections idle for Options::idleTimeout are closed. Malformed messages are
  /// answered "refused: malformed request" here. Every request appended to `out` is owed one
  /// reply(). Appends to `out`; never blocks.
  void poll(std::vector<ReceivedCommand>& out);
  /// Sends `ack` on `connection` (one answer owed by a request from poll()); the connection
  /// counts as idle again from now. false when the connection is gone or full.
  bool reply(std::uint64_t connection, const CommandAck& ack) noexcept;

  [[nodiscard]] std::uint64_t refusedPeers() const noexcept;
  [[nodiscard]] std::uint64_t malformed() const noexcept;
  /// Connections closed because they were idle (timed out, or made room for a new one).
  [[nodiscard]] std::uint64_t closedIdle() const noexcept;
  [[nodiscard]] std::size_t connections() const noexcept;

 private:
  explicit CommandListener(std::unique_ptr<CommandListenerImpl> impl) noexcept;
  std::unique_ptr<CommandListenerImpl> m_impl;
};

struct CommandClientImpl;

/// The issuer side: `vcu`, the HMI, the web and telemetry services.
/// @note not thread-safe; one send at a time. Blocks up to the timeout given to send().
class CommandClient {
 public:
  /// Connects to every command socket of `instance`. Fails with a clear reason when the
  /// folder is missing (no stack running), not accessible (not root, not in the group) or
  /// untrustworthy (writable by others), or when no socket answers.
  static Result<CommandClient> connect(std::string_view instance);

  CommandClient(CommandClient&& other) noexcept;
  CommandClient& operator=(CommandClient&& other) noexcept;
  CommandClient(const CommandClient&) = delete;
  CommandClient& operator=(const CommandClient&) = delete;
  ~CommandClient();

  /// Sends `request` to every service and waits for the owner's answer. A zero requestId
  /// becomes a fresh random one; a zero deadlineNs becomes now + `timeout` (an issuer that
  /// tracks its own timeouts, like the HMI, sets both). An error when no service owns it or
  /// none answered by the deadline: then nothing was or will be applied.
  /// A service that refused the connection (its limits, the peer check) sent its reason: when
  /// no owner answered and every other service did, that refusal is the answer (accepted =
  /// false, the request's id and issuer, responder = that service); at the deadline it is part
  /// of the error. A connection the service closed as idle is opened again once, before
  /// sending (the request had not reached it).
  Result<CommandAck> send(CommandRequest request, std::chrono::nanoseconds timeout);

  /// The services connected ("vcu-fsm", ...).
  [[nodiscard]] std::vector<std::string> services() const;

 private:
  explicit CommandClient(std::unique_ptr<CommandClientImpl> impl) noexcept;
  std::unique_ptr<CommandClientImpl> m_impl;
};

}  // namespace openvcu::ipc
