#pragma once
// The "j1939" object of a bus in vehicle.json: this VCU's J1939-81 NAME on that bus, the
// address it claims first and the range it may move to (docs/config.md, "buses[].j1939";
// design note docs/design/j1939-address-claim.md).
//
//   "j1939": {"name": {"identityNumber": 1, "manufacturerCode": 0, "function": 128,
//                      "vehicleSystem": 1, "industryGroup": 3, "arbitraryAddressCapable": true},
//             "preferredAddress": 33, "addressRange": [128, 247]}
//   -> BusJ1939{NAME 0xB002800000000001, preferred 0x21, range 0x80..0xF7, claim}

#include "openvcu/j1939/address_claim.hpp"
#include "openvcu/j1939/name.hpp"

#include <cstdint>

namespace openvcu::config {

struct BusJ1939 {
  j1939::Name name;                  ///< every field within its width (checked at load)
  std::uint8_t preferredAddress{};   ///< 0..253; default: the node's DBC NmStationAddress
  std::uint8_t rangeFirst{j1939::DEFAULT_CLAIM_RANGE_FIRST};  ///< <= rangeLast, 0..253
  std::uint8_t rangeLast{j1939::DEFAULT_CLAIM_RANGE_LAST};
  bool claim{true};                  ///< false: the NAME is configured, no claim is sent

  /// The address claimer's settings for this bus.
  [[nodiscard]] j1939::AddressClaimerConfig claimerConfig() const noexcept {
    return j1939::AddressClaimerConfig{name, preferredAddress, rangeFirst, rangeLast};
  }
};

}  // namespace openvcu::config
