#include "virtual_bus.hpp"

#include <algorithm>

#include "openvcu/config/catalog.hpp"

namespace openvcu::ecusim {

Result<VirtualBus> VirtualBus::create(const config::VehicleConfig& vehicle) {
  VirtualBus bus;
  bus.m_vehicle = &vehicle;
  bus.m_bindings = bridge::DatabaseBinding(vehicle.database);
  bus.m_txByMessage.assign(vehicle.database.messages.size(), -1);
  bus.m_rxByMessage.assign(vehicle.database.messages.size(), -1);
  for (std::size_t b = 0; b < vehicle.buses.size(); ++b) {
    for (const std::size_t index : vehicle.buses[b].messages) {
      const dbc::Message& message = vehicle.database.messages[index];
      if (message.pseudo || message.length > can::MAX_DATA_LENGTH) continue;
      if (config::sentBy(message, vehicle.node)) {
        Rx rx;
        rx.messageIndex = index;
        rx.id = message.id;
        rx.extended = message.extended;
        rx.values.assign(message.signals.size(), std::numeric_limits<double>::quiet_NaN());
        if (bus.m_rxByMessage[index] < 0) bus.m_rxByMessage[index] = static_cast<std::int32_t>(bus.m_rx.size());
        bus.m_rx.push_back(std::move(rx));
        continue;
      }
      Tx tx;
      tx.messageIndex = index;
      tx.bus = b;
      tx.node = message.transmitter;
      tx.frame.id = message.id;
      tx.frame.flags = message.extended ? can::FLAG_EXTENDED : 0;
      const auto initial = bus.m_bindings[index].codec().initialPayload();
      tx.frame.length = static_cast<std::uint8_t>(std::min<std::size_t>(initial.size(), can::MAX_DATA_LENGTH));
      std::copy_n(initial.begin(), tx.frame.length, tx.frame.data.begin());
      tx.cycleNs = message.cycleTimeMs ? static_cast<std::int64_t>(*message.cycleTimeMs) * 1'000'000 : 0;
      if (bus.m_txByMessage[index] < 0) bus.m_txByMessage[index] = static_cast<std::int32_t>(bus.m_tx.size());
      bus.m_tx.push_back(std::move(tx));
    }
  }
  return bus;
}

Result<bridge::SignalRef> VirtualBus::output(const std::string& message, const std::string& signal) const {
  for (const Tx& tx : m_tx) {
    const bridge::MessageBinding& binding = m_bindings[tx.messageIndex];
    if (binding.message().name != message) continue;
    if (const auto maybeSignal = binding.signalIndex(signal)) return bridge::SignalRef{tx.messageIndex, *maybeSignal};
    return Error{"message " + message + " has no signal " + signal};
  }
  return Error{"no simulated node transmits a message " + message + " on a configured bus"};
}

Result<std::size_t> VirtualBus::outputMessage(const std::string& name) const {
  for (std::size_t i = 0; i < m_tx.size(); ++i) {
    if (m_vehicle->database.messages[m_tx[i].messageIndex].name == name) return i;
  }
  return Error{"no simulated node transmits a message " + name + " on a configured bus"};
}

Result<bridge::SignalRef> VirtualBus::input(const std::string& message, const std::string& signal) const {
  for (const Rx& rx : m_rx) {
    const bridge::MessageBinding& binding = m_bindings[rx.messageIndex];
    if (binding.message().name != message) continue;
    if (const auto maybeSignal = binding.signalIndex(signal)) return bridge::SignalRef{rx.messageIndex, *maybeSignal};
    return Error{"message " + message + " has no signal " + signal};
  }
  return Error{"the VCU (" + m_vehicle->node + ") transmits no message " + message + " on a configured bus"};
}

void VirtualBus::set(bridge::SignalRef ref, double value) noexcept {
  if (ref.message >= m_txByMessage.size() || m_txByMessage[ref.message] < 0) return;
  Tx& tx = m_tx[static_cast<std::size_t>(m_txByMessage[ref.message])];
  (void)m_bindings[ref.message].encodeClamped(ref.signal, value,
                                              std::span<std::uint8_t>(tx.frame.data.data(), tx.frame.length));
}

double VirtualBus::current(bridge::SignalRef ref) const noexcept {
  if (!isOutput(ref)) return std::numeric_limits<double>::quiet_NaN();
  const Tx& tx = m_tx[static_cast<std::size_t>(m_txByMessage[ref.message])];
  const auto value = m_bindings[ref.message].value(ref.signal, tx.frame.payload());
  return value ? *value : std::numeric_limits<double>::quiet_NaN();
}

bool VirtualBus::receive(const can::Frame& frame, std::int64_t atNs) noexcept {
  for (Rx& rx : m_rx) {
    if (rx.id != frame.id || rx.extended != frame.extended()) continue;
    (void)m_bindings[rx.messageIndex].decodeValues(frame.payload(), rx.values);
    rx.lastNs = atNs;
    ++m_received;
    return true;
  }
  return false;
}

std::int64_t VirtualBus::nextDueNs() const noexcept {
  std::int64_t next = NEVER;
  for (const Tx& tx : m_tx) {
    if (tx.cycleNs > 0) next = std::min(next, tx.nextNs);
  }
  return next;
}

void VirtualBus::start(std::int64_t nowNs) noexcept {
  // Each node sends its messages from one task, as an ECU does: a node's messages share a
  // phase, and the nodes are 1 ms apart in the order they first appear.
  std::size_t phases = 0;
  for (std::size_t i = 0; i < m_tx.size(); ++i) {
    Tx& tx = m_tx[i];
    if (tx.cycleNs <= 0) continue;
    std::size_t phase = phases;
    for (std::size_t j = 0; j < i; ++j) {
      if (m_tx[j].cycleNs > 0 && m_tx[j].node == tx.node) {
        phase = m_tx[j].phase;
        break;
      }
    }
    if (phase == phases) ++phases;
    tx.phase = phase;
    tx.nextNs = nowNs + (static_cast<std::int64_t>(phase) * 1'000'000) % tx.cycleNs;
  }
}

bool VirtualBus::setSilent(const std::string& node, bool silent) {
  bool found = false;
  for (Tx& tx : m_tx) {
    if (tx.node != node) continue;
    tx.silent = silent;
    found = true;
  }
  return found;
}

std::vector<std::string> VirtualBus::nodes() const {
  std::vector<std::string> names;
  for (const Tx& tx : m_tx) {
    if (std::find(names.begin(), names.end(), tx.node) == names.end()) names.push_back(tx.node);
  }
  return names;
}

std::vector<FrameTarget> VirtualBus::transmitted(const std::string& messageOrNode) const {
  std::vector<FrameTarget> targets;
  for (const Tx& tx : m_tx) {
    if (tx.node != messageOrNode && m_vehicle->database.messages[tx.messageIndex].name != messageOrNode) continue;
    targets.push_back(FrameTarget{tx.bus, tx.frame.id, tx.frame.extended()});
  }
  return targets;
}

}  // namespace openvcu::ecusim
