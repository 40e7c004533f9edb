#include "openvcu/ipc/command_socket.hpp"

#include <dirent.h>
#include <fcntl.h>
#include <grp.h>
#include <poll.h>
#include <pwd.h>
#include <sys/epoll.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/timerfd.h>
#include <sys/un.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>

#include "openvcu/core/clock.hpp"
#include "openvcu/ipc/topics.hpp"

namespace openvcu::ipc {

namespace {

std::string errnoText(int error) {
  return std::strerror(error);
}

/// Owns one file descriptor.
class Fd {
 public:
  Fd() = default;
  explicit Fd(int fd) noexcept : m_fd(fd) {}
  Fd(Fd&& other) noexcept : m_fd(std::exchange(other.m_fd, -1)) {}
  Fd& operator=(Fd&& other) noexcept {
    if (this != &other) {
      reset();
      m_fd = std::exchange(other.m_fd, -1);
    }
    return *this;
  }
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  ~Fd() { reset(); }
  void reset() noexcept {
    if (m_fd >= 0) ::close(m_fd);
    m_fd = -1;
  }
  [[nodiscard]] int get() const noexcept { return m_fd; }
  [[nodiscard]] bool valid() const noexcept { return m_fd >= 0; }

 private:
  int m_fd{-1};
};

std::optional<PeerCredentials> peerOf(int fd) {
  ucred credentials{};
  socklen_t length = sizeof credentials;
  if (::getsockopt(fd, SOL_SOCKET, SO_PEERCRED, &credentials, &length) != 0) return std::nullopt;
  return PeerCredentials{credentials.pid, credentials.uid, credentials.gid};
}

bool fillAddress(const std::string& path, sockaddr_un& address) {
  address = {};
  address.sun_family = AF_UNIX;
  if (path.size() >= sizeof address.sun_path) return false;
  std::memcpy(address.sun_path, path.c_str(), path.size() + 1);
  return true;
}

bool sendMessage(int fd, const std::vector<std::uint8_t>& bytes) noexcept {
  if (bytes.empty()) return false;
  const ssize_t sent = ::send(fd, bytes.data(), bytes.size(), MSG_DONTWAIT | MSG_NOSIGNAL);
  return sent == static_cast<ssize_t>(bytes.size());
}

/// What waits on a connection, seen without taking it.
enum class Queued : std::uint8_t { Nothing, Message, Closed };

Queued peekAt(int fd) noexcept {
  char byte = 0;
  const ssize_t size = ::recv(fd, &byte, 1, MSG_PEEK | MSG_DONTWAIT);
  if (size > 0) return Queued::Message;
  if (size == 0 || (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)) return Queued::Closed;
  return Queued::Nothing;
}

/// "uid 65534 (pid 812)".
std::string describePeer(const PeerCredentials& peer) {
  return "uid " + std::to_string(peer.uid) + " (pid " + std::to_string(peer.pid) + ")";
}

std::string groupText(const std::optional<std::uint32_t>& group, const std::string& name) {
  return group ? "group '" + name + "'" : "group '" + name + "' (which does not exist on this host)";
}

}  // namespace

std::string commandRoot() {
  const char* fromEnvironment = std::getenv(COMMAND_ROOT_ENV);
  if (fromEnvironment != nullptr && fromEnvironment[0] == '/') return fromEnvironment;
  return std::string(DEFAULT_COMMAND_ROOT);
}

std::string commandSocketDir(std::string_view instance) {
  return commandRoot() + "/" + std::string(instance);
}

std::optional<std::uint32_t> groupId(const std::string& name) {
  group entry{};
  group* found = nullptr;
  std::array<char, 16384> buffer{};
  if (::getgrnam_r(name.c_str(), &entry, buffer.data(), buffer.size(), &found) != 0 || found == nullptr) {
    return std::nullopt;
  }
  return found->gr_gid;
}

std::optional<std::uint32_t> userId(const std::string& name) {
  passwd entry{};
  passwd* found = nullptr;
  std::array<char, 16384> buffer{};
  if (::getpwnam_r(name.c_str(), &entry, buffer.data(), buffer.size(), &found) != 0 || found == nullptr) {
    return std::nullopt;
  }
  return found->pw_uid;
}

bool mayCommand(const PeerCredentials& peer, std::optional<std::uint32_t> group) {
  if (peer.uid == 0 || peer.uid == ::geteuid()) return true;
  if (!group) return false;
  if (peer.gid == *group) return true;
  // Supplementary groups are not in SO_PEERCRED: the kernel's list of the peer process.
  std::ifstream status("/proc/" + std::to_string(peer.pid) + "/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("Groups:", 0) != 0) continue;
    std::istringstream groups(line.substr(7));
    std::uint32_t gid = 0;
    while (groups >> gid) {
      if (gid == *group) return true;
    }
    return false;
  }
  return false;
}

// ---- listener ----------------------------------------------------------------------------

struct CommandListenerImpl {
  struct Connection {
    Fd fd;
    PeerCredentials peer;
    std::int64_t activeNs{};  ///< accepted, last request taken or last answer sent (CLOCK_MONOTONIC)
    std::uint32_t owed{};     ///< requests taken and not answered yet
  };
  /// The epoll data of the idle timer (connections are 1, 2, ...; the listening socket 0).
  static constexpr std::uint64_t IDLE_TIMER = std::numeric_limits<std::uint64_t>::max();

  CommandListener::Options options;
  std::string directory;
  std::string path;
  std::optional<std::uint32_t> group;
  Fd epoll;
  Fd listening;
  Fd idleTimer;            ///< timerfd (CLOCK_MONOTONIC, absolute) in `epoll`
  std::int64_t armedNs{};  ///< when idleTimer fires; 0: disarmed
  ino_t inode{};
  std::map<std::uint64_t, Connection> connections;  // by id; the epoll data is the id
  std::uint64_t nextId{1};
  std::uint64_t refusedPeers{0};
  std::uint64_t malformed{0};
  std::uint64_t closedIdle{0};
  std::vector<std::uint8_t> buffer = std::vector<std::uint8_t>(MAX_COMMAND_BYTES + 1);

  ~CommandListenerImpl() {
    // Remove the socket only when it is still ours (a newer instance may have replaced it).
    struct stat info {};
    if (!path.empty() && ::lstat(path.c_str(), &info) == 0 && info.st_ino == inode) ::unlink(path.c_str());
  }

  /// Refuses a connection with one answer saying why, then closes it.
  void refuse(Fd fd, const std::string& reason) {
    CommandAck ack;
    ack.responder = options.program;
    ack.accepted = false;
    ack.reason = reason;
    (void)sendMessage(fd.get(), encodeCommandAck(ack));
    ++refusedPeers;
  }

  [[nodiscard]] std::int64_t idleNs() const noexcept { return options.idleTimeout.count(); }

  [[nodiscard]] std::size_t connectionsOf(std::uint32_t uid) const noexcept {
    return static_cast<std::size_t>(std::count_if(connections.begin(), connections.end(),
                                                  [uid](const auto& entry) { return entry.second.peer.uid == uid; }));
  }

  /// No answer owed and no request waiting: it may be closed. A connection whose peer has gone
  /// counts as idle; one with a request waiting counts as active from now.
  bool idle(Connection& connection, std::int64_t nowNs) noexcept {
    if (connection.owed > 0) return false;
    if (peekAt(connection.fd.get()) != Queued::Message) return true;
    connection.activeNs = nowNs;
    return false;
  }

  /// The oldest idle connection of `uid`, or with no uid given, of the user holding the most
  /// connections; nothing when every candidate waits for an answer.
  std::optional<std::uint64_t> oldestIdle(std::optional<std::uint32_t> uid, std::int64_t nowNs) {
    std::optional<std::uint64_t> chosen;
    std::size_t chosenHolds = 0;
    std::int64_t chosenSince = 0;
    for (auto& [id, connection] : connections) {
      if (uid && connection.peer.uid != *uid) continue;
      if (!idle(connection, nowNs)) continue;
      const std::size_t holds = uid ? 0 : connectionsOf(connection.peer.uid);
      if (chosen && (holds < chosenHolds || (holds == chosenHolds && connection.activeNs >= chosenSince))) continue;
      chosen = id;
      chosenHolds = holds;
      chosenSince = connection.activeNs;
    }
    return chosen;
  }

  /// Makes room for a connection of `uid`; a refusal reason when every connection in the way
  /// waits for an answer.
  std::optional<std::string> makeRoom(std::uint32_t uid, std::int64_t nowNs) {
    const std::size_t fromUser = connectionsOf(uid);
    if (fromUser >= options.maxConnectionsPerUser) {
      const auto victim = oldestIdle(uid, nowNs);
      if (!victim) {
        return "too many open command connections for uid " + std::to_string(uid) + ": its " +
               std::to_string(fromUser) + " all wait for answers (" + std::to_string(connections.size()) +
               " in all); try again";
      }
      drop(*victim);
      ++closedIdle;
    }
    if (connections.size() >= options.maxConnections) {
      const auto victim = oldestIdle(std::nullopt, nowNs);
      if (!victim) {
        return "too many open command connections: all " + std::to_string(connections.size()) + " wait for answers (" +
               std::to_string(connectionsOf(uid)) + " from uid " + std::to_string(uid) + "); try again";
      }
      drop(*victim);
      ++closedIdle;
    }
    return std::nullopt;
  }

  /// Closes the connections idle for idleTimeout.
  void closeIdle(std::int64_t nowNs) {
    for (auto entry = connections.begin(); entry != connections.end();) {
      Connection& connection = entry->second;
      if (nowNs - connection.activeNs < idleNs() || !idle(connection, nowNs)) {
        ++entry;
        continue;
      }
      ::epoll_ctl(epoll.get(), EPOLL_CTL_DEL, connection.fd.get(), nullptr);
      entry = connections.erase(entry);
      ++closedIdle;
    }
  }

  /// Arms the idle timer for the earliest connection that may go idle, unless it is armed
  /// earlier already (an early wake-up finds nothing to close and arms again).
  void armIdleTimer() noexcept {
    std::int64_t earliest = std::numeric_limits<std::int64_t>::max();
    for (const auto& [id, connection] : connections) {
      if (connection.owed == 0) earliest = std::min(earliest, connection.activeNs + idleNs());
    }
    if (earliest == std::numeric_limits<std::int64_t>::max() || (armedNs != 0 && armedNs <= earliest)) return;
    itimerspec due{};
    due.it_value.tv_sec = static_cast<time_t>(earliest / 1'000'000'000);
    due.it_value.tv_nsec = static_cast<long>(earliest % 1'000'000'000);
    if (::timerfd_settime(idleTimer.get(), TFD_TIMER_ABSTIME, &due, nullptr) == 0) armedNs = earliest;
  }

  void onIdleTimer() {
    std::uint64_t expirations = 0;
    [[maybe_unused]] const auto got = ::read(idleTimer.get(), &expirations, sizeof expirations);
    armedNs = 0;  // a one-shot timer that fired is disarmed
    closeIdle(clock::monotonicNs());
  }

  void acceptAll() {
    for (int accepted = 0; accepted < 64; ++accepted) {
      Fd fd(::accept4(listening.get(), nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC));
      if (!fd.valid()) return;  // EAGAIN: none left (other errors: try again on the next wake-up)
      const auto peer = peerOf(fd.get());
      if (!peer) {
        refuse(std::move(fd), "cannot read the credentials of the connecting process");
        continue;
      }
      if (!mayCommand(*peer, group)) {
        refuse(std::move(fd), describePeer(*peer) + " may not command this stack: only root and members of " +
                                  groupText(group, options.groupName) + " may");
        continue;
      }
      const std::int64_t nowNs = clock::monotonicNs();
      if (auto refusal = makeRoom(peer->uid, nowNs)) {
        refuse(std::move(fd), *refusal);
        continue;
      }
      const std::uint64_t id = nextId++;
      epoll_event event{};
      event.events = EPOLLIN;
      event.data.u64 = id;
      if (::epoll_ctl(epoll.get(), EPOLL_CTL_ADD, fd.get(), &event) != 0) continue;
      connections.emplace(id, Connection{std::move(fd), *peer, nowNs, 0});
    }
  }

  void drop(std::uint64_t id) {
    const auto found = connections.find(id);
    if (found == connections.end()) return;
    ::epoll_ctl(epoll.get(), EPOLL_CTL_DEL, found->second.fd.get(), nullptr);
    connections.erase(found);
  }

  /// Takes one message of connection `id`, if it has one.
  void takeOne(std::uint64_t id, std::uint32_t events, std::vector<ReceivedCommand>& out) {
    const auto found = connections.find(id);
    if (found == connections.end()) return;
    Connection& connection = found->second;
    const ssize_t size = ::recv(connection.fd.get(), buffer.data(), buffer.size(), MSG_DONTWAIT | MSG_TRUNC);
    if (size == 0 || (size < 0 && errno != EAGAIN && errno != EINTR)) {
      drop(id);
      return;
    }
    if (size < 0) {
      if ((events & (EPOLLHUP | EPOLLERR)) != 0) drop(id);
      return;
    }
    connection.activeNs = clock::monotonicNs();
    std::optional<CommandRequest> request;
    if (static_cast<std::size_t>(size) <= MAX_COMMAND_BYTES) {
      request = decodeCommandRequest(buffer.data(), static_cast<std::size_t>(size));
    }
    if (!request) {
      ++malformed;
      CommandAck ack;
      ack.responder = options.program;
      ack.reason =
          static_cast<std::size_t>(size) > MAX_COMMAND_BYTES
              ? "malformed request: " + std::to_string(size) + " bytes, more than " + std::to_string(MAX_COMMAND_BYTES)
              : "malformed request: not one command_request_t";
      (void)sendMessage(connection.fd.get(), encodeCommandAck(ack));
      return;
    }
    ++connection.owed;
    out.push_back(ReceivedCommand{id, connection.peer, std::move(*request)});
  }
};

Result<CommandListener> CommandListener::open(Options options) {
  if (!isValidName(options.instance)) return Error{"invalid instance name '" + options.instance + "'"};
  if (!isValidName(options.program)) return Error{"invalid program name '" + options.program + "'"};
  auto impl = std::make_unique<CommandListenerImpl>();
  impl->group = groupId(options.groupName);
  impl->directory = commandSocketDir(options.instance);
  impl->path = impl->directory + "/" + options.program + ".sock";
  const std::string root = commandRoot();
  const uid_t self = ::geteuid();

  // <root> (0755) and <root>/<instance> (0750 root:group, or 0700).
  if (::mkdir(root.c_str(), 0755) != 0 && errno != EEXIST) {
    return Error{"cannot create the command folder " + root + ": " + errnoText(errno)};
  }
  const mode_t folderMode = impl->group ? 0750 : 0700;
  if (::mkdir(impl->directory.c_str(), folderMode) != 0 && errno != EEXIST) {
    return Error{"cannot create the command folder " + impl->directory + ": " + errnoText(errno)};
  }
  struct stat folder {};
  if (::lstat(impl->directory.c_str(), &folder) != 0 || !S_ISDIR(folder.st_mode)) {
    return Error{impl->directory + ": not a folder; commands cannot be served there"};
  }
  if (folder.st_uid != self && folder.st_uid != 0) {
    return Error{impl->directory + " is owned by uid " + std::to_string(folder.st_uid) +
                 ", not by this user or root: refusing to serve commands there"};
  }
  if (folder.st_uid == self) {
    const gid_t folderGroup = impl->group ? static_cast<gid_t>(*impl->group) : static_cast<gid_t>(-1);
    if (::chown(impl->directory.c_str(), static_cast<uid_t>(-1), folderGroup) != 0 ||
        ::chmod(impl->directory.c_str(), folderMode) != 0) {
      return Error{"cannot set owner and mode of " + impl->directory + ": " + errnoText(errno)};
    }
  } else if ((folder.st_mode & 0022) != 0) {
    return Error{impl->directory + " is writable by others: refusing to serve commands there"};
  }

  sockaddr_un address{};
  if (!fillAddress(impl->path, address)) return Error{"command socket path too long: " + impl->path};
  // A socket left by a process that died is removed; one that answers is a live twin.
  struct stat existing {};
  if (::lstat(impl->path.c_str(), &existing) == 0) {
    if (!S_ISSOCK(existing.st_mode)) return Error{impl->path + " exists and is not a socket"};
    Fd probe(::socket(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC | SOCK_NONBLOCK, 0));
    if (probe.valid() && ::connect(probe.get(), reinterpret_cast<const sockaddr*>(&address), sizeof address) == 0) {
      return Error{"another " + options.program + " of instance '" + options.instance + "' is running (" + impl->path +
                   " answers)"};
    }
    ::unlink(impl->path.c_str());
  }

  impl->listening = Fd(::socket(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC | SOCK_NONBLOCK, 0));
  if (!impl->listening.valid()) return Error{"cannot create a command socket: " + errnoText(errno)};
  if (::bind(impl->listening.get(), reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0) {
    return Error{"cannot bind the command socket " + impl->path + ": " + errnoText(errno)};
  }
  const mode_t socketMode = impl->group ? 0660 : 0600;
  const gid_t socketGroup = impl->group ? static_cast<gid_t>(*impl->group) : static_cast<gid_t>(-1);
  if (::chown(impl->path.c_str(), static_cast<uid_t>(-1), socketGroup) != 0 ||
      ::chmod(impl->path.c_str(), socketMode) != 0) {
    const int error = errno;
    ::unlink(impl->path.c_str());
    return Error{"cannot set owner and mode of " + impl->path + ": " + errnoText(error)};
  }
  struct stat bound {};
  if (::lstat(impl->path.c_str(), &bound) == 0) impl->inode = bound.st_ino;
  if (::listen(impl->listening.get(), 64) != 0)
    return Error{"cannot listen on " + impl->path + ": " + errnoText(errno)};

  impl->epoll = Fd(::epoll_create1(EPOLL_CLOEXEC));
  if (!impl->epoll.valid()) return Error{"epoll_create1: " + errnoText(errno)};
  epoll_event event{};
  event.events = EPOLLIN;
  event.data.u64 = 0;  // 0: the listening socket; connections are 1, 2, ...
  if (::epoll_ctl(impl->epoll.get(), EPOLL_CTL_ADD, impl->listening.get(), &event) != 0) {
    return Error{"epoll_ctl: " + errnoText(errno)};
  }
  impl->idleTimer = Fd(::timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC));
  if (!impl->idleTimer.valid()) return Error{"timerfd_create: " + errnoText(errno)};
  event.data.u64 = CommandListenerImpl::IDLE_TIMER;
  if (::epoll_ctl(impl->epoll.get(), EPOLL_CTL_ADD, impl->idleTimer.get(), &event) != 0) {
    return Error{"epoll_ctl: " + errnoText(errno)};
  }
  impl->options = std::move(options);
  return CommandListener(std::move(impl));
}

CommandListener::CommandListener(std::unique_ptr<CommandListenerImpl> impl) noexcept : m_impl(std::move(impl)) {}
CommandListener::CommandListener(CommandListener&& other) noexcept = default;
CommandListener& CommandListener::operator=(CommandListener&& other) noexcept = default;
CommandListener::~CommandListener() = default;

int CommandListener::fd() const noexcept {
  return m_impl->epoll.get();
}
const std::string& CommandListener::path() const noexcept {
  return m_impl->path;
}
bool CommandListener::groupAccess() const noexcept {
  return m_impl->group.has_value();
}

void CommandListener::poll(std::vector<ReceivedCommand>& out) {
  std::array<epoll_event, 64> ready{};
  const int count = ::epoll_wait(m_impl->epoll.get(), ready.data(), static_cast<int>(ready.size()), 0);
  for (int i = 0; i < count; ++i) {
    const epoll_event& event = ready.at(static_cast<std::size_t>(i));
    if (event.data.u64 == 0) {
      m_impl->acceptAll();
    } else if (event.data.u64 == CommandListenerImpl::IDLE_TIMER) {
      m_impl->onIdleTimer();
    } else {
      m_impl->takeOne(event.data.u64, event.events, out);
    }
  }
  m_impl->armIdleTimer();
}

bool CommandListener::reply(std::uint64_t connection, const CommandAck& ack) noexcept {
  const auto found = m_impl->connections.find(connection);
  if (found == m_impl->connections.end()) return false;
  CommandListenerImpl::Connection& open = found->second;
  if (open.owed > 0) --open.owed;
  open.activeNs = clock::monotonicNs();
  m_impl->armIdleTimer();
  try {
    return sendMessage(open.fd.get(), encodeCommandAck(ack));
  } catch (...) {
    return false;
  }
}

std::uint64_t CommandListener::refusedPeers() const noexcept {
  return m_impl->refusedPeers;
}
std::uint64_t CommandListener::malformed() const noexcept {
  return m_impl->malformed;
}
std::uint64_t CommandListener::closedIdle() const noexcept {
  return m_impl->closedIdle;
}
std::size_t CommandListener::connections() const noexcept {
  return m_impl->connections.size();
}

// ---- client ------------------------------------------------------------------------------

struct CommandClientImpl {
  struct Service {
    std::string name;
    std::string path;
    Fd fd;
  };
  std::string directory;
  std::uint32_t folderOwner{};
  std::vector<Service> services;
  std::vector<std::uint8_t> buffer = std::vector<std::uint8_t>(MAX_COMMAND_BYTES + 1);

  /// A connection to the socket at `path`, served by root or the folder's owner.
  /// `connectError` is connect(2)'s errno when that failed, else 0.
  Result<Fd> connectTo(const std::string& path, int& connectError) const {
    connectError = 0;
    sockaddr_un address{};
    if (!fillAddress(path, address)) {
      connectError = ENAMETOOLONG;
      return Error{path + ": path too long for a Unix socket"};
    }
    Fd fd(::socket(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0));
    if (!fd.valid()) return Error{"cannot create a socket: " + errnoText(errno)};
    if (::connect(fd.get(), reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0) {
      connectError = errno;
      return Error{path + ": " + errnoText(connectError)};
    }
    const auto server = peerOf(fd.get());
    if (!server || (server->uid != 0 && server->uid != folderOwner)) {
      return Error{"refusing " + path + ": served by uid " + (server ? std::to_string(server->uid) : "?") +
                   ", not by root or the folder's owner"};
    }
    return fd;
  }

  /// The listener's refusal of this connection (request id 0, not accepted), read from what
  /// the service left on it before closing it; answers to earlier requests are skipped.
  std::optional<CommandAck> takeRefusal(int fd) {
    for (int message = 0; message < 64; ++message) {
      const ssize_t size = ::recv(fd, buffer.data(), buffer.size(), MSG_DONTWAIT);
      if (size <= 0) return std::nullopt;
      auto ack = decodeCommandAck(buffer.data(), static_cast<std::size_t>(size));
      if (ack && ack->requestId == 0 && !ack->accepted) return ack;
    }
    return std::nullopt;
  }

  enum class Delivery : std::uint8_t { Sent, Busy, Refused, Gone };

  /// Sends `bytes` to service `index`. A connection the service closed without a word (idle
  /// for COMMAND_IDLE_TIMEOUT, or the service restarted) is opened again once; one it closed
  /// with a refusal puts that into `refusal`.
  Delivery deliver(std::size_t index, const std::vector<std::uint8_t>& bytes, std::optional<CommandAck>& refusal) {
    Service& service = services[index];
    for (int attempt = 0; attempt < 2; ++attempt) {
      if (::send(service.fd.get(), bytes.data(), bytes.size(), MSG_DONTWAIT | MSG_NOSIGNAL) ==
          static_cast<ssize_t>(bytes.size())) {
        return Delivery::Sent;
      }
      // A full socket buffer means a busy service: it does not get this request.
      if (errno == EAGAIN || errno == EWOULDBLOCK) return Delivery::Busy;
      if (auto refused = takeRefusal(service.fd.get())) {
        refusal = std::move(refused);
        return Delivery::Refused;
      }
      if (attempt > 0) break;
      int connectError = 0;
      auto again = connectTo(service.path, connectError);
      if (!again) return Delivery::Gone;
      service.fd = std::move(*again);
    }
    return Delivery::Gone;
  }
};

Result<CommandClient> CommandClient::connect(std::string_view instance) {
  if (!isValidName(instance)) return Error{"invalid instance name '" + std::string(instance) + "'"};
  auto impl = std::make_unique<CommandClientImpl>();
  impl->directory = commandSocketDir(instance);
  const std::string who = ::geteuid() == 0 ? "" : " (commands need root or membership of the stack's command group)";
  struct stat folder {};
  if (::stat(impl->directory.c_str(), &folder) != 0) {
    if (errno == ENOENT) {
      return Error{"no stack of instance '" + std::string(instance) + "' is running here (" + impl->directory +
                   " does not exist)"};
    }
    return Error{"cannot reach " + impl->directory + ": " + errnoText(errno) + who};
  }
  // Trust only a folder that root, this user or the installed stack's user owns and nobody
  // else can write.
  const std::optional<std::uint32_t> stackUser = userId(STACK_USER);
  const bool trustedOwner =
      folder.st_uid == 0 || folder.st_uid == ::geteuid() || (stackUser && folder.st_uid == *stackUser);
  if (!trustedOwner || (folder.st_mode & 0022) != 0) {
    return Error{"refusing " + impl->directory + ": owned by uid " + std::to_string(folder.st_uid) +
                 " or writable by others, so its sockets cannot be trusted"};
  }
  impl->folderOwner = folder.st_uid;
  DIR* listing = ::opendir(impl->directory.c_str());
  if (listing == nullptr) return Error{"cannot read " + impl->directory + ": " + errnoText(errno) + who};
  std::vector<std::string> names;
  while (const dirent* entry = ::readdir(listing)) {
    const std::string name = entry->d_name;
    constexpr std::string_view SUFFIX = ".sock";
    if (name.size() > SUFFIX.size() && name.ends_with(SUFFIX)) names.push_back(name.substr(0, name.size() - 5));
  }
  ::closedir(listing);
  std::sort(names.begin(), names.end());
  std::string lastError;
  for (const std::string& name : names) {
    const std::string path = impl->directory + "/" + name + ".sock";
    int connectError = 0;
    auto fd = impl->connectTo(path, connectError);
    if (!fd) {
      if (connectError == EACCES || connectError == EPERM)
        return Error{"cannot connect to " + fd.error().message + who};
      if (connectError == 0) return fd.error();  // no socket of our own, or an untrusted server
      lastError = fd.error().message;            // ECONNREFUSED: a service that is not running
      continue;
    }
    impl->services.push_back(CommandClientImpl::Service{name, path, std::move(*fd)});
  }
  if (impl->services.empty()) {
    return Error{"no service of instance '" + std::string(instance) + "' answers commands (" +
                 (lastError.empty() ? "no socket in " + impl->directory : lastError) + ")"};
  }
  return CommandClient(std::move(impl));
}

CommandClient::CommandClient(std::unique_ptr<CommandClientImpl> impl) noexcept : m_impl(std::move(impl)) {}
CommandClient::CommandClient(CommandClient&& other) noexcept = default;
CommandClient& CommandClient::operator=(CommandClient&& other) noexcept = default;
CommandClient::~CommandClient() = default;

std::vector<std::string> CommandClient::services() const {
  std::vector<std::string> names;
  for (const auto& service : m_impl->services) names.push_back(service.name);
  return names;
}

Result<CommandAck> CommandClient::send(CommandRequest request, std::chrono::nanoseconds timeout) {
  const std::int64_t deadline =
      request.deadlineNs > 0 ? request.deadlineNs : clock::monotonicNs() + std::max<std::int64_t>(timeout.count(), 1);
  if (request.requestId == 0) request.requestId = randomRequestId();
  request.deadlineNs = deadline;
  const std::vector<std::uint8_t> bytes = encodeCommandRequest(request);
  if (bytes.empty() || bytes.size() > MAX_COMMAND_BYTES) {
    return Error{"the command does not fit one message (" + std::to_string(bytes.size()) + " bytes, at most " +
                 std::to_string(MAX_COMMAND_BYTES) + ")"};
  }
  auto& services = m_impl->services;
  std::vector<bool> waiting(services.size(), false);
  std::optional<CommandAck> refusal;  // a service's listener refused the connection: why
  std::size_t open = 0;
  std::size_t refused = 0;
  for (std::size_t i = 0; i < services.size(); ++i) {
    switch (m_impl->deliver(i, bytes, refusal)) {
      case CommandClientImpl::Delivery::Sent:
        waiting[i] = true;
        ++open;
        break;
      case CommandClientImpl::Delivery::Refused:
        ++refused;
        break;
      case CommandClientImpl::Delivery::Busy:
      case CommandClientImpl::Delivery::Gone:
        break;
    }
  }
  std::vector<std::string> notOwners;
  std::vector<pollfd> fds(services.size());
  while (open > 0) {
    const std::int64_t left = deadline - clock::monotonicNs();
    if (left <= 0) break;
    for (std::size_t i = 0; i < services.size(); ++i) {
      fds[i] = pollfd{waiting[i] ? services[i].fd.get() : -1, POLLIN, 0};
    }
    const int timeoutMs = static_cast<int>(std::min<std::int64_t>((left + 999'999) / 1'000'000, 60'000));
    if (::poll(fds.data(), fds.size(), timeoutMs) < 0 && errno != EINTR) break;
    for (std::size_t i = 0; i < services.size(); ++i) {
      if (!waiting[i] || fds[i].revents == 0) continue;
      const ssize_t size = ::recv(services[i].fd.get(), m_impl->buffer.data(), m_impl->buffer.size(), MSG_DONTWAIT);
      if (size < 0 && (errno == EAGAIN || errno == EINTR)) continue;
      if (size <= 0) {  // the service closed the connection (stopped): no answer from it
        waiting[i] = false;
        --open;
        continue;
      }
      const auto ack = decodeCommandAck(m_impl->buffer.data(), static_cast<std::size_t>(size));
      if (!ack) continue;
      if (ack->requestId == 0 && !ack->accepted) {  // the listener refused the connection
        refusal = *ack;
        ++refused;
        waiting[i] = false;
        --open;
        continue;
      }
      if (ack->requestId != request.requestId) continue;  // an answer to an earlier, expired request
      if (ack->owner) return *ack;
      notOwners.push_back(services[i].name);
      waiting[i] = false;
      --open;
    }
  }
  if (open == 0 && refusal && notOwners.size() + refused == services.size()) {
    // Nobody else owns the command: the refusal is the answer; the service never saw it.
    CommandAck answer = std::move(*refusal);
    answer.requestId = request.requestId;
    answer.issuer = request.issuer;
    answer.owner = true;
    return answer;
  }
  if (open == 0 && notOwners.size() == services.size()) {
    std::string names;
    for (const std::string& name : notOwners) names += (names.empty() ? "" : ", ") + name;
    return Error{"no running service answers for '" + request.key + "' (" + names + ": not theirs)"};
  }
  const double seconds = static_cast<double>(timeout.count()) / 1e9;
  std::ostringstream text;
  text << "no service answered within " << seconds << " s";
  if (refusal) text << " (" << refusal->responder << " refused the connection: " << refusal->reason << ")";
  text << "; the command expired and will not be applied";
  return Error{text.str()};
}

}  // namespace openvcu::ipc
