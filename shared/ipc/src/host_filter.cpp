#include "openvcu/ipc/host_filter.hpp"

#include <dirent.h>
#include <linux/filter.h>     // sock_filter, sock_fprog, BPF_*, SKF_AD_*
#include <linux/if_packet.h>  // PACKET_LOOPBACK
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/stat.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <string>

namespace openvcu::ipc {

namespace {

/// The loopback device's ifindex: 1 in every network namespace (Linux LOOPBACK_IFINDEX,
/// include/net/flow.h), so the filter needs no per-namespace lookup.
constexpr std::uint32_t LOOPBACK_IFINDEX = 1;
/// Returned by a socket filter: keep this many bytes of the datagram (all of it) or none.
constexpr std::uint32_t ACCEPT_WHOLE = 0xFFFF'FFFFU;
constexpr std::uint32_t DROP = 0;

constexpr std::uint32_t ancillary(int offset) noexcept {
  return static_cast<std::uint32_t>(SKF_AD_OFF + offset);
}

// if (ifindex == lo) accept; if (pkttype == PACKET_LOOPBACK) accept; drop.
// Jump offsets count instructions after the jump: jt/jf.
const std::array<sock_filter, 6> THIS_HOST_ONLY{{
    BPF_STMT(BPF_LD | BPF_W | BPF_ABS, ancillary(SKF_AD_IFINDEX)),
    BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, LOOPBACK_IFINDEX, 2, 0),
    BPF_STMT(BPF_LD | BPF_W | BPF_ABS, ancillary(SKF_AD_PKTTYPE)),
    BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, PACKET_LOOPBACK, 0, 1),
    BPF_STMT(BPF_RET | BPF_K, ACCEPT_WHOLE),
    BPF_STMT(BPF_RET | BPF_K, DROP),
}};

std::string errnoText() {
  return std::strerror(errno);
}

/// true for an AF_INET SOCK_DGRAM (UDP) socket with SO_REUSEADDR on, bound to `port`
/// (0: to any port): how LCM's udpm provider sets up its receive socket.
bool isLcmReceiveSocket(int fd, std::uint16_t port) noexcept {
  int domain = 0;
  int type = 0;
  int reuse = 0;
  socklen_t length = sizeof domain;
  if (::getsockopt(fd, SOL_SOCKET, SO_DOMAIN, &domain, &length) != 0 || domain != AF_INET) return false;
  length = sizeof type;
  if (::getsockopt(fd, SOL_SOCKET, SO_TYPE, &type, &length) != 0 || type != SOCK_DGRAM) return false;
  length = sizeof reuse;
  if (::getsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &reuse, &length) != 0 || reuse == 0) return false;
  sockaddr_in address{};
  socklen_t addressLength = sizeof address;
  if (::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &addressLength) != 0) return false;
  const std::uint16_t bound = ntohs(address.sin_port);
  return bound != 0 && (port == 0 || bound == port);
}

/// Calls visit(fd, inode) for each socket among this process's open files.
template <typename Visit>
Status forEachSocket(Visit visit) {
  DIR* folder = ::opendir("/proc/self/fd");
  if (folder == nullptr) return Error{"cannot list /proc/self/fd: " + errnoText()};
  const int own = ::dirfd(folder);
  while (const dirent* entry = ::readdir(folder)) {
    char* end = nullptr;
    const long fd = std::strtol(entry->d_name, &end, 10);
    if (end == entry->d_name || *end != '\0' || fd == own) continue;
    struct stat status {};
    if (::fstat(static_cast<int>(fd), &status) != 0 || !S_ISSOCK(status.st_mode)) continue;
    visit(static_cast<int>(fd), static_cast<std::uint64_t>(status.st_ino));
  }
  ::closedir(folder);
  return {};
}

}  // namespace

Status acceptOnlyFromThisHost(int fd) {
  sock_fprog program{};
  program.len = static_cast<unsigned short>(THIS_HOST_ONLY.size());
  program.filter = const_cast<sock_filter*>(THIS_HOST_ONLY.data());  // the kernel copies it
  if (::setsockopt(fd, SOL_SOCKET, SO_ATTACH_FILTER, &program, sizeof program) != 0) {
    return Error{"cannot attach the this-host-only filter to socket " + std::to_string(fd) + ": " + errnoText()};
  }
  return {};
}

bool acceptsOnlyFromThisHost(int fd) noexcept {
  std::array<sock_filter, THIS_HOST_ONLY.size() + 1> attached{};
  socklen_t count = attached.size();  // SO_GET_FILTER counts instructions, not bytes
  if (::getsockopt(fd, SOL_SOCKET, SO_GET_FILTER, attached.data(), &count) != 0) return false;
  if (count != THIS_HOST_ONLY.size()) return false;
  return std::equal(THIS_HOST_ONLY.begin(), THIS_HOST_ONLY.end(), attached.begin(),
                    [](const sock_filter& a, const sock_filter& b) {
                      return a.code == b.code && a.jt == b.jt && a.jf == b.jf && a.k == b.k;
                    });
}

Result<std::vector<std::uint64_t>> openSocketInodes() {
  std::vector<std::uint64_t> inodes;
  Status listed = forEachSocket([&](int /*fd*/, std::uint64_t inode) { inodes.push_back(inode); });
  if (!listed) return listed.error();
  std::sort(inodes.begin(), inodes.end());
  return inodes;
}

Result<std::size_t> restrictNewUdpSockets(const std::vector<std::uint64_t>& known, std::uint16_t port) {
  std::size_t filtered = 0;
  std::string failure;
  Status listed = forEachSocket([&](int fd, std::uint64_t inode) {
    if (std::binary_search(known.begin(), known.end(), inode) || !isLcmReceiveSocket(fd, port)) return;
    Status attached = acceptOnlyFromThisHost(fd);
    if (attached) {
      ++filtered;
    } else {
      failure = attached.error().message;
    }
  });
  if (!listed) return listed.error();
  if (!failure.empty()) return Error{failure};
  if (filtered == 0) {
    return Error{"found no new UDP socket bound to port " + std::to_string(port) + " (LCM's receive socket)"};
  }
  return filtered;
}

}  // namespace openvcu::ipc
