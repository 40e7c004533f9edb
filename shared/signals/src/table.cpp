#include "openvcu/signals/table.hpp"

#include <sys/mman.h>
#include <unistd.h>

#include <bit>
#include <new>
#include <optional>
#include <utility>

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

std::int64_t monotonicNowNs() noexcept {
  return detail::monotonicNs();
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
        return SignalTable(lock.release(), probe.mapping.release(), bytes, names.display, created);
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

SignalTable::SignalTable(int lockFd, void* base, std::size_t bytes, std::string name, bool created) noexcept
    : m_lockFd(lockFd),
      m_base(base),
      m_bytes(bytes),
      m_header(std::launder(static_cast<detail::TableHeader*>(base))),
      m_slots(std::launder(
          reinterpret_cast<detail::Slot*>(static_cast<unsigned char*>(base) + sizeof(detail::TableHeader)))),
      m_slotCount(m_header->slotCount),
      m_name(std::move(name)),
      m_created(created) {}

SignalTable::SignalTable(SignalTable&& other) noexcept
    : m_lockFd(std::exchange(other.m_lockFd, -1)),
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
  if (m_base != nullptr) munmap(m_base, m_bytes);
  if (m_lockFd >= 0) ::close(m_lockFd);  // drops our LOCK_SH: we are no longer attached
  m_base = nullptr;
  m_lockFd = -1;
  m_header = nullptr;
  m_slots = nullptr;
  m_slotCount = 0;
}

TableInfo SignalTable::info() const {
  TableInfo info;
  info.name = m_name;
  if (m_header == nullptr) return info;
  info.formatVersion = m_header->formatVersion;
  info.layoutHash = m_header->layoutHash;
  info.slotCount = m_header->slotCount;
  info.bytes = m_bytes;
  info.createdRealtimeNs = m_header->createdRealtimeNs;
  info.creatorPid = m_header->creatorPid;
  info.createdByThisProcess = m_created;
  return info;
}

// ---- writers ----------------------------------------------------------------------------

bool SignalTable::writeBus(SignalIndex index, double value, std::int64_t timestampNs, std::uint16_t source,
                           Quality quality) noexcept {
  if (index >= m_slotCount) return false;
  detail::writePlane(m_slots[index].bus, payload(value, timestampNs, busAux(source, quality)));
  detail::notifyChange(m_header->changeWord);
  return true;
}

bool SignalTable::markBusQuality(SignalIndex index, Quality quality) noexcept {
  if (index >= m_slotCount) return false;
  detail::Plane& plane = m_slots[index].bus;
  detail::Record current;
  if (!detail::readPlane(plane, current) || current.ticket == 0) return false;
  detail::markQuality(plane, current.ticket, static_cast<std::uint8_t>(quality));
  detail::notifyChange(m_header->changeWord);
  return true;
}

bool SignalTable::writeCommand(SignalIndex index, double value, std::int64_t timestampNs, WriterId writer) noexcept {
  if (index >= m_slotCount) return false;
  detail::writePlane(m_slots[index].command, payload(value, timestampNs, writer));
  detail::notifyChange(m_header->changeWord);
  return true;
}

bool SignalTable::setOverride(SignalIndex index, double value, std::int64_t timestampNs, WriterId writer) noexcept {
  if (index >= m_slotCount) return false;
  detail::writePlane(m_slots[index].override, payload(value, timestampNs, overrideAux(writer, true)));
  detail::notifyChange(m_header->changeWord);
  return true;
}

bool SignalTable::clearOverride(SignalIndex index, std::int64_t timestampNs, WriterId writer) noexcept {
  if (index >= m_slotCount) return false;
  detail::writePlane(m_slots[index].override, payload(0.0, timestampNs, overrideAux(writer, false)));
  detail::notifyChange(m_header->changeWord);
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

}  // namespace openvcu::signals
