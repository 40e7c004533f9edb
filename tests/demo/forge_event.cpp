// The forger's and the witnesses' tools for event_trust_test.sh:
//
//   forge_event fault ADDRESS INSTANCE NAME COUNT
//       sends COUNT hand-made LCM datagrams (LC02 header) to ADDRESS:7667 with TTL 1, each an
//       active CRITICAL fault_event_t NAME from source vcu-fsm on OPENVCU_<I>_FAULT, as a
//       host on the LAN could (ADDRESS: the LCM group or a host's own address)
//   forge_event listen INSTANCE SECONDS
//       plain LCM on the default URL, as lcm-spy receives: prints "SEEN <name>" for each
//       fault: proof that a datagram really reached this host's LCM port
//   forge_event events INSTANCE SECONDS
//       ipc::EventBus on the default URL, as every consumer of the stack receives: prints
//       "EVENT <name>" for each fault, or "ERROR <why>" when the bus does not open
// Each listener prints "LISTENING" once it is subscribed.
#include <arpa/inet.h>
#include <lcm/lcm.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <iostream>
#include <string>
#include <vector>

#include "lan_datagrams.hpp"
#include "openvcu/core/clock.hpp"
#include "openvcu/ipc/event_bus.hpp"
#include "openvcu/ipc/events.hpp"

namespace ipc = openvcu::ipc;
namespace demo = openvcu::demo;

namespace {

void onFault(const lcm_recv_buf_t* buffer, const char*, void*) {
  const auto fault = ipc::decodeFaultEvent(buffer->data, buffer->data_size);
  std::cout << "SEEN " << (fault ? fault->name : std::string("(undecodable)")) << std::endl;
}

int listen(const std::string& instance, int seconds) {
  lcm_t* lcm = lcm_create(std::string(ipc::DEFAULT_EVENT_URL).c_str());
  if (lcm == nullptr) {
    std::cout << "ERROR cannot open LCM" << std::endl;
    return 2;
  }
  lcm_subscribe(lcm, ipc::channelName(instance, ipc::EventKind::Fault).c_str(), &onFault, nullptr);
  std::cout << "LISTENING" << std::endl;
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(seconds);
  while (std::chrono::steady_clock::now() < end) lcm_handle_timeout(lcm, 100);
  lcm_destroy(lcm);
  return 0;
}

int events(const std::string& instance, int seconds) {
  auto bus = ipc::EventBus::open(ipc::DEFAULT_EVENT_URL, instance);
  if (!bus) {
    std::cout << "ERROR " << bus.error().toString() << std::endl;
    return 2;
  }
  auto subscription =
      bus->onFault([](const ipc::FaultEvent& fault) { std::cout << "EVENT " << fault.name << std::endl; });
  if (!subscription) {
    std::cout << "ERROR " << subscription.error().toString() << std::endl;
    return 2;
  }
  std::cout << "LISTENING" << std::endl;
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(seconds);
  while (std::chrono::steady_clock::now() < end) bus->handle(std::chrono::milliseconds(100));
  return 0;
}

int fault(const std::string& address, const std::string& instance, const std::string& name, int count) {
  const ipc::FaultEvent forged{0, name, "vcu-fsm", ipc::FaultSeverity::Critical, true, "forged"};
  const std::vector<std::uint8_t> packet =
      demo::lcmDatagram(ipc::channelName(instance, ipc::EventKind::Fault), ipc::encodeFaultEvent(forged),
                        static_cast<std::uint32_t>(openvcu::clock::monotonicNs()));
  const int sent =
      demo::sendToLcmPort(address, count, [&](int) { return std::vector<std::vector<std::uint8_t>>{packet}; });
  if (sent < 0) return 2;
  std::cout << "SENT " << sent << std::endl;
  return sent > 0 ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  const std::vector<std::string> args(argv + 1, argv + argc);
  if (args.size() == 5 && args[0] == "fault") return fault(args[1], args[2], args[3], std::stoi(args[4]));
  if (args.size() == 3 && args[0] == "listen") return listen(args[1], std::stoi(args[2]));
  if (args.size() == 3 && args[0] == "events") return events(args[1], std::stoi(args[2]));
  std::cerr << "usage: forge_event fault ADDRESS INSTANCE NAME COUNT | listen INSTANCE SECONDS |"
               " events INSTANCE SECONDS\n";
  return 2;
}
