#include "openvcu/ipc/runtime.hpp"

#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <optional>
#include <thread>

#include "iceoryx_hoofs/log/logmanager.hpp"
#include "iceoryx_posh/iceoryx_posh_types.hpp"
#include "iceoryx_posh/runtime/posh_runtime.hpp"

namespace openvcu::ipc {

namespace {

/// Which socket file RouDi had bound when this process registered.
struct SocketIdentity {
  dev_t device{};
  ino_t inode{};
  std::int64_t changeNs{};
  bool operator==(const SocketIdentity&) const = default;
};

struct RuntimeState {
  bool initialized{false};
  std::string name;
  std::optional<SocketIdentity> roudiSocket;
};

std::optional<SocketIdentity> socketIdentity() noexcept {
  struct stat info {};
  const std::string path(ROUDI_SOCKET_PATH);
  if (::stat(path.c_str(), &info) != 0) return std::nullopt;
  return SocketIdentity{info.st_dev, info.st_ino,
                        static_cast<std::int64_t>(info.st_ctim.tv_sec) * 1'000'000'000 + info.st_ctim.tv_nsec};
}

RuntimeState& state() {
  static RuntimeState instance;
  return instance;
}

bool isValidAppName(std::string_view name) noexcept {
  if (name.empty() || name.size() > iox::MAX_RUNTIME_NAME_LENGTH) return false;
  for (const char c : name) {
    const bool ok =
        (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '.' || c == '-';
    if (!ok) return false;
  }
  return true;
}

/// connect() to RouDi's datagram socket: succeeds only while RouDi has it bound.
/// Returns 0 or the errno of the failure.
int probeRoudi() noexcept {
  const int fd = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return errno;
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  static_assert(ROUDI_SOCKET_PATH.size() < sizeof(address.sun_path));
  std::memcpy(address.sun_path, ROUDI_SOCKET_PATH.data(), ROUDI_SOCKET_PATH.size());
  // NOLINTNEXTLINE(cppcoreguidelines-pro-type-reinterpret-cast): the sockets API
  const int rc = ::connect(fd, reinterpret_cast<const sockaddr*>(&address), sizeof(address));
  const int error = rc == 0 ? 0 : errno;
  ::close(fd);
  return error;
}

std::string roudiError(int error) {
  const bool denied = error == EACCES || error == EPERM;
  std::string message = denied ? "iox-roudi is running but this user may not use it" : "iox-roudi is not running";
  message += " (";
  message += ROUDI_SOCKET_PATH;
  message += ": ";
  message += std::strerror(error);
  message += denied ? "): frame streams need root or membership of group 'openvcu' (docs/design/security.md)"
                    : "); start it first, e.g. `config/iceoryx/iox-roudi.sh`";
  return message;
}

}  // namespace

Status Runtime::init(std::string_view appName, std::chrono::milliseconds waitForRoudi) {
  RuntimeState& current = state();
  if (current.initialized) {
    if (current.name == appName) return {};
    return Error{"iceoryx runtime already initialised as '" + current.name + "', cannot re-initialise as '" +
                 std::string(appName) + "'"};
  }
  if (!isValidAppName(appName)) {
    return Error{"invalid iceoryx runtime name '" + std::string(appName) + "': use 1.." +
                 std::to_string(iox::MAX_RUNTIME_NAME_LENGTH) + " characters of [A-Za-z0-9_.-]"};
  }
  const auto deadline = std::chrono::steady_clock::now() + waitForRoudi;
  int error = probeRoudi();
  while (error != 0 && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds{5});
    error = probeRoudi();
  }
  if (error != 0) return Error{roudiError(error)};

  iox::log::LogManager::GetLogManager().SetDefaultLogLevel(iox::log::LogLevel::kWarn,
                                                           iox::log::LogLevelOutput::kHideLogLevel);
  iox::runtime::PoshRuntime::initRuntime(
      iox::RuntimeName_t(iox::cxx::TruncateToCapacity, appName.data(), appName.size()));
  current.initialized = true;
  current.name = std::string(appName);
  current.roudiSocket = socketIdentity();
  return {};
}

bool Runtime::initialized() noexcept {
  return state().initialized;
}

std::string Runtime::name() {
  return state().name;
}

bool Runtime::roudiReachable() noexcept {
  return probeRoudi() == 0;
}

bool Runtime::roudiReplaced() noexcept {
  const RuntimeState& current = state();
  if (!current.initialized || !current.roudiSocket) return false;
  const auto now = socketIdentity();
  if (!now || *now == *current.roudiSocket) return false;
  return probeRoudi() == 0;
}

bool Runtime::waitForRoudi(std::chrono::milliseconds timeout) noexcept {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!roudiReachable()) {
    if (std::chrono::steady_clock::now() >= deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds{5});
  }
  return true;
}

}  // namespace openvcu::ipc
