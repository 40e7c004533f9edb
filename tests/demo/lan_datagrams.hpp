#pragma once
// What a host on the VCU's LAN sends in security_test.sh (forge_command) and
// event_trust_test.sh (forge_event): hand-made LCM datagrams (LC02 header: one fragment) to
// the LCM port of an address, with TTL 1.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace openvcu::demo {

inline constexpr std::uint16_t LCM_PORT = 7667;
inline constexpr std::uint32_t LCM_SHORT_MAGIC = 0x4c433032;  // "LC02": one-fragment LCM message

/// One LCM datagram: magic, sequence number, channel, NUL, the encoded message.
inline std::vector<std::uint8_t> lcmDatagram(const std::string& channel, const std::vector<std::uint8_t>& payload,
                                             std::uint32_t sequence) {
  const std::uint32_t header[2] = {htonl(LCM_SHORT_MAGIC), htonl(sequence)};
  std::vector<std::uint8_t> packet(sizeof header + channel.size() + 1 + payload.size(), 0);
  std::memcpy(packet.data(), header, sizeof header);
  std::memcpy(packet.data() + sizeof header, channel.data(), channel.size());
  if (!payload.empty()) std::memcpy(packet.data() + sizeof header + channel.size() + 1, payload.data(), payload.size());
  return packet;
}

/// Sends `rounds` rounds to `address`:7667 with TTL 1, 20 ms apart; round i sends the
/// datagrams packetsOf(i) returns. The number of datagrams sent whole, or -1 when `address`
/// is not an IPv4 address.
template <typename PacketsOf>
int sendToLcmPort(const std::string& address, int rounds, PacketsOf packetsOf) {
  sockaddr_in target{};
  target.sin_family = AF_INET;
  target.sin_port = htons(LCM_PORT);
  if (::inet_pton(AF_INET, address.c_str(), &target.sin_addr) != 1) return -1;
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  const int ttl = 1;
  ::setsockopt(fd, IPPROTO_IP, IP_MULTICAST_TTL, &ttl, sizeof ttl);
  int sent = 0;
  for (int i = 0; i < rounds; ++i) {
    for (const std::vector<std::uint8_t>& packet : packetsOf(i)) {
      if (::sendto(fd, packet.data(), packet.size(), 0, reinterpret_cast<const sockaddr*>(&target), sizeof target) ==
          static_cast<ssize_t>(packet.size())) {
        ++sent;
      }
    }
    ::usleep(20'000);
  }
  ::close(fd);
  return sent;
}

}  // namespace openvcu::demo
