// The attacker's and the careless user's tools for security_test.sh (issue 18):
//
//   forge_command listen URL INSTANCE SECONDS
//       subscribes to the instance's old LCM COMMAND channel and prints "SEEN <channel>" for
//       every message: proof that a forged datagram really reached the stack's host
//   forge_command datagram ADDRESS INSTANCE KEY VALUE COUNT
//       sends COUNT hand-made LCM datagrams (LC02 header) to ADDRESS:7667 with TTL 1: an
//       OperatorSwitch request on OPENVCU_<I>_COMMAND and an "accepted" answer for it on
//       OPENVCU_<I>_ACK, each with a valid deadline, as a host on the LAN could
//   forge_command flood INSTANCE SERVICE COUNT KEY
//       one connection to <service>.sock, COUNT SetSignal requests for KEY as fast as the
//       socket takes them, reading the answers meanwhile; prints
//       "ANSWERED <answers> OF <count> IN <ms> MS"
#include <arpa/inet.h>
#include <lcm/lcm.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <cstring>
#include <iostream>
#include <string>
#include <vector>

#include "lan_datagrams.hpp"
#include "openvcu/core/clock.hpp"
#include "openvcu/ipc/command_socket.hpp"
#include "openvcu/ipc/events.hpp"

namespace ipc = openvcu::ipc;
namespace demo = openvcu::demo;

namespace {

void onMessage(const lcm_recv_buf_t*, const char* channel, void*) {
  std::cout << "SEEN " << channel << std::endl;
}

int listen(const std::string& url, const std::string& instance, int seconds) {
  lcm_t* lcm = lcm_create(url.c_str());
  if (lcm == nullptr) {
    std::cout << "ERROR cannot open " << url << std::endl;
    return 2;
  }
  lcm_subscribe(lcm, ipc::channelName(instance, ipc::EventKind::Command).c_str(), &onMessage, nullptr);
  std::cout << "LISTENING" << std::endl;
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(seconds);
  while (std::chrono::steady_clock::now() < end) lcm_handle_timeout(lcm, 100);
  lcm_destroy(lcm);
  return 0;
}

int datagram(const std::string& address, const std::string& instance, const std::string& key, double value, int count) {
  const int sent = demo::sendToLcmPort(address, count, [&](int i) {
    const std::int64_t id = 1000 + i;
    const ipc::CommandRequest request{0,   id,    "vcu-hmi", ipc::CommandKind::OperatorSwitch,
                                      key, value, "",        openvcu::clock::monotonicNs() + 10'000'000'000};
    const ipc::CommandAck ack{0, id, "vcu", "vcu-fsm", true, "", true};
    return std::vector<std::vector<std::uint8_t>>{
        demo::lcmDatagram(ipc::channelName(instance, ipc::EventKind::Command), ipc::encodeCommandRequest(request),
                          static_cast<std::uint32_t>(2 * i)),
        demo::lcmDatagram(ipc::channelName(instance, ipc::EventKind::Ack), ipc::encodeCommandAck(ack),
                          static_cast<std::uint32_t>(2 * i + 1))};
  });
  if (sent < 0) return 2;
  std::cout << "SENT " << sent << std::endl;
  return sent > 0 ? 0 : 1;
}

int flood(const std::string& instance, const std::string& service, int count, const std::string& key) {
  const std::string path = ipc::commandSocketDir(instance) + "/" + service + ".sock";
  const int fd = ::socket(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0);
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  std::strncpy(address.sun_path, path.c_str(), sizeof(address.sun_path) - 1);
  if (::connect(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0) {
    std::cout << "ERROR connect " << path << ": " << std::strerror(errno) << std::endl;
    return 2;
  }
  const auto start = std::chrono::steady_clock::now();
  int sentCount = 0;
  int answers = 0;
  std::vector<std::uint8_t> buffer(ipc::MAX_COMMAND_BYTES);
  while (answers < count) {
    if (std::chrono::steady_clock::now() - start > std::chrono::seconds(60)) break;
    pollfd pfd{fd, static_cast<short>(POLLIN | (sentCount < count ? POLLOUT : 0)), 0};
    if (::poll(&pfd, 1, 1000) < 0) break;
    if ((pfd.revents & POLLIN) != 0) {
      if (::recv(fd, buffer.data(), buffer.size(), MSG_DONTWAIT) > 0) ++answers;
    }
    if ((pfd.revents & POLLOUT) != 0 && sentCount < count) {
      const ipc::CommandRequest request{0,   sentCount + 1, "flood", ipc::CommandKind::SetSignal,
                                        key, 1.0,           "",      openvcu::clock::monotonicNs() + 30'000'000'000};
      const auto bytes = ipc::encodeCommandRequest(request);
      if (::send(fd, bytes.data(), bytes.size(), MSG_DONTWAIT | MSG_NOSIGNAL) == static_cast<ssize_t>(bytes.size())) {
        ++sentCount;
      }
    }
    if ((pfd.revents & (POLLHUP | POLLERR)) != 0) break;
  }
  const auto ms =
      std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() - start).count();
  std::cout << "ANSWERED " << answers << " OF " << count << " IN " << ms << " MS" << std::endl;
  ::close(fd);
  return answers == count ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  const std::vector<std::string> args(argv + 1, argv + argc);
  if (args.size() == 4 && args[0] == "listen") return listen(args[1], args[2], std::stoi(args[3]));
  if (args.size() == 6 && args[0] == "datagram") {
    return datagram(args[1], args[2], args[3], std::stod(args[4]), std::stoi(args[5]));
  }
  if (args.size() == 5 && args[0] == "flood") return flood(args[1], args[2], std::stoi(args[3]), args[4]);
  std::cerr << "usage: forge_command listen URL INSTANCE SECONDS | datagram ADDRESS INSTANCE KEY VALUE COUNT |"
               " flood INSTANCE SERVICE COUNT KEY\n";
  return 2;
}
