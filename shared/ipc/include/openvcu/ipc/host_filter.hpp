#pragma once
// "From this host only", enforced by the kernel on a receiving datagram socket: what
// EventBus attaches to LCM's udpm sockets so that no event from another host reaches a
// consumer (docs/design/ipc.md, "Events come from this host").
//
//   const auto known = ipc::openSocketInodes();        // before the library makes its sockets
//   ... lcm_create(url); lcm_get_fileno(lcm); ...       // the library binds and joins
//   auto restricted = ipc::restrictNewUdpSockets(*known, 7667);  // -> 1 socket filtered
//   if (!restricted) { std::cerr << restricted.error().toString() << '\n'; return 1; }
//
// The filter (classic BPF, SO_ATTACH_FILTER) accepts a datagram when it came in on the
// loopback interface (ifindex 1 in every network namespace) or is this host's own
// multicast looped back to it (packet type PACKET_LOOPBACK, whatever interface the group
// is routed through); it drops everything else: multicast from the LAN (any TTL), unicast
// to one of the host's addresses from another host.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "openvcu/core/result.hpp"

namespace openvcu::ipc {

/// Attaches the this-host-only filter to the datagram socket `fd` (replacing any filter
/// it had). Datagrams already queued on the socket are not filtered: attach before
/// anything reads, or drain afterwards (EventBus does).
/// @note thread-safe (one system call); not for per-frame paths.
Status acceptOnlyFromThisHost(int fd);

/// true when `fd` carries exactly the filter acceptOnlyFromThisHost attaches.
[[nodiscard]] bool acceptsOnlyFromThisHost(int fd) noexcept;

/// The inode numbers of this process's open sockets, sorted (from /proc/self/fd).
/// Error when /proc/self/fd cannot be read.
Result<std::vector<std::uint64_t>> openSocketInodes();

/// Attaches the filter to every IPv4 UDP socket of this process that is new (its inode is
/// not in `known`, sorted, from openSocketInodes) and set up as LCM's udpm receive socket
/// is: SO_REUSEADDR on and bound to `port` (0: to any port). Other new sockets (LCM's send
/// socket, a resolver's query socket opened by another thread meanwhile) are left alone.
/// Returns how many sockets got the filter; an Error when one could not be filtered or
/// when there is none (then the receive socket was not found).
/// Example: known = sockets before lcm_create("udpm://239.255.76.67:7667?ttl=0") and
/// lcm_get_fileno, port 7667 -> 1 (the receive socket, bound to 0.0.0.0:7667).
Result<std::size_t> restrictNewUdpSockets(const std::vector<std::uint64_t>& known, std::uint16_t port);

}  // namespace openvcu::ipc
