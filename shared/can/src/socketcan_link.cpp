// socketcan:IFACE: the Link over a raw CAN socket. The wait handle is an epoll fd that holds
// the socket (while open) and a timerfd (while reopening); receive() drains both.
// Design: docs/design/socketcan.md. Kernel facts: linux/can.h, linux/can/raw.h, can.rst.

#include "openvcu/can/socketcan_link.hpp"

#include <linux/can/raw.h>
#include <net/if.h>
#include <net/if_arp.h>
#include <sys/epoll.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <sys/timerfd.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <utility>

#include "openvcu/can/event_queue.hpp"
#include "openvcu/can/socketcan_codec.hpp"

namespace openvcu::can {
namespace {

/// Owns one file descriptor; closes it when destroyed or reset.
class FileDescriptor {
 public:
  FileDescriptor() = default;
  explicit FileDescriptor(int fd) noexcept : m_fd(fd) {}
  FileDescriptor(const FileDescriptor&) = delete;
  FileDescriptor& operator=(const FileDescriptor&) = delete;
  FileDescriptor(FileDescriptor&& other) noexcept : m_fd(std::exchange(other.m_fd, -1)) {}
  FileDescriptor& operator=(FileDescriptor&& other) noexcept {
    if (this != &other) reset(std::exchange(other.m_fd, -1));
    return *this;
  }
  ~FileDescriptor() { reset(); }

  [[nodiscard]] int get() const noexcept { return m_fd; }
  [[nodiscard]] bool valid() const noexcept { return m_fd >= 0; }
  int release() noexcept { return std::exchange(m_fd, -1); }
  void reset(int fd = -1) noexcept {
    if (m_fd >= 0) ::close(m_fd);
    m_fd = fd;
  }

 private:
  int m_fd{-1};
};

constexpr std::int64_t NS_PER_SECOND = 1'000'000'000;

std::int64_t clockNs(clockid_t clock) noexcept {
  timespec now{};
  ::clock_gettime(clock, &now);
  return std::int64_t{now.tv_sec} * NS_PER_SECOND + now.tv_nsec;
}

struct ClockReading {
  std::int64_t realtimeNs{};
  std::int64_t monotonicNs{};
};

ClockReading readClocks() noexcept {
  return {clockNs(CLOCK_REALTIME), clockNs(CLOCK_MONOTONIC)};
}

/// A zero or tiny reopen interval must not turn the timer into a busy loop.
constexpr std::chrono::milliseconds MIN_REOPEN_INTERVAL{10};

/// Datagrams per recvmmsg call: one system call for a burst, 32 * 72 bytes of buffers.
constexpr std::size_t RECEIVE_BATCH = 32;

/// Control messages of one datagram: SCM_TIMESTAMPNS and SO_RXQ_OVFL, with room for a
/// stamp triple should SO_TIMESTAMPING ever be switched on (the kernel truncates, MSG_CTRUNC,
/// rather than overflow).
constexpr std::size_t CONTROL_SIZE =
    CMSG_SPACE(sizeof(timespec)) + CMSG_SPACE(sizeof(std::uint32_t)) + CMSG_SPACE(3 * sizeof(timespec));

struct alignas(cmsghdr) ControlBuffer {
  std::array<unsigned char, CONTROL_SIZE> bytes;
};

struct alignas(8) DatagramBuffer {  // canfd_frame's alignment (data is aligned(8))
  std::array<std::uint8_t, FD_DATAGRAM_SIZE> bytes;
};

/// errno values of a non-blocking recv/send that only mean "not now".
bool isTransient(int error) noexcept {
  return error == EAGAIN || error == EWOULDBLOCK || error == EINTR;
}

/// errno values of send() that mean the kernel's transmit queue is full.
bool isQueueFull(int error) noexcept {
  return isTransient(error) || error == ENOBUFS;
}

SocketAttempt failed(int errorNumber, const char* what = "") noexcept {
  return SocketAttempt{-1, errorNumber, what};
}

/// Fills ifr_name; false when the name does not fit (the kernel would say ENODEV).
bool setInterfaceName(ifreq& request, const char* interface) noexcept {
  const std::size_t length = ::strnlen(interface, IFNAMSIZ);
  if (length == 0 || length >= IFNAMSIZ) return false;
  std::memcpy(request.ifr_name, interface, length);
  request.ifr_name[length] = '\0';
  return true;
}

template <typename T>
bool setOption(int fd, int level, int option, const T& value) noexcept {
  return ::setsockopt(fd, level, option, &value, sizeof value) == 0;
}

class SocketCanLink final : public Link {
 public:
  SocketCanLink(const std::string& interface, const LinkOptions& options, SocketOpener opener, FileDescriptor epoll,
                FileDescriptor timer)
      : m_interface(interface),
        m_name("socketcan:" + interface),
        m_opener(std::move(opener)),
        m_reopenInterval(std::max(options.reopenInterval, MIN_REOPEN_INTERVAL)),
        m_epoll(std::move(epoll)),
        m_timer(std::move(timer)) {
    if (fitsKernelFilters(options.filters.size())) {
      m_kernelFilters = toKernelFilters(options.filters);
    } else {
      m_userFilters = options.filters;
    }
    m_setup.interfaceName = m_interface.c_str();
    m_setup.fd = options.fd;
    m_setup.errorFrames = options.errorFrames;
    m_setup.kernelFilters = !options.filters.empty() && m_userFilters.empty();
    m_setup.filters = m_kernelFilters;
    for (std::size_t i = 0; i < RECEIVE_BATCH; ++i) {
      m_vectors[i] = iovec{m_datagrams[i].bytes.data(), m_datagrams[i].bytes.size()};
      msghdr& header = m_messages[i].msg_hdr;
      header.msg_iov = &m_vectors[i];
      header.msg_iovlen = 1;
      header.msg_control = m_controls[i].bytes.data();
    }
  }
  ~SocketCanLink() override { closeSocket(); }

  [[nodiscard]] LinkKind kind() const noexcept override { return LinkKind::SocketCan; }
  [[nodiscard]] const std::string& name() const noexcept override { return m_name; }
  [[nodiscard]] WaitHandle waitHandle() noexcept override { return WaitHandle{m_epoll.get(), nullptr}; }
  std::size_t receive(std::span<ReceivedFrame> out) noexcept override;
  SendStatus send(const Frame& frame) noexcept override;
  std::optional<BusEvent> nextEvent() noexcept override { return m_events.pop(); }
  [[nodiscard]] bool up() const noexcept override { return m_socket.valid(); }
  [[nodiscard]] LinkStats stats() const noexcept override { return m_stats; }

  /// The first open, before the link is handed out: the socket, or the reason there is none.
  [[nodiscard]] SocketAttempt openFirst() noexcept { return m_opener(m_setup); }
  /// Takes `fd` as the link's socket and watches it; 0, or the errno of epoll_ctl (fd closed).
  int adopt(int fd) noexcept;
  void queue(BusEventKind kind, std::uint32_t detail) noexcept {
    m_events.push(BusEvent{kind, clockNs(CLOCK_MONOTONIC), detail, 0, 0});
  }
  /// Closes the socket (if any), queues LinkDown and starts the reopen timer.
  void goDown(int reason) noexcept;

 private:
  void closeSocket() noexcept;
  void armTimer() noexcept;
  void disarmTimer() noexcept;
  /// Consumes the timer's expirations; when due and down, tries to reopen.
  void serviceTimer() noexcept;
  void handleDatagram(std::size_t index, const ClockReading& clocks, std::span<ReceivedFrame> out,
                      std::size_t& written) noexcept;
  void noteDropCount(std::uint32_t dropCount, std::int64_t monotonicNs) noexcept;
  SendStatus sendFailed(SendStatus status) noexcept {
    ++m_stats.sendFailures;
    return status;
  }

  std::string m_interface;
  std::string m_name;
  std::vector<can_filter> m_kernelFilters;
  std::vector<IdFilter> m_userFilters;  // only when there are more filters than the kernel takes
  SocketSetup m_setup;
  SocketOpener m_opener;
  std::chrono::milliseconds m_reopenInterval;
  FileDescriptor m_epoll;
  FileDescriptor m_timer;
  FileDescriptor m_socket;
  bool m_timerArmed{};
  std::uint32_t m_lastDropCount{};  // SO_RXQ_OVFL is cumulative per socket
  detail::EventQueue m_events;
  LinkStats m_stats;
  // Receive buffers, wired together once in the constructor: no allocation per frame.
  std::array<DatagramBuffer, RECEIVE_BATCH> m_datagrams{};
  std::array<ControlBuffer, RECEIVE_BATCH> m_controls{};
  std::array<iovec, RECEIVE_BATCH> m_vectors{};
  std::array<mmsghdr, RECEIVE_BATCH> m_messages{};
};

int SocketCanLink::adopt(int fd) noexcept {
  FileDescriptor socket(fd);
  epoll_event interest{};
  interest.events = EPOLLIN;
  interest.data.fd = fd;
  if (::epoll_ctl(m_epoll.get(), EPOLL_CTL_ADD, fd, &interest) != 0) return errno;
  m_socket = std::move(socket);
  m_lastDropCount = 0;
  return 0;
}

void SocketCanLink::closeSocket() noexcept {
  if (!m_socket.valid()) return;
  ::epoll_ctl(m_epoll.get(), EPOLL_CTL_DEL, m_socket.get(), nullptr);
  m_socket.reset();
}

void SocketCanLink::goDown(int reason) noexcept {
  closeSocket();
  queue(BusEventKind::LinkDown, static_cast<std::uint32_t>(reason));
  armTimer();
}

void SocketCanLink::armTimer() noexcept {
  const auto seconds = std::chrono::duration_cast<std::chrono::seconds>(m_reopenInterval);
  const auto nanoseconds = std::chrono::duration_cast<std::chrono::nanoseconds>(m_reopenInterval - seconds);
  itimerspec period{};
  period.it_value.tv_sec = static_cast<time_t>(seconds.count());
  period.it_value.tv_nsec = static_cast<long>(nanoseconds.count());
  period.it_interval = period.it_value;  // periodic: one attempt per interval until one succeeds
  m_timerArmed = ::timerfd_settime(m_timer.get(), 0, &period, nullptr) == 0;
}

void SocketCanLink::disarmTimer() noexcept {
  const itimerspec stop{};
  ::timerfd_settime(m_timer.get(), 0, &stop, nullptr);  // also clears pending expirations
  m_timerArmed = false;
}

void SocketCanLink::serviceTimer() noexcept {
  std::uint64_t expirations = 0;
  if (::read(m_timer.get(), &expirations, sizeof expirations) != static_cast<ssize_t>(sizeof expirations)) return;
  if (m_socket.valid()) {
    disarmTimer();
    return;
  }
  const SocketAttempt attempt = m_opener(m_setup);
  if (attempt.fd < 0) return;  // still gone or down: the next period tries again
  if (adopt(attempt.fd) != 0) return;
  disarmTimer();
  ++m_stats.reopenings;
  queue(BusEventKind::LinkUp, 0);
}

std::size_t SocketCanLink::receive(std::span<ReceivedFrame> out) noexcept {
  if (m_timerArmed) serviceTimer();
  std::size_t written = 0;
  // Never read more datagrams than there is room for frames: each yields at most one.
  while (m_socket.valid() && written < out.size()) {
    const std::size_t wanted = std::min(out.size() - written, RECEIVE_BATCH);
    for (std::size_t i = 0; i < wanted; ++i) {
      m_messages[i].msg_hdr.msg_controllen = sizeof(ControlBuffer);  // the kernel shrinks it
      m_messages[i].msg_hdr.msg_flags = 0;
      m_messages[i].msg_len = 0;
    }
    const int count =
        ::recvmmsg(m_socket.get(), m_messages.data(), static_cast<unsigned int>(wanted), MSG_DONTWAIT, nullptr);
    if (count <= 0) {
      // EAGAIN: drained. EINTR: the wait handle stays readable, the caller comes back.
      // ENETDOWN (interface down), ENODEV (interface gone) or anything else: start over.
      const int error = count < 0 ? errno : 0;
      if (error != 0 && !isTransient(error)) goDown(error);
      break;
    }
    const ClockReading clocks = readClocks();
    for (std::size_t i = 0; i < static_cast<std::size_t>(count) && m_socket.valid(); ++i) {
      handleDatagram(i, clocks, out, written);
    }
  }
  return written;
}

void SocketCanLink::handleDatagram(std::size_t index, const ClockReading& clocks, std::span<ReceivedFrame> out,
                                   std::size_t& written) noexcept {
  const mmsghdr& message = m_messages[index];
  if (message.msg_len == 0) {
    // A raw CAN socket never reads an empty datagram; a socket at end of file does.
    goDown(ENOTCONN);
    return;
  }
  const std::span<const std::uint8_t> datagram(m_datagrams[index].bytes.data(), message.msg_len);
  std::optional<Frame> maybeFrame = decodeSocketFrame(datagram);
  if (!maybeFrame) return;  // neither CAN nor CAN FD (CAN XL is never enabled): skipped
  Frame& frame = *maybeFrame;

  const ReceiveMetadata metadata = parseControlMessages(message.msg_hdr);
  std::int64_t monotonicNs = clocks.monotonicNs;
  if (metadata.timestampNs) {
    frame.timestampNs = *metadata.timestampNs;
    monotonicNs = realtimeToMonotonic(frame.timestampNs, clocks.realtimeNs, clocks.monotonicNs);
  } else {
    frame.timestampNs = clocks.realtimeNs;
  }
  if (metadata.dropCount) noteDropCount(*metadata.dropCount, monotonicNs);

  if ((frame.flags & FLAG_ERROR) != 0) {
    ++m_stats.errorFrames;
    std::array<BusEvent, MAX_ERROR_EVENTS> events{};
    const std::size_t eventCount = decodeErrorFrame(frame, monotonicNs, events);
    for (std::size_t i = 0; i < eventCount; ++i) m_events.push(events[i]);
    return;
  }
  if (!m_userFilters.empty() && !acceptedByFilters(m_userFilters, frame)) {
    ++m_stats.filteredOut;
    return;
  }
  out[written++] = ReceivedFrame{frame, monotonicNs};
  ++m_stats.framesReceived;
}

void SocketCanLink::noteDropCount(std::uint32_t dropCount, std::int64_t monotonicNs) noexcept {
  const std::uint32_t lost = dropCount - m_lastDropCount;  // unsigned: survives the counter's wrap
  m_lastDropCount = dropCount;
  if (lost == 0) return;
  m_stats.receiveDropped += lost;
  m_events.push(BusEvent{BusEventKind::RxOverflow, monotonicNs, lost, 0, 0});
}

SendStatus SocketCanLink::send(const Frame& frame) noexcept {
  if (!m_socket.valid()) return sendFailed(SendStatus::Down);
  DatagramBuffer datagram;
  const std::size_t size = encodeSocketFrame(frame, m_setup.fd, datagram.bytes);
  if (size == 0) return sendFailed(SendStatus::Invalid);
  const ssize_t sent = ::send(m_socket.get(), datagram.bytes.data(), size, MSG_DONTWAIT | MSG_NOSIGNAL);
  if (sent == static_cast<ssize_t>(size)) {
    ++m_stats.framesSent;
    return SendStatus::Sent;
  }
  if (sent >= 0) return sendFailed(SendStatus::Busy);  // datagrams go whole or not at all
  const int error = errno;
  if (isQueueFull(error)) return sendFailed(SendStatus::Busy);
  if (error == EINVAL || error == EMSGSIZE) return sendFailed(SendStatus::Invalid);
  goDown(error);  // ENETDOWN, ENODEV, ...: the socket is no use any more
  return sendFailed(SendStatus::Down);
}

}  // namespace

SocketAttempt openRawCanSocket(const SocketSetup& setup) noexcept {
  FileDescriptor socket(::socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW));
  if (!socket.valid()) return failed(errno);  // EAFNOSUPPORT: no SocketCAN in this kernel
  const int fd = socket.get();

  const unsigned int interfaceIndex = ::if_nametoindex(setup.interfaceName);
  if (interfaceIndex == 0) return failed(errno == 0 ? ENODEV : errno);

  ifreq request{};
  if (!setInterfaceName(request, setup.interfaceName)) return failed(ENODEV);
  if (::ioctl(fd, SIOCGIFHWADDR, &request) != 0) return failed(errno, "cannot read the interface type");
  if (request.ifr_hwaddr.sa_family != ARPHRD_CAN) return failed(EMEDIUMTYPE);
  if (setup.fd) {
    if (::ioctl(fd, SIOCGIFMTU, &request) != 0) return failed(errno, "cannot read the interface MTU");
    if (request.ifr_mtu < static_cast<int>(FD_DATAGRAM_SIZE)) {
      return failed(EOPNOTSUPP, "the bus is configured for CAN FD but the interface is classic CAN only (MTU 16)");
    }
  }

  constexpr int ON = 1;
  if (setup.fd && !setOption(fd, SOL_CAN_RAW, CAN_RAW_FD_FRAMES, ON)) {
    return failed(errno, "cannot enable CAN FD frames (CAN_RAW_FD_FRAMES)");
  }
  if (setup.kernelFilters && ::setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FILTER, setup.filters.data(),
                                          static_cast<socklen_t>(setup.filters.size_bytes())) != 0) {
    return failed(errno, "cannot set the receive filters (CAN_RAW_FILTER)");
  }
  constexpr can_err_mask_t ALL_ERROR_CLASSES = CAN_ERR_MASK;
  if (setup.errorFrames && !setOption(fd, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, ALL_ERROR_CLASSES)) {
    return failed(errno, "cannot enable error frames (CAN_RAW_ERR_FILTER)");
  }
  if (!setOption(fd, SOL_SOCKET, SO_TIMESTAMPNS, ON)) return failed(errno, "cannot enable receive timestamps");
  if (!setOption(fd, SOL_SOCKET, SO_RXQ_OVFL, ON)) return failed(errno, "cannot enable drop counting (SO_RXQ_OVFL)");

  sockaddr_can address{};
  address.can_family = AF_CAN;
  address.can_ifindex = static_cast<int>(interfaceIndex);
  if (::bind(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0) {
    return failed(errno, "cannot bind");
  }
  // A bound socket on a down interface only reports ENETDOWN: wait until it is up.
  if (::ioctl(fd, SIOCGIFFLAGS, &request) != 0) return failed(errno, "cannot read the interface flags");
  if ((request.ifr_flags & IFF_UP) == 0) return failed(ENETDOWN);
  return SocketAttempt{socket.release(), 0, ""};
}

Result<std::unique_ptr<Link>> openSocketCanLinkWith(const std::string& interface, const LinkOptions& options,
                                                    SocketOpener opener) {
  if (!validInterfaceName(interface)) {
    return Error{"socketcan:" + interface + ": not an interface name (1..15 characters, no '/', ':' or blanks)"};
  }
  if (!opener) return Error{"socketcan:" + interface + ": no socket opener given"};
  FileDescriptor epoll(::epoll_create1(EPOLL_CLOEXEC));
  if (!epoll.valid()) return Error{openErrorMessage(interface, "cannot create the wait handle (epoll)", errno)};
  FileDescriptor timer(::timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC));
  if (!timer.valid()) return Error{openErrorMessage(interface, "cannot create the reopen timer", errno)};
  epoll_event interest{};
  interest.events = EPOLLIN;
  interest.data.fd = timer.get();
  if (::epoll_ctl(epoll.get(), EPOLL_CTL_ADD, timer.get(), &interest) != 0) {
    return Error{openErrorMessage(interface, "cannot watch the reopen timer", errno)};
  }

  auto link =
      std::make_unique<SocketCanLink>(interface, options, std::move(opener), std::move(epoll), std::move(timer));
  const SocketAttempt attempt = link->openFirst();
  if (attempt.fd >= 0) {
    if (const int error = link->adopt(attempt.fd); error != 0) {
      return Error{openErrorMessage(interface, "cannot watch the socket", error)};
    }
    link->queue(BusEventKind::LinkUp, 0);
  } else if (attempt.errorNumber == ENETDOWN) {
    link->goDown(ENETDOWN);  // exists but is down: wait for it like for a lost interface
  } else {
    return Error{openErrorMessage(interface, attempt.what != nullptr ? attempt.what : "", attempt.errorNumber)};
  }
  return std::unique_ptr<Link>(std::move(link));
}

Result<std::unique_ptr<Link>> openSocketCanLink(const std::string& interface, const LinkOptions& options) {
  return openSocketCanLinkWith(interface, options, &openRawCanSocket);
}

}  // namespace openvcu::can
