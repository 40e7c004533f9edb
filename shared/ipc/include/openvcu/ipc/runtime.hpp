#pragma once
// The process's connection to iox-roudi, the shared-memory broker of the frame streams.
//
//   if (auto initResult = ipc::Runtime::init("vcu-can-rx.hhea"); !initResult) {
//     std::cerr << initResult.error().toString() << '\n';   // "iox-roudi is not running ..."
//     return 1;
//   }
//
// Every FramePublisher, FrameSubscriber and Waiter needs an initialised Runtime; their
// create() functions return an error otherwise. iceoryx allows one runtime per process
// for the whole life of the process: init() once, early in main, before other threads.

#include <chrono>
#include <string>
#include <string_view>

#include "openvcu/core/result.hpp"

namespace openvcu::ipc {

/// Where iox-roudi listens (iceoryx 2.0.3 on Linux: a Unix datagram socket).
inline constexpr std::string_view ROUDI_SOCKET_PATH = "/tmp/roudi";

class Runtime {
 public:
  /// Registers this process with iox-roudi under `appName` ([A-Za-z0-9_.-], 1..100
  /// characters, unique among running processes: a second process under the same name
  /// cuts the first one off). Checks first that RouDi answers on its socket, retrying
  /// until `waitForRoudi` has passed, and returns "iox-roudi is not running" instead of
  /// blocking inside iceoryx. Sets iceoryx's log level to warning. Calling it again with
  /// the same name succeeds; with another name it fails.
  /// @note not thread-safe; call from main before starting threads. Blocks at most
  ///       `waitForRoudi` plus RouDi's registration reply (iceoryx aborts the process if
  ///       RouDi dies between the check and the reply).
  static Status init(std::string_view appName, std::chrono::milliseconds waitForRoudi = std::chrono::milliseconds{0});

  /// true once init() succeeded.
  static bool initialized() noexcept;

  /// The name given to init(); empty before.
  static std::string name();

  /// true when something accepts connections on ROUDI_SOCKET_PATH (RouDi is up and
  /// reachable by this user). Cheap: one socket() + connect(); sends nothing.
  static bool roudiReachable() noexcept;

  /// true when iox-roudi's socket is no longer the one this process registered with
  /// (another inode or change time: a new RouDi bound it) and the new RouDi answers.
  /// The process's ports belong to the dead RouDi and iceoryx 2.0 cannot move them, so the
  /// caller must end the process and let its supervisor start it again. false before
  /// init() and while no RouDi answers (the old one may be down only for a moment).
  /// Cheap: one stat() and, only when the socket changed, one connect().
  static bool roudiReplaced() noexcept;

  /// Polls roudiReachable() every few milliseconds until it is true or `timeout` passed.
  /// Tests and supervisors use it as the readiness check after starting iox-roudi.
  static bool waitForRoudi(std::chrono::milliseconds timeout) noexcept;
};

}  // namespace openvcu::ipc
