#include "openvcu/core/clock.hpp"
#include "openvcu/signals/table.hpp"

#include <signal.h>
#include <sys/mman.h>
#include <unistd.h>

#include <atomic>
#include <bit>
#include <cerrno>
#include <new>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "fault_guard.hpp"
#include "layout.hpp"
#include "notifier.hpp"
#include "segment.hpp"

namespace openvcu::signals {

namespace {

constexpr std::size_t MAX_INSTANCE_NAME = 64;
constexpr int MAX_OPEN_ATTEMPTS = 100;  // rounds of "somebody else is creating it right now"
constexpr useconds_t OPEN_RETRY_US = 1000;

constexpr mode_t OWNER_ONLY_MODE = 0600;
constexpr mode_t OWNER_AND_GROUP_MODE = 0660;

// Aux word layouts (32 bits each): bus = source | quality << 16; command = writer;
// override = writer | active << 16.
constexpr unsigned QUALITY_SHIFT = 16;
constexpr unsigned ACTIVE_SHIFT = 16;
constexpr std::uint32_t LOW_16_BITS = 0xFFFF;

constexpr std::uint32_t busAux(std::uint16_t source, Quality quality) noexcept {
  return std::uint32_t{source} | std::uint32_t{static_cast<std::uint8_t>(quality)} << QUALITY_SHIFT;
}
constexpr std::uint32_t overrideAux(WriterId writer, bool active) noexcept {
  return std::uint32_t{writer} | (active ? 1u << ACTIVE_SHIFT : 0u);
}

detail::Payload payload(double value, std::int64_t timestampNs, std::uint32_t aux) noexcept {
  return {std::bit_cast<std::uint64_t>(value), timestampNs, aux};
}

bool isInstanceCharacter(char c) noexcept {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' || c == '_';
}

}  // namespace

std::string_view qualityName(Quality quality) noexcept {
  switch (quality) {
    case Quality::NeverReceived:
      return "NeverReceived";
    case Quality::Valid:
      return "Valid";
    case Quality::Stale:
      return "Stale";
    case Quality::OutOfRange:
      return "OutOfRange";
  }
  return "?";
}

std::optional<EffectiveCommand> effectiveCommand(const SlotSnapshot& snapshot) noexcept {
  if (snapshot.override.active) {
    return EffectiveCommand{snapshot.override.value, snapshot.override.timestampNs, snapshot.override.writer, true};
  }
  if (snapshot.command.updates == 0) return std::nullopt;
  return EffectiveCommand{snapshot.command.value, snapshot.command.timestampNs, snapshot.command.writer, false};
}

// ---- opening ----------------------------------------------------------------------------

Status SignalTable::checkInstanceName(std::string_view instance) {
  bool valid = !instance.empty() && instance.size() <= MAX_INSTANCE_NAME;
  for (const char c : instance) valid = valid && isInstanceCharacter(c);
  if (valid) return {};
  return Error{"invalid instance name '" + std::string(instance) + "': use 1 to " + std::to_string(MAX_INSTANCE_NAME) +
               " letters, digits, '-' or '_'"};
}

std::string SignalTable::segmentPath(std::string_view instance) {
  return detail::namesFor(instance).segmentPath;
}

std::string SignalTable::lockPath(std::string_view instance) {
  return detail::namesFor(instance).lockPath;
}

Status SignalTable::remove(std::string_view instance) {
  if (auto nameStatus = checkInstanceName(instance); !nameStatus) return nameStatus;
  return detail::unlinkNames(detail::namesFor(instance));
}

// The protocol (docs/design/signal-table.md, "Creation and attachment"):
//   1. LOCK_SH on the lock file (waits only while a creator holds LOCK_EX).
//   2. Open and check the segment. Ready: attach, keeping LOCK_SH for our lifetime.
//   3. Missing, incomplete or of another configuration: try LOCK_EX | LOCK_NB. It succeeds
//      only when no other process is attached or checking; then (re-)create the table,
//      drop the lock and go back to 1 to attach like everybody else. When it fails,
//      a mismatch is refused and anything else retried (another process is creating it).
Result<SignalTable> SignalTable::open(const Catalog& catalog, std::string_view instance, OpenMode mode,
                                      Permissions permissions) {
  if (auto nameStatus = checkInstanceName(instance); !nameStatus) return nameStatus.error();
  const detail::Names names = detail::namesFor(instance);
  const detail::Expected expected{catalog.layoutHash(), static_cast<std::uint32_t>(catalog.size())};
  const mode_t fileMode = permissions == Permissions::OwnerAndGroup ? OWNER_AND_GROUP_MODE : OWNER_ONLY_MODE;
  bool mustRecreate = mode == OpenMode::Recreate;
  std::optional<ino_t> maybeCreatedInode;

  for (int attempt = 0; attempt < MAX_OPEN_ATTEMPTS; ++attempt) {
    auto lockResult = detail::lockShared(names, mode != OpenMode::AttachOnly, fileMode);
    if (!lockResult) return lockResult.error();
    detail::UniqueFd lock = std::move(*lockResult);

    if (!mustRecreate) {
      auto probeResult = detail::probeSegment(names, expected);
      if (!probeResult) return probeResult.error();
      detail::Probe& probe = *probeResult;
      if (probe.state == detail::SegmentState::Ready) {
        const bool created = maybeCreatedInode == probe.inode;
        const std::size_t bytes = probe.mapping.bytes();
        return SignalTable(lock.release(), probe.segment.release(), probe.mapping.release(), bytes, expected.layoutHash,
                           expected.slotCount, probe.generation, names.display, created);
      }
      if (mode == OpenMode::AttachOnly) return Error{probe.reason};
      if (!detail::tryLockExclusive(lock.get())) {
        if (probe.state == detail::SegmentState::Mismatch) return Error{probe.reason};
        usleep(OPEN_RETRY_US);  // another process is creating it: wait for its LOCK_EX, look again
        continue;
      }
    } else if (!detail::tryLockExclusive(lock.get())) {
      // Processes are attached: leave them the old table and its lock file, and build the
      // fresh table under new names.
      if (auto unlinkStatus = detail::unlinkNames(names); !unlinkStatus) return unlinkStatus.error();
      continue;
    }

    auto createResult = detail::createSegment(names, expected, fileMode);
    if (!createResult) return createResult.error();
    maybeCreatedInode = *createResult;
    mustRecreate = false;
    // Closing `lock` drops LOCK_EX; the next round attaches under LOCK_SH.
  }
  return Error{"cannot open table '" + names.display + "': it kept being created or reset by other processes"};
}

SignalTable::SignalTable(int lockFd, int segmentFd, void* base, std::size_t bytes, std::uint64_t layoutHash,
                         std::uint32_t slotCount, std::uint64_t generation, std::string name, bool created) noexcept
    : m_lockFd(lockFd),
      m_segmentFd(segmentFd),
      m_base(base),
      m_bytes(bytes),
      m_header(std::launder(static_cast<detail::TableHeader*>(base))),
      m_slots(std::launder(
          reinterpret_cast<detail::Slot*>(static_cast<unsigned char*>(base) + sizeof(detail::TableHeader)))),
      m_slotCount(slotCount),
      m_name(std::move(name)),
      m_created(created) {
  const detail::GuardedHeader header{layoutHash, slotCount, generation};
  m_guard = detail::guardMapping(base, bytes, segmentFd, &header);
}

SignalTable::SignalTable(SignalTable&& other) noexcept
    : m_lockFd(std::exchange(other.m_lockFd, -1)),
      m_segmentFd(std::exchange(other.m_segmentFd, -1)),
      m_guard(std::exchange(other.m_guard, nullptr)),
      m_base(std::exchange(other.m_base, nullptr)),
      m_bytes(std::exchange(other.m_bytes, 0)),
      m_header(std::exchange(other.m_header, nullptr)),
      m_slots(std::exchange(other.m_slots, nullptr)),
      m_slotCount(std::exchange(other.m_slotCount, 0)),
      m_name(std::move(other.m_name)),
      m_created(other.m_created) {}

SignalTable& SignalTable::operator=(SignalTable&& other) noexcept {
  if (this != &other) {
    release();
    m_lockFd = std::exchange(other.m_lockFd, -1);
    m_segmentFd = std::exchange(other.m_segmentFd, -1);
    m_guard = std::exchange(other.m_guard, nullptr);
    m_base = std::exchange(other.m_base, nullptr);
    m_bytes = std::exchange(other.m_bytes, 0);
    m_header = std::exchange(other.m_header, nullptr);
    m_slots = std::exchange(other.m_slots, nullptr);
    m_slotCount = std::exchange(other.m_slotCount, 0);
    m_name = std::move(other.m_name);
    m_created = other.m_created;
  }
  return *this;
}

SignalTable::~SignalTable() {
  release();
}

void SignalTable::release() noexcept {
  detail::unguardMapping(m_guard);
  if (m_base != nullptr) munmap(m_base, m_bytes);
  if (m_segmentFd >= 0) ::close(m_segmentFd);
  if (m_lockFd >= 0) ::close(m_lockFd);  // drops our LOCK_SH: we are no longer attached
  m_guard = nullptr;
  m_base = nullptr;
  m_segmentFd = -1;
  m_lockFd = -1;
  m_header = nullptr;
  m_slots = nullptr;
  m_slotCount = 0;
}

TableInfo SignalTable::info() const {
  TableInfo info;
  info.name = m_name;
  if (m_header == nullptr) return info;
  // atomic_ref: a process restoring a damaged header may write these fields meanwhile.
  info.formatVersion = std::atomic_ref<std::uint32_t>(m_header->formatVersion).load(std::memory_order_relaxed);
  info.layoutHash = std::atomic_ref<std::uint64_t>(m_header->layoutHash).load(std::memory_order_relaxed);
  info.slotCount = std::atomic_ref<std::uint32_t>(m_header->slotCount).load(std::memory_order_relaxed);
  info.bytes = m_bytes;
  info.createdRealtimeNs = std::atomic_ref<std::int64_t>(m_header->createdRealtimeNs).load(std::memory_order_relaxed);
  info.creatorPid = std::atomic_ref<std::int32_t>(m_header->creatorPid).load(std::memory_order_relaxed);
  info.createdByThisProcess = m_created;
  return info;
}

// ---- writers ----------------------------------------------------------------------------

// Why the watchers mask may be loaded relaxed after the table's epoch add (and why a new
// watch cannot miss a write that raced its creation): watch() stores its bits and then
// does an acq_rel add on the same changeWord that every writer adds to after its write.
// Those adds are totally ordered: if the writer's comes first, the watch's add acquires the
// writer's release and the watcher's first look sees the value; if the watch's comes first,
// the writer's add acquires the watch's release and this load sees the bit.
void SignalTable::notify(detail::Plane& plane, bool changed) noexcept {
  detail::notifyChange(m_header->changeWord);
  if (!changed) return;  // the same value again: the table's epoch moves, the watches sleep on
  std::uint64_t mask = plane.watchers.load(std::memory_order_relaxed);
  while (mask != 0) {
    const int bit = std::countr_zero(mask);
    mask &= mask - 1;
    detail::notifyChange(m_header->watches[static_cast<std::size_t>(bit)].changeWord);
  }
}

namespace {

/// Writes `entry` into `plane` and says whether it differs from the write just before it in
/// ticket order (value bits or aux: source, quality as marked, writer, override flag); the
/// time stamp alone is no change. When that write cannot be read (still being written by
/// another writer, or lapped) the answer is "changed": a watch may wake for nothing, never
/// miss a change.
bool writeAndCompare(detail::Plane& plane, const detail::Payload& entry, bool busPlane) noexcept {
  const std::uint64_t ticket = detail::claimTicket(plane);
  bool changed = true;
  detail::Record previous;
  if (ticket > 1 && detail::readEntry(plane, ticket - 1, previous)) {
    std::uint32_t aux = previous.payload.aux;
    std::uint8_t marked{};
    if (busPlane && detail::markedQuality(plane, ticket - 1, marked)) {
      aux = (aux & LOW_16_BITS) | std::uint32_t{marked} << QUALITY_SHIFT;
    }
    changed = previous.payload.valueBits != entry.valueBits || aux != entry.aux;
  }
  detail::storeEntry(plane, ticket, entry);
  return changed;
}

}  // namespace

bool SignalTable::writeBus(SignalIndex index, double value, std::int64_t timestampNs, std::uint16_t source,
                           Quality quality) noexcept {
  if (index >= m_slotCount) return false;
  const bool changed = writeAndCompare(m_slots[index].bus, payload(value, timestampNs, busAux(source, quality)), true);
  notify(m_slots[index].bus, changed);
  return true;
}

bool SignalTable::markBusQuality(SignalIndex index, Quality quality) noexcept {
  if (index >= m_slotCount) return false;
  detail::Plane& plane = m_slots[index].bus;
  detail::Record current;
  if (!detail::readPlane(plane, current) || current.ticket == 0) return false;
  auto before = static_cast<std::uint8_t>(current.payload.aux >> QUALITY_SHIFT);
  std::uint8_t marked{};
  if (detail::markedQuality(plane, current.ticket, marked)) before = marked;
  detail::markQuality(plane, current.ticket, static_cast<std::uint8_t>(quality));
  notify(plane, before != static_cast<std::uint8_t>(quality));
  return true;
}

bool SignalTable::writeCommand(SignalIndex index, double value, std::int64_t timestampNs, WriterId writer) noexcept {
  if (index >= m_slotCount) return false;
  const bool changed = writeAndCompare(m_slots[index].command, payload(value, timestampNs, writer), false);
  notify(m_slots[index].command, changed);
  return true;
}

bool SignalTable::setOverride(SignalIndex index, double value, std::int64_t timestampNs, WriterId writer) noexcept {
  if (index >= m_slotCount) return false;
  const bool changed =
      writeAndCompare(m_slots[index].override, payload(value, timestampNs, overrideAux(writer, true)), false);
  notify(m_slots[index].override, changed);
  return true;
}

bool SignalTable::clearOverride(SignalIndex index, std::int64_t timestampNs, WriterId writer) noexcept {
  if (index >= m_slotCount) return false;
  const bool changed =
      writeAndCompare(m_slots[index].override, payload(0.0, timestampNs, overrideAux(writer, false)), false);
  notify(m_slots[index].override, changed);
  return true;
}

// ---- readers ----------------------------------------------------------------------------

std::optional<BusValue> SignalTable::readBus(SignalIndex index) const noexcept {
  if (index >= m_slotCount) return std::nullopt;
  const detail::Plane& plane = m_slots[index].bus;
  detail::Record record;
  if (!detail::readPlane(plane, record)) return std::nullopt;
  auto quality = static_cast<std::uint8_t>(record.payload.aux >> QUALITY_SHIFT);
  std::uint8_t markedQuality{};
  if (detail::markedQuality(plane, record.ticket, markedQuality)) quality = markedQuality;
  return BusValue{std::bit_cast<double>(record.payload.valueBits), record.payload.timestampNs,
                  static_cast<std::uint16_t>(record.payload.aux & LOW_16_BITS), static_cast<Quality>(quality),
                  record.ticket};
}

std::optional<CommandValue> SignalTable::readCommand(SignalIndex index) const noexcept {
  if (index >= m_slotCount) return std::nullopt;
  detail::Record record;
  if (!detail::readPlane(m_slots[index].command, record)) return std::nullopt;
  return CommandValue{std::bit_cast<double>(record.payload.valueBits), record.payload.timestampNs,
                      static_cast<WriterId>(record.payload.aux & LOW_16_BITS), record.ticket};
}

std::optional<OverrideValue> SignalTable::readOverride(SignalIndex index) const noexcept {
  if (index >= m_slotCount) return std::nullopt;
  detail::Record record;
  if (!detail::readPlane(m_slots[index].override, record)) return std::nullopt;
  return OverrideValue{std::bit_cast<double>(record.payload.valueBits), record.payload.timestampNs,
                       static_cast<WriterId>(record.payload.aux & LOW_16_BITS),
                       ((record.payload.aux >> ACTIVE_SHIFT) & 1u) != 0, record.ticket};
}

std::optional<SlotSnapshot> SignalTable::read(SignalIndex index) const noexcept {
  auto maybeBus = readBus(index);
  auto maybeCommand = readCommand(index);
  auto maybeOverride = readOverride(index);
  if (!maybeBus || !maybeCommand || !maybeOverride) return std::nullopt;
  return SlotSnapshot{*maybeBus, *maybeCommand, *maybeOverride};
}

// ---- change notification ----------------------------------------------------------------

std::uint32_t SignalTable::changeEpoch() const noexcept {
  return m_header == nullptr ? 0 : detail::currentEpoch(m_header->changeWord);
}

std::uint32_t SignalTable::waitForChange(std::uint32_t lastEpoch, std::chrono::nanoseconds timeout) const noexcept {
  if (m_header == nullptr) return lastEpoch;
  return detail::waitForEpochChange(m_header->changeWord, lastEpoch, timeout);
}

// ---- damage -----------------------------------------------------------------------------

std::string TableDamage::describe(std::string_view tableName) const {
  std::string line = "signal table '" + std::string(tableName) + "' was damaged (";
  std::string facts;
  const auto add = [&facts](const std::string& fact) { facts += (facts.empty() ? "" : ", ") + fact; };
  if (foundBytes >= 0) add("truncated to " + std::to_string(foundBytes) + " of " + std::to_string(tableBytes) + " bytes");
  if (busErrors > 0) add(std::to_string(busErrors) + " bus error" + (busErrors == 1 ? "" : "s") + " absorbed");
  if (restoredElsewhere) add("restored by another process");
  if (facts.empty()) add("header overwritten");
  line += facts + "): ";
  std::string done;
  if (sizeRestored) done = "size";
  if (headerRestored) done += done.empty() ? "header" : " and header";
  line += done.empty() ? "table whole again" : done + " restored";
  if (privatePages) line += ", private pages replaced by the table";
  return line + "; values written before are lost";
}

std::uint64_t SignalTable::damageCount() const noexcept {
  if (m_guard == nullptr) return 0;
  (void)detail::checkHeader(*m_guard);
  return m_guard->damage.load(std::memory_order_relaxed);
}

bool SignalTable::damaged() const noexcept {
  if (m_guard == nullptr) return false;
  return damageCount() != m_guard->reported.load(std::memory_order_relaxed) ||
         m_guard->detached.load(std::memory_order_relaxed);
}

std::optional<TableDamage> SignalTable::checkAndRepair() noexcept {
  if (m_guard == nullptr) return std::nullopt;
  detail::GuardEntry& guard = *m_guard;
  (void)detail::restoreSize(guard);
  (void)detail::reattach(guard);
  (void)detail::checkHeader(guard);
  const std::uint64_t damage = guard.damage.load(std::memory_order_relaxed);
  if (damage == guard.reported.load(std::memory_order_relaxed)) return std::nullopt;
  guard.reported.store(damage, std::memory_order_relaxed);
  guard.lastFaultPage.store(0, std::memory_order_relaxed);
  const std::uint32_t events = guard.events.exchange(0, std::memory_order_relaxed);
  TableDamage report;
  report.busErrors = guard.faults.exchange(0, std::memory_order_relaxed);
  report.foundBytes = guard.foundBytes.exchange(-1, std::memory_order_relaxed);
  report.tableBytes = m_bytes;
  report.sizeRestored = (events & detail::EVENT_SIZE_RESTORED) != 0;
  report.headerRestored = (events & detail::EVENT_HEADER_RESTORED) != 0;
  report.restoredElsewhere = (events & detail::EVENT_RESTORED_ELSEWHERE) != 0;
  report.privatePages = (events & detail::EVENT_PRIVATE_PAGES) != 0;
  return report;
}

// ---- watches ----------------------------------------------------------------------------

namespace {

/// true when the owner of an entry is gone: its pid does not exist and it has not renewed
/// its lease for WATCH_LEASE. (An entry whose dead owner's pid was reused by a live process
/// stays taken until that process ends: a lost entry, never a stolen one.)
bool abandoned(std::int32_t owner, std::int64_t aliveNs, std::int64_t nowNs) noexcept {
  const std::int64_t leaseNs = std::chrono::nanoseconds(WATCH_LEASE).count();
  if (nowNs - aliveNs < leaseNs) return false;
  return ::kill(owner, 0) != 0 && errno == ESRCH;
}

void forEachPlane(detail::Slot& slot, const auto& action) noexcept {
  action(slot.bus);
  action(slot.command);
  action(slot.override);
}

}  // namespace

SignalWatch SignalTable::watch(std::span<const SignalIndex> indexes) {
  SignalWatch result;
  result.m_header = m_header;
  result.m_slots = m_slots;
  if (m_header == nullptr) return result;
  for (const SignalIndex index : indexes) {
    if (index < m_slotCount) result.m_indexes.push_back(index);
  }
  const auto self = static_cast<std::int32_t>(::getpid());
  const std::int64_t now = clock::monotonicNs();
  for (std::size_t i = 0; i < detail::MAX_WATCHES && result.m_entry < 0; ++i) {
    detail::WatchEntry& entry = m_header->watches[i];
    std::atomic_ref<std::int32_t> owner(entry.ownerPid);
    std::int32_t current = owner.load(std::memory_order_acquire);
    const std::int64_t alive = std::atomic_ref<std::int64_t>(entry.aliveNs).load(std::memory_order_relaxed);
    if (current != 0 && !abandoned(current, alive, now)) continue;
    if (!owner.compare_exchange_strong(current, self, std::memory_order_acq_rel)) continue;
    std::atomic_ref<std::int64_t>(entry.aliveNs).store(now, std::memory_order_relaxed);
    result.m_entry = static_cast<int>(i);
  }
  if (result.m_entry < 0) return result;  // falls back to the table's epoch

  const std::uint64_t bit = std::uint64_t{1} << result.m_entry;
  std::vector<bool> wanted(m_slotCount, false);
  for (const SignalIndex index : result.m_indexes) wanted[index] = true;
  for (std::uint32_t index = 0; index < m_slotCount; ++index) {
    forEachPlane(m_slots[index], [&](detail::Plane& plane) {
      if (wanted[index]) {
        plane.watchers.fetch_or(bit, std::memory_order_relaxed);
      } else if ((plane.watchers.load(std::memory_order_relaxed) & bit) != 0) {
        plane.watchers.fetch_and(~bit, std::memory_order_relaxed);  // a previous owner's
      }
    });
  }
  // Orders the bits before the caller's first look (see notify()).
  detail::notifyChange(m_header->changeWord);
  return result;
}

SignalWatch::SignalWatch(SignalWatch&& other) noexcept
    : m_header(std::exchange(other.m_header, nullptr)),
      m_slots(std::exchange(other.m_slots, nullptr)),
      m_indexes(std::move(other.m_indexes)),
      m_entry(std::exchange(other.m_entry, -1)) {}

SignalWatch& SignalWatch::operator=(SignalWatch&& other) noexcept {
  if (this != &other) {
    release();
    m_header = std::exchange(other.m_header, nullptr);
    m_slots = std::exchange(other.m_slots, nullptr);
    m_indexes = std::move(other.m_indexes);
    m_entry = std::exchange(other.m_entry, -1);
  }
  return *this;
}

SignalWatch::~SignalWatch() {
  release();
}

void SignalWatch::release() noexcept {
  if (m_header == nullptr || m_entry < 0) return;
  std::atomic_ref<std::int32_t> owner(m_header->watches[static_cast<std::size_t>(m_entry)].ownerPid);
  std::int32_t self = static_cast<std::int32_t>(::getpid());
  // After damage wiped the table, the entry may belong to another process's watch: then
  // neither its bits nor its claim are ours to clear.
  if (owner.load(std::memory_order_acquire) == self) {
    const std::uint64_t bit = std::uint64_t{1} << m_entry;
    for (const SignalIndex index : m_indexes) {
      forEachPlane(m_slots[index],
                   [bit](detail::Plane& plane) { plane.watchers.fetch_and(~bit, std::memory_order_relaxed); });
    }
    (void)owner.compare_exchange_strong(self, 0, std::memory_order_release, std::memory_order_relaxed);
  }
  m_entry = -1;
}

std::uint32_t SignalWatch::epoch() const noexcept {
  if (m_header == nullptr) return 0;
  if (m_entry < 0) return detail::currentEpoch(m_header->changeWord);
  return detail::currentEpoch(m_header->watches[static_cast<std::size_t>(m_entry)].changeWord);
}

std::uint32_t SignalWatch::wait(std::uint32_t lastEpoch, std::chrono::nanoseconds timeout) noexcept {
  if (m_header == nullptr) return lastEpoch;
  if (m_entry < 0) return detail::waitForEpochChange(m_header->changeWord, lastEpoch, timeout);
  detail::WatchEntry& entry = m_header->watches[static_cast<std::size_t>(m_entry)];
  std::atomic_ref<std::int64_t>(entry.aliveNs).store(clock::monotonicNs(), std::memory_order_relaxed);
  return detail::waitForEpochChange(entry.changeWord, lastEpoch, timeout);
}

}  // namespace openvcu::signals
