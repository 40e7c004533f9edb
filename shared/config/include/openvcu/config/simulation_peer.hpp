#pragma once
// The optional "j1939Peer" of simulation.json: one scripted J1939 node vcu-ecu-sim plays on
// a bus besides the DBC's nodes (services/ecu-sim/README.md, "The scripted J1939 peer").
//
//   "j1939Peer": {"bus": "vehicle", "address": 249,
//                 "name": {"identityNumber": 7, "manufacturerCode": 0, "function": 128,
//                          "vehicleSystem": 1, "industryGroup": 3, "arbitraryAddressCapable": false},
//                 "script": [{"atMs": 2000, "request": 65226, "to": "vcu"},
//                            {"atMs": 3000, "claim": 33}]}
//   -> SimPeerConfig{bus 0, address 0xF9, 2 steps in time order}

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "openvcu/j1939/name.hpp"

namespace openvcu::config {

struct SimPeerStep {
  enum class Kind : std::uint8_t {
    Claim,    ///< an Address Claimed for `address` with the peer's NAME
    Request,  ///< a Request for `pgn` from the peer's current address to `to` (or the VCU)
  };
  std::int64_t atNs{};  ///< after the simulation's start
  Kind kind{Kind::Request};
  std::uint8_t address{};  ///< Claim: the address claimed
  std::uint32_t pgn{};     ///< Request: the requested PGN
  std::uint8_t to{};       ///< Request: the destination (255: global) unless toVcu
  bool toVcu{};            ///< Request: the VCU's address as the peer last saw it claimed
};

struct SimPeerConfig {
  std::string bus;                           ///< a bus of vehicle.json that has a "j1939" object
  std::size_t busIndex{};                    ///< into VehicleConfig::buses
  std::uint8_t address{};                    ///< claimed at the start, 0..253
  j1939::Name name;                          ///< the peer's NAME
  j1939::Name vcuName;                       ///< the VCU's NAME on that bus (its "j1939" object)
  std::vector<SimPeerStep> script;           ///< sorted by atNs (file order among equal times)
  std::vector<std::uint32_t> requestedPgns;  ///< each PGN the script requests, once, in file order
};

}  // namespace openvcu::config
