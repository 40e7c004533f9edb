#pragma once
// Frames the ecu-sim tests send to the simulated vehicle: a DBC message from its initial
// payload with some signals encoded, and the J1939-76 safety header (SHM) heading an SDM.

#include <doctest/doctest.h>

#include <algorithm>
#include <map>
#include <span>
#include <string>

#include "openvcu/can/frame.hpp"
#include "openvcu/dbc/codec.hpp"
#include "openvcu/dbc/model.hpp"
#include "openvcu/j1939/safety.hpp"

namespace openvcu::ecusim::test {

/// The frame of DBC message `name` from its initial payload with `values` encoded.
inline can::Frame encodedFrame(const dbc::Database& database, const dbc::DatabaseCodec& codecs, const std::string& name,
                               const std::map<std::string, double>& values) {
  const dbc::Message* message = database.findMessage(name);
  REQUIRE_MESSAGE(message, name);
  const auto index = static_cast<std::size_t>(message - database.messages.data());
  can::Frame out;
  out.id = message->id;
  out.flags = message->extended ? can::FLAG_EXTENDED : 0;
  const auto initial = codecs[index].initialPayload();
  out.length = static_cast<std::uint8_t>(initial.size());
  std::copy(initial.begin(), initial.end(), out.data.begin());
  for (const auto& [signal, value] : values) {
    const auto* found = message->findSignal(signal);
    REQUIRE_MESSAGE(found, signal);
    const auto signalIndex = static_cast<std::uint32_t>(found - message->signals.data());
    REQUIRE(codecs[index].encode(signalIndex, value, std::span<std::uint8_t>(out.data.data(), out.length)) ==
            dbc::EncodeStatus::Ok);
  }
  return out;
}

/// The next SHM of `builder`'s pair for the SDM `data` (its sequence number advances).
inline can::Frame safetyHeaderFor(j1939::SafetyPairBuilder& builder, const can::Frame& data) {
  const auto header = builder.nextHeader(j1939::SafetyDataView(data.data.data(), 8));
  can::Frame shm;
  shm.id = builder.headerCanId();
  shm.flags = can::FLAG_EXTENDED;
  shm.length = 8;
  std::copy(header.begin(), header.end(), shm.data.begin());
  return shm;
}

}  // namespace openvcu::ecusim::test
