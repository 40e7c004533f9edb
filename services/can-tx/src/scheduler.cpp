#include "scheduler.hpp"

#include <algorithm>
#include <climits>
#include <cmath>

#include "openvcu/bridge/message_binding.hpp"
#include "openvcu/config/catalog.hpp"
#include "openvcu/j1939/acknowledgement.hpp"
#include "openvcu/j1939/computed_fields.hpp"
#include "openvcu/j1939/id.hpp"
#include "openvcu/j1939/safety.hpp"
#include "openvcu/j1939/time_date.hpp"

namespace openvcu::cantx {
namespace {

using Payload = std::array<std::uint8_t, can::MAX_DATA_LENGTH>;

constexpr std::int64_t NEVER = INT64_MAX;

/// Frames held back at once at most (Impl::emit); HHEA holds one (PropA_C4) per S1_ES pair.
constexpr std::size_t HELD_CAPACITY = 64;

/// The counters a frame's fate goes to when it finally leaves (either may be null).
struct Outcome {
  std::atomic<std::uint64_t>* sent{};
  std::atomic<std::uint64_t>* failed{};
};
struct HeldFrame {
  std::size_t bus{};
  can::Frame frame{};
  Outcome outcome{};
};
enum class Emitted : std::uint8_t { Sent, Held, Failed };

}  // namespace

// ---- Scheduler ------------------------------------------------------------------------------

struct FieldState {
  ComputedField config;
  Payload mask{};                             ///< the field's own bits
  j1939::RollingCounter counter{0, 0};        ///< Counter: the next value
};

struct ScheduledEntry {
  ScheduledMessage config;
  const bridge::MessageBinding* binding{};  ///< the message's codec and table slots
  const dbc::MessageCodec* codec{};
  std::uint32_t length{};
  std::uint8_t sourceAddress{};
  std::vector<FieldState> fields;
  /// Per DBC signal: the effective command it was last sent with (kept through table damage).
  std::vector<std::optional<double>> commanded;
  std::optional<j1939::SafetyPairBuilder> pair;
  std::optional<std::size_t> headerMessage;  ///< the DBC message describing the SHM, if any
  std::size_t index{};                       ///< its place in the schedule (Scheduler's `scheduled`)
  std::int64_t nextNs{NEVER};                ///< next cyclic deadline
  std::int64_t nextCheckNs{NEVER};           ///< next on-change check
  std::int64_t lastCyclicSendNs{};
  bool consecutive{};                        ///< the previous cycle was sent: measure the period
  bool sdmPending{};
  std::int64_t sdmDueNs{NEVER};
  std::int64_t shmSentNs{};
  Payload sdm{};
  Payload last{};
  bool hasLast{};
  MessageStats stats;
};

struct Scheduler::Impl {
  const config::VehicleConfig& vehicle;
  signals::SignalTable& table;
  TxPort& port;
  Clock& clock;
  bridge::DatabaseBinding bindings;  ///< per DBC message: codec, table slots and ranges
  std::vector<SendGroup> groups;
  std::vector<std::optional<double>> groupCommanded;  ///< per group: its signal's last effective command
  std::uint64_t seenDamage{};   ///< table.damageCount() when the last grace window started
  std::int64_t graceUntilNs{};  ///< CLOCK_MONOTONIC end of that window
  std::size_t room{};  ///< entries' reserved capacity: add() never reallocates
  std::vector<PreparedMessage> entries;  // pointers: atomics are not movable; reserved at create()
  SchedulerCounters counters;
  /// `entries` in the order a burst of due messages goes out: shortest cycle first, then the
  /// schedule's order (on-change-only messages last). With harmonic cycles a message then has
  /// the same messages before it in every burst it is in, so a slot shared with longer
  /// cycles does not shift its period (room reserved at create()).
  std::vector<ScheduledEntry*> sendOrder;
  /// The J1939-76 pairs among `entries` (room for every entry reserved at create()).
  std::vector<ScheduledEntry*> pairs;
  /// Frames waiting for a pending SDM of their PGN, SA and DA (emit()); fixed room, no allocation.
  std::array<HeldFrame, HELD_CAPACITY> held{};
  std::size_t heldCount{};
  std::uint8_t ownAddress{j1939::NULL_ADDRESS};
  std::optional<std::size_t> timeDateMessage;  ///< DBC message with PGN 65254 this node sends
  std::int8_t localHourOffset{};
  std::int8_t localMinuteOffset{};

  Impl(const config::VehicleConfig& v, const signals::Catalog& c, signals::SignalTable& t, TxPort& p, Clock& k)
      : vehicle(v), table(t), port(p), clock(k), bindings(v.database, c) {}

  // ---- building frames ------------------------------------------------------------------

  /// The state of one scheduled message (allocates; reads only the configuration).
  Result<PreparedMessage> build(const ScheduledMessage& config) const {
    PreparedMessage entry(new ScheduledEntry());
    entry->config = config;
    entry->binding = &bindings[config.message];
    entry->codec = &entry->binding->codec();
    entry->length = entry->codec->length();
    if (entry->length > can::MAX_DATA_LENGTH) {
      return Error{"message '" + vehicle.database.messages[config.message].name + "' is " +
                   std::to_string(entry->length) + " bytes: longer than a CAN frame (transport protocol sending is "
                   "not supported)"};
    }
    entry->sourceAddress = config.extended ? j1939::Id::fromCanId(config.canId).sourceAddress : 0;
    entry->commanded.assign(entry->binding->signalCount(), std::nullopt);
    for (const ComputedField& field : config.computed) {
      FieldState state;
      state.config = field;
      state.counter = j1939::RollingCounter(field.start, field.modulo);
      dbc::DecodedValue ones;
      ones.kind = dbc::RawKind::Unsigned;
      ones.rawUnsigned = ~std::uint64_t{0};
      const std::uint32_t bits = vehicle.database.messages[config.message].signals[field.signal].size;
      ones.rawUnsigned = bits >= 64 ? ones.rawUnsigned : (std::uint64_t{1} << bits) - 1;
      (void)entry->codec->encodeRaw(field.signal, ones, std::span<std::uint8_t>(state.mask.data(), entry->length));
      entry->fields.push_back(state);
    }
    if (config.safetyDeltaNs) {
      entry->pair.emplace(config.canId, 0);
      const std::uint32_t header = entry->pair->headerCanId();
      for (std::size_t m = 0; m < vehicle.database.messages.size(); ++m) {
        const dbc::Message& candidate = vehicle.database.messages[m];
        if (candidate.extended && (candidate.id & 0x03FFFFFFu) == (header & 0x03FFFFFFu)) {
          entry->headerMessage = m;
          break;
        }
      }
    }
    return entry;
  }

  /// A command that was seen and now reads as never written: the table lost its values
  /// (update counters go back only then). True while it is kept (TABLE_DAMAGE_GRACE_NS from
  /// when this process learnt of the damage); after that it is forgotten and the default
  /// applies. Called only on that rare path, so the damage check costs nothing per frame.
  bool keepAfterWipe(std::optional<double>& last) noexcept {
    if (!last) return false;
    const std::int64_t now = clock.monotonicNs();
    if (const std::uint64_t damage = table.damageCount(); damage != seenDamage) {
      seenDamage = damage;
      graceUntilNs = now + TABLE_DAMAGE_GRACE_NS;
    }
    if (now < graceUntilNs) return true;
    last.reset();
    return false;
  }

  /// The effective command of `key` (override, else command), remembered in `last`; while
  /// the table's values are lost, `last`.
  std::optional<double> commandOf(signals::SignalIndex key, std::optional<double>& last) noexcept {
    const auto snapshot = table.read(key);
    if (!snapshot) return last;  // a write in progress: the previous command
    if (const auto effective = signals::effectiveCommand(*snapshot)) {
      last = effective->value;
      return last;
    }
    if (keepAfterWipe(last)) return last;
    return std::nullopt;
  }

  bool groupOn(const ScheduledEntry& entry) noexcept {
    if (!entry.config.group) return true;
    const std::size_t g = *entry.config.group;
    return commandOf(groups[g].signal, groupCommanded[g]).value_or(groups[g].initial) != 0.0;
  }

  void build(ScheduledEntry& entry, Payload& payload) noexcept {
    const auto initial = entry.codec->initialPayload();
    std::copy(initial.begin(), initial.end(), payload.begin());
    const std::span<std::uint8_t> buffer(payload.data(), entry.length);
    // multiplexed signals are skipped by the binding (docs/design/can-tx.md)
    const bridge::EncodeResult result =
        entry.binding->encodeFrom(buffer, [&](std::uint32_t s, std::optional<signals::SignalIndex> slot) noexcept {
          std::optional<double> value = entry.config.defaults[s];
          if (slot) {
            if (const auto command = commandOf(*slot, entry.commanded[s])) value = command;
          }
          return value;
        });
    if (result.errors > 0) {
      entry.stats.encodeErrors.store(entry.stats.encodeErrors.load(std::memory_order_relaxed) + result.errors,
                                     std::memory_order_relaxed);
    }
  }

  void compute(ScheduledEntry& entry, Payload& payload) noexcept {
    const std::span<std::uint8_t> buffer(payload.data(), entry.length);
    for (FieldState& field : entry.fields) {
      for (std::uint32_t b = 0; b < entry.length; ++b) payload[b] = static_cast<std::uint8_t>(payload[b] & ~field.mask[b]);
      std::uint64_t value = 0;
      switch (field.config.algorithm) {
        case FieldAlgorithm::Counter:
          value = field.counter.next();
          break;
        case FieldAlgorithm::Sum8:
        case FieldAlgorithm::Xor8:
        case FieldAlgorithm::Crc8SaeJ1850: {
          // the covered bytes: every byte that is not all field
          Payload covered;
          std::size_t count = 0;
          for (std::uint32_t b = 0; b < entry.length; ++b) {
            if (field.mask[b] != 0xFF) covered[count++] = payload[b];
          }
          const std::span<const std::uint8_t> bytes(covered.data(), count);
          if (field.config.algorithm == FieldAlgorithm::Sum8) value = j1939::sum8(bytes);
          if (field.config.algorithm == FieldAlgorithm::Xor8) value = j1939::xor8(bytes);
          if (field.config.algorithm == FieldAlgorithm::Crc8SaeJ1850) value = j1939::crc8SaeJ1850(bytes);
          break;
        }
        case FieldAlgorithm::J1939Checksum4:
          value = j1939::j1939Checksum4(std::span<const std::uint8_t>(payload.data(), entry.length), entry.config.canId);
          break;
      }
      dbc::DecodedValue raw;
      raw.kind = dbc::RawKind::Unsigned;
      const std::uint32_t bits = vehicle.database.messages[entry.config.message].signals[field.config.signal].size;
      raw.rawUnsigned = bits >= 64 ? value : value & ((std::uint64_t{1} << bits) - 1);
      (void)entry.codec->encodeRaw(field.config.signal, raw, buffer);
    }
  }

  can::Frame frameOf(std::uint32_t id, bool extended, std::span<const std::uint8_t> payload) const noexcept {
    can::Frame frame;
    frame.id = id;
    frame.flags = extended ? can::FLAG_EXTENDED : 0;
    if (payload.size() > 8) frame.flags = static_cast<std::uint8_t>(frame.flags | can::FLAG_FD | can::FLAG_BRS);
    frame.length = static_cast<std::uint8_t>(payload.size());
    std::copy(payload.begin(), payload.end(), frame.data.begin());
    return frame;
  }

  /// Writes what went out to the bus plane of DBC message `messageIndex`'s slots (Valid).
  void record(std::size_t messageIndex, std::span<const std::uint8_t> payload, std::uint8_t source,
              std::int64_t nowNs) noexcept {
    (void)bindings[messageIndex].decodeInto(table, payload, nowNs, source, bridge::RangeCheck::None);
  }

  static void increment(std::atomic<std::uint64_t>& counter) noexcept {
    counter.store(counter.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
  }

  // ---- the J1939-76 ordering rule -------------------------------------------------------
  // A J1939-76 receiver takes the first frame with the PGN, SA and DA its SHM names as the
  // SDM (j1939::sameSafetyIdentity; the priority is not compared). So between an SHM and its
  // SDM nothing else with those three may go out on that bus. Every frame other than a pair's
  // own SHM and SDM reaches the port through emit(), which holds such a frame until the SDM
  // has gone out; an SHM first sends any pending SDM of its identity (sendHeader()).

  /// The pair whose pending SDM a J1939-76 receiver would confuse `frame` with, or nullptr.
  ScheduledEntry* pendingLike(std::size_t bus, std::uint32_t canId, bool extended) const noexcept {
    if (!extended) return nullptr;  // J1939 (and so J1939-76) identifiers are 29-bit
    for (ScheduledEntry* pair : pairs) {
      if (pair->sdmPending && pair->config.bus == bus && j1939::sameSafetyIdentity(pair->config.canId, canId)) {
        return pair;
      }
    }
    return nullptr;
  }

  Emitted deliver(std::size_t bus, const can::Frame& frame, Outcome outcome) noexcept {
    const bool sent = port.send(bus, frame) == can::SendStatus::Sent;
    if (std::atomic<std::uint64_t>* counter = sent ? outcome.sent : outcome.failed) increment(*counter);
    return sent ? Emitted::Sent : Emitted::Failed;
  }

  /// Sends `frame` now, or holds it while a pending SDM has its PGN, SA and DA (it then goes
  /// out right after that SDM, in the order held). When the hold is full the SDM goes out at
  /// once, before its delta, and the frame after it: never between SHM and SDM, never lost.
  Emitted emit(std::size_t bus, const can::Frame& frame, Outcome outcome) noexcept {
    while (ScheduledEntry* pair = pendingLike(bus, frame.id, frame.extended())) {
      if (heldCount < held.size()) {
        held[heldCount++] = HeldFrame{bus, frame, outcome};
        increment(counters.held);
        return Emitted::Held;
      }
      increment(counters.sdmsEarly);
      sendData(*pair);
    }
    return deliver(bus, frame, outcome);
  }

  /// After an SDM went out: sends the held frames no pending SDM blocks any more, in order.
  void releaseHeld() noexcept {
    std::size_t kept = 0;
    for (std::size_t i = 0; i < heldCount; ++i) {
      const HeldFrame& item = held[i];
      if (pendingLike(item.bus, item.frame.id, item.frame.extended()) != nullptr) {
        held[kept++] = item;
      } else {
        (void)deliver(item.bus, item.frame, item.outcome);
      }
    }
    heldCount = kept;
  }

  /// Builds and sends one instance of the message (its SHM when it is a safety SDM).
  void transmit(ScheduledEntry& entry, Payload& payload) noexcept {
    const std::span<const std::uint8_t> bytes(payload.data(), entry.length);
    if (entry.pair) {
      sendHeader(entry, payload);
      return;
    }
    const std::int64_t now = clock.monotonicNs();
    (void)emit(entry.config.bus, frameOf(entry.config.canId, entry.config.extended, bytes),
               Outcome{nullptr, &entry.stats.sendFailures});
    increment(entry.stats.frames);
    record(entry.config.message, bytes, entry.sourceAddress, now);
  }

  /// The SHM of a pair; its SDM (`payload`) becomes pending, due deltaNs after the SHM.
  void sendHeader(ScheduledEntry& entry, const Payload& payload) noexcept {
    // One pending SDM per PGN, SA and DA: an earlier pair's SDM, this message's own or
    // another's with the same identity, goes out first (never leave an SHM without its SDM).
    for (ScheduledEntry* pair : pairs) {
      if (pair->sdmPending && pair->config.bus == entry.config.bus &&
          j1939::sameSafetyIdentity(pair->config.canId, entry.config.canId)) {
        sendData(*pair);
      }
    }
    const j1939::SafetyPayload header =
        entry.pair->nextHeader(j1939::SafetyDataView(payload.data(), j1939::SAFETY_MESSAGE_LENGTH));
    if (port.send(entry.config.bus, frameOf(entry.pair->headerCanId(), true, header)) != can::SendStatus::Sent) {
      increment(entry.stats.sendFailures);
    }
    const std::int64_t now = clock.monotonicNs();  // after the SHM left: the delta starts here
    if (entry.headerMessage) record(*entry.headerMessage, header, entry.sourceAddress, now);
    entry.sdm = payload;
    entry.sdmPending = true;
    entry.shmSentNs = now;
    entry.sdmDueNs = now + *entry.config.safetyDeltaNs;
  }

  /// The SDM of a pair whose SHM went out; then the frames it held back.
  void sendData(ScheduledEntry& entry) noexcept {
    const std::int64_t now = clock.monotonicNs();
    const std::span<const std::uint8_t> bytes(entry.sdm.data(), entry.length);
    if (port.send(entry.config.bus, frameOf(entry.config.canId, true, bytes)) != can::SendStatus::Sent) {
      increment(entry.stats.sendFailures);
    }
    increment(entry.stats.frames);
    entry.stats.deltaError.record(now - entry.shmSentNs - *entry.config.safetyDeltaNs);
    entry.sdmPending = false;
    entry.sdmDueNs = NEVER;
    record(entry.config.message, bytes, entry.sourceAddress, now);
    releaseHeld();
  }

  /// Sends every pending SDM due at `nowNs`.
  void sendDueData(std::int64_t nowNs) noexcept {
    for (ScheduledEntry* pair : pairs) {
      if (pair->sdmPending && pair->sdmDueNs <= nowNs) sendData(*pair);
    }
  }

  void cyclic(ScheduledEntry& entry, std::int64_t nowNs) noexcept {
    const std::int64_t cycle = entry.config.cycleNs;
    const std::int64_t late = nowNs - entry.nextNs;
    const std::int64_t skipped = late / cycle;  // whole cycles already past: not sent
    entry.nextNs += (skipped + 1) * cycle;
    if (!entry.config.enabled || !groupOn(entry)) {
      entry.consecutive = false;
      return;
    }
    if (skipped > 0) {
      entry.stats.missed.store(entry.stats.missed.load(std::memory_order_relaxed) + static_cast<std::uint64_t>(skipped),
                               std::memory_order_relaxed);
      entry.consecutive = false;
    }
    Payload payload;
    build(entry, payload);
    compute(entry, payload);
    const std::int64_t sendNs = clock.monotonicNs();
    if (entry.consecutive) entry.stats.periodError.record(sendNs - entry.lastCyclicSendNs - cycle);
    entry.lastCyclicSendNs = sendNs;
    entry.consecutive = true;
    transmit(entry, payload);
    entry.last = payload;
    entry.hasLast = true;
  }

  void changeCheck(ScheduledEntry& entry, std::int64_t nowNs) noexcept {
    const std::int64_t interval = entry.config.minIntervalNs;
    entry.nextCheckNs += ((nowNs - entry.nextCheckNs) / interval + 1) * interval;
    if (!entry.config.enabled || !groupOn(entry)) return;
    Payload payload;
    build(entry, payload);
    // compare before the computed fields: counters change every frame by design
    Payload previous = entry.last;
    if (entry.hasLast) {
      Payload masked = payload;
      for (const FieldState& field : entry.fields) {
        for (std::uint32_t b = 0; b < entry.length; ++b) {
          masked[b] = static_cast<std::uint8_t>(masked[b] & ~field.mask[b]);
          previous[b] = static_cast<std::uint8_t>(previous[b] & ~field.mask[b]);
        }
      }
      if (std::equal(masked.begin(), masked.begin() + entry.length, previous.begin())) return;
    }
    compute(entry, payload);
    transmit(entry, payload);
    entry.last = payload;
    entry.hasLast = true;
  }

  // ---- the order of a burst ---------------------------------------------------------------

  static bool sendsBefore(const ScheduledEntry& a, const ScheduledEntry& b) noexcept {
    const std::int64_t cycleA = a.config.cycleNs > 0 ? a.config.cycleNs : NEVER;
    const std::int64_t cycleB = b.config.cycleNs > 0 ? b.config.cycleNs : NEVER;
    return cycleA != cycleB ? cycleA < cycleB : a.index < b.index;
  }

  /// Puts `entry` (not in sendOrder) at its place; within the reserved room: no allocation.
  void placeInOrder(ScheduledEntry* entry) noexcept {
    const auto at = std::find_if(sendOrder.begin(), sendOrder.end(),
                                 [&](const ScheduledEntry* other) noexcept { return sendsBefore(*entry, *other); });
    sendOrder.insert(at, entry);
  }

  /// After `entry`'s cycle changed.
  void reorder(ScheduledEntry* entry) noexcept {
    if (const auto at = std::find(sendOrder.begin(), sendOrder.end(), entry); at != sendOrder.end()) {
      sendOrder.erase(at);
    }
    placeInOrder(entry);
  }
};

Result<std::unique_ptr<Scheduler>> Scheduler::create(const config::VehicleConfig& vehicle, const Schedule& schedule,
                                                     const signals::Catalog& catalog, signals::SignalTable& table,
                                                     TxPort& port, Clock& clock, std::int64_t startNs) {
  auto impl = std::make_unique<Impl>(vehicle, catalog, table, port, clock);
  impl->groups = schedule.groups;
  impl->groupCommanded.assign(impl->groups.size(), std::nullopt);
  impl->seenDamage = table.damageCount();
  impl->localHourOffset = schedule.localHourOffset;
  impl->localMinuteOffset = schedule.localMinuteOffset;
  for (const dbc::Node& node : vehicle.database.nodes) {
    if (node.name == vehicle.node) {
      if (auto address = config::nodeAddress(vehicle.database, node)) impl->ownAddress = *address;
    }
  }
  for (std::size_t m = 0; m < vehicle.database.messages.size(); ++m) {
    const dbc::Message& message = vehicle.database.messages[m];
    if (!message.extended || message.pseudo) continue;
    if (!config::sentBy(message, vehicle.node)) continue;
    if (j1939::pgnOf(message.id) == j1939::PGN_TIME_DATE && !impl->timeDateMessage) {
      impl->timeDateMessage = m;
    }
  }
  impl->room = std::max(vehicle.database.messages.size(), schedule.messages.size());
  impl->entries.reserve(impl->room);
  impl->sendOrder.reserve(impl->room);
  impl->pairs.reserve(impl->room);
  for (const ScheduledMessage& config : schedule.messages) {
    auto entry = impl->build(config);
    if (!entry) return entry.error();
    if (config.cycleNs > 0) (*entry)->nextNs = startNs + config.offsetNs;
    if (config.onChange) (*entry)->nextCheckNs = startNs + config.offsetNs;
    if ((*entry)->pair) impl->pairs.push_back(entry->get());
    (*entry)->index = impl->entries.size();
    impl->placeInOrder(entry->get());
    impl->entries.emplace_back(entry->release());
  }
  return std::unique_ptr<Scheduler>(new Scheduler(std::move(impl)));
}

Scheduler::Scheduler(std::unique_ptr<Impl> impl) noexcept : m_impl(std::move(impl)) {}
Scheduler::~Scheduler() = default;

void Scheduler::run(std::int64_t nowNs) noexcept {
  Impl& impl = *m_impl;
  // SDMs first: their deltas are the tightest deadlines.
  impl.sendDueData(nowNs);
  for (ScheduledEntry* entry : impl.sendOrder) {
    const bool cyclicDue = entry->config.cycleNs > 0 && entry->nextNs <= nowNs;
    const bool checkDue = entry->config.onChange && entry->nextCheckNs <= nowNs;
    if (!cyclicDue && !checkDue) continue;
    // an SDM that fell due while a burst of frames goes out leaves between two of them
    impl.sendDueData(impl.clock.monotonicNs());
    if (cyclicDue) impl.cyclic(*entry, nowNs);
    if (checkDue) impl.changeCheck(*entry, nowNs);
  }
}

std::int64_t Scheduler::nextDeadlineNs() const noexcept {
  std::int64_t next = NEVER;
  for (const auto& entry : m_impl->entries) {
    if (entry->sdmPending) next = std::min(next, entry->sdmDueNs);
    if (entry->config.cycleNs > 0) next = std::min(next, entry->nextNs);
    if (entry->config.onChange) next = std::min(next, entry->nextCheckNs);
  }
  return next;
}

std::int64_t Scheduler::nextDataDeadlineNs() const noexcept {
  std::int64_t next = NEVER;
  for (const ScheduledEntry* pair : m_impl->pairs) {
    if (pair->sdmPending) next = std::min(next, pair->sdmDueNs);
  }
  return next;
}

void Scheduler::setCycle(std::size_t scheduled, std::int64_t cycleNs, std::int64_t nowNs) noexcept {
  ScheduledEntry& entry = *m_impl->entries[scheduled];
  const std::int64_t previous = entry.config.cycleNs;
  entry.config.cycleNs = cycleNs;
  entry.consecutive = false;
  m_impl->reorder(&entry);
  if (cycleNs <= 0) {
    entry.nextNs = NEVER;
    return;
  }
  // keep the phase of the last deadline when there was one; otherwise start now
  const std::int64_t lastDue = previous > 0 ? entry.nextNs - previous : nowNs - cycleNs;
  entry.nextNs = std::max(nowNs, lastDue + cycleNs);
}

void Scheduler::setEnabled(std::size_t scheduled, bool enabled) noexcept {
  m_impl->entries[scheduled]->config.enabled = enabled;
}

void Scheduler::setDefault(std::size_t scheduled, std::uint32_t signal, double value) noexcept {
  ScheduledEntry& entry = *m_impl->entries[scheduled];
  if (signal < entry.config.defaults.size()) entry.config.defaults[signal] = value;
}

void Scheduler::sendOnce(std::size_t bus, const can::Frame& frame) noexcept {
  Impl& impl = *m_impl;
  (void)impl.emit(bus, frame, Outcome{&impl.counters.oneShots, &impl.counters.oneShotFailures});
}

void Scheduler::answerRequest(std::size_t bus, const j1939::Request& request) noexcept {
  Impl& impl = *m_impl;
  const std::uint32_t pgn = request.pgn;
  const std::int64_t now = impl.clock.monotonicNs();
  if (pgn == j1939::PGN_TIME_DATE) {
    const std::int64_t realtime = impl.clock.realtimeNs();
    const j1939::UtcInstant instant{realtime / 1'000'000'000, static_cast<std::uint32_t>(realtime % 1'000'000'000),
                                    impl.localMinuteOffset, impl.localHourOffset};
    if (const auto payload = j1939::encodeTimeDate(instant)) {
      const std::uint32_t id = impl.timeDateMessage
                                   ? impl.vehicle.database.messages[*impl.timeDateMessage].id
                                   : j1939::Id::fromPgn(j1939::PGN_TIME_DATE, 6, impl.ownAddress, j1939::GLOBAL_ADDRESS)
                                         .toCanId();
      if (impl.emit(bus, impl.frameOf(id, true, *payload), Outcome{&impl.counters.requestsAnswered, nullptr}) !=
          Emitted::Failed) {
        if (impl.timeDateMessage) impl.record(*impl.timeDateMessage, *payload, impl.ownAddress, now);
      }
      return;
    }
  }
  for (auto& entry : impl.entries) {
    if (entry->config.bus != bus || !entry->config.extended) continue;
    if (j1939::pgnOf(entry->config.canId) != pgn) continue;
    Payload payload;
    impl.build(*entry, payload);
    impl.compute(*entry, payload);
    impl.transmit(*entry, payload);
    impl.increment(impl.counters.requestsAnswered);
    return;
  }
  if (request.global) return;  // J1939-21: no NACK to a global request
  const j1939::AcknowledgementPayload nack = j1939::encodeAcknowledgement(
      j1939::Acknowledgement{j1939::AckControl::Negative, j1939::GROUP_FUNCTION_NOT_APPLICABLE, request.requester, pgn});
  const std::uint32_t id = j1939::acknowledgementCanId(j1939::ACKNOWLEDGEMENT_DEFAULT_PRIORITY, impl.ownAddress);
  (void)impl.emit(bus, impl.frameOf(id, true, nack), Outcome{&impl.counters.requestsNacked, nullptr});
}

void ScheduledEntryDeleter::operator()(ScheduledEntry* entry) const noexcept { delete entry; }

Result<PreparedMessage> Scheduler::prepare(const ScheduledMessage& message) const { return m_impl->build(message); }

const MessageStats& Scheduler::statsOf(const ScheduledEntry& entry) noexcept { return entry.stats; }

bool Scheduler::add(PreparedMessage& message, std::int64_t nowNs) noexcept {
  std::vector<PreparedMessage>& entries = m_impl->entries;
  if (!message || entries.size() >= m_impl->room) return false;
  if (message->config.cycleNs > 0) message->nextNs = nowNs;
  if (message->config.onChange) message->nextCheckNs = nowNs;
  if (message->pair) m_impl->pairs.push_back(message.get());  // reserved at create() as well
  message->index = entries.size();
  m_impl->placeInOrder(message.get());  // reserved at create() as well
  entries.push_back(std::move(message));  // within the reserved capacity: no allocation
  return true;
}

std::size_t Scheduler::capacity() const noexcept { return m_impl->room; }

const MessageStats& Scheduler::stats(std::size_t scheduled) const noexcept { return m_impl->entries[scheduled]->stats; }
const SchedulerCounters& Scheduler::counters() const noexcept { return m_impl->counters; }

}  // namespace openvcu::cantx
