#pragma once
// The signal table: one slot per catalog signal in POSIX shared memory, shared by the
// independent processes of one stack instance (can-rx, can-tx, fsm, gpio, hmi, vcu).
// Each slot has three planes, each with its own update counter:
//   bus      the value seen on the bus (can-rx; can-tx for what it sent), with quality
//   command  the commanded value (fsm, gpio inputs, operator commands)
//   override an operator override that wins over the command until cleared
// Reads and writes never block and never take a lock; a process killed at any instruction
// can neither block nor corrupt what the others read, and a restarted one simply carries
// on. Design, protocol and memory-ordering argument: docs/design/signal-table.md.
//
//   auto catalogResult = signals::Catalog::create(std::move(infos));
//   auto openResult = signals::SignalTable::open(*catalogResult, "hhea");
//   if (!openResult) { std::cerr << openResult.error().toString() << '\n'; return 1; }
//   SignalTable& table = *openResult;
//   table.writeBus(soc, 87.5, clock::monotonicNs(), 0xF3, signals::Quality::Valid);
//   if (const auto maybeBus = table.readBus(soc)) use(maybeBus->value);
//
// Timestamps are the caller's; the stack uses CLOCK_MONOTONIC nanoseconds (clock::monotonicNs()),
// which every process on the host shares.

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "openvcu/core/clock.hpp"
#include "openvcu/core/result.hpp"
#include "openvcu/signals/catalog.hpp"

namespace openvcu::signals {

namespace detail {
struct TableHeader;
struct Slot;
struct Plane;
struct GuardEntry;
}  // namespace detail

enum class Quality : std::uint8_t {
  NeverReceived = 0,  ///< no value since the table was created
  Valid = 1,
  Stale = 2,       ///< no update within the signal's timeout
  OutOfRange = 3,  ///< decoded value outside the DBC range
};

/// "NeverReceived", "Valid", "Stale", "OutOfRange" ("?" for anything else).
[[nodiscard]] std::string_view qualityName(Quality quality) noexcept;

/// The bus plane. `updates` is the number of the write returned (writes started on this
/// plane up to and including it); 0 with NeverReceived when the plane was never written.
struct BusValue {
  double value{};
  std::int64_t timestampNs{};
  std::uint16_t source{};  ///< J1939 source address or other producer id
  Quality quality{Quality::NeverReceived};
  std::uint64_t updates{};
};

struct CommandValue {
  double value{};
  std::int64_t timestampNs{};
  WriterId writer{};
  std::uint64_t updates{};  ///< 0: never commanded
};

struct OverrideValue {
  double value{};  ///< 0 after clearOverride()
  std::int64_t timestampNs{};
  WriterId writer{};  ///< who set it, or who cleared it
  bool active{};
  std::uint64_t updates{};  ///< 0: never set
};

/// The three planes of one slot. Each plane is a consistent (value, timestamp, flags)
/// triple; the planes are read one after the other, not as one atomic unit.
struct SlotSnapshot {
  BusValue bus;
  CommandValue command;
  OverrideValue override;
};

/// The value a transmitter should send: the override when active, else the command.
struct EffectiveCommand {
  double value{};
  std::int64_t timestampNs{};
  WriterId writer{};
  bool overridden{};
};

/// Override wins over command; empty when neither an active override nor any command exists.
/// @note noexcept, allocation-free.
[[nodiscard]] std::optional<EffectiveCommand> effectiveCommand(const SlotSnapshot& snapshot) noexcept;


/// How long a watch entry whose owner's pid is gone stays reserved after its last wait.
inline constexpr std::chrono::seconds WATCH_LEASE{10};

enum class OpenMode : std::uint8_t {
  /// Services: attach; create the table if it is missing or was left incomplete by a
  /// killed creator; replace a table of another configuration only when no process is
  /// attached to it (otherwise refuse with a message naming both layouts).
  CreateOrAttach,
  /// Tools that must not create anything (`vcu signal get`): attach or fail.
  AttachOnly,
  /// `vcu table reset`: always start from a fresh, all-NeverReceived table. Processes still
  /// attached keep the old table (now nameless) until they restart.
  Recreate,
};

enum class Permissions : std::uint8_t {
  OwnerOnly,      ///< 0600 (default): every process of the instance runs as one user
  OwnerAndGroup,  ///< 0660: e.g. the HMI runs as another user of the creator's group
};

/// What the header of an open table says.
struct TableInfo {
  std::string name;  ///< "openvcu-hhea": the segment /dev/shm/openvcu-hhea
  std::uint32_t formatVersion{};
  std::uint64_t layoutHash{};
  std::uint32_t slotCount{};
  std::size_t bytes{};
  std::int64_t createdRealtimeNs{};  ///< CLOCK_REALTIME at creation
  std::int32_t creatorPid{};
  bool createdByThisProcess{};  ///< this open() created (or re-created) the table
};

/// What SignalTable::checkAndRepair() found since its last report (issue 18: the segment
/// truncated or overwritten under running processes). The table is whole again when it is
/// reported; the values written before the damage are lost (every slot reads as never
/// written until its writer writes it again).
struct TableDamage {
  std::uint64_t busErrors{};     ///< SIGBUS faults in the table absorbed by this process
  std::int64_t foundBytes{-1};   ///< the segment's size when this process found it short; -1: not seen short
  std::size_t tableBytes{};      ///< the size it has again
  bool sizeRestored{};           ///< this process restored the segment's size
  bool headerRestored{};         ///< this process wrote the wiped or overwritten header again
  bool restoredElsewhere{};      ///< another process restored it (this one saw a new generation)
  bool privatePages{};           ///< some accesses used private zero pages until the segment was mapped again
  /// One line: "signal table 'openvcu-hhea' was damaged (truncated to 0 of 578688 bytes,
  /// 3 bus errors absorbed): size and header restored; values written before are lost".
  [[nodiscard]] std::string describe(std::string_view tableName) const;
};

/// A mapped signal table. Valid once open() returned it; move-only; unmapping (destructor)
/// detaches this process. Index arguments out of range make writes return false and reads
/// return empty.
/// @note thread-safe and process-safe: any number of threads and processes may call any
///       method concurrently. Every per-signal method is noexcept, allocation-free,
///       lock-free and free of system calls (except the wake described at waitForChange).
/// A watch on chosen signals (SignalTable::watch): its epoch moves when one of them changes
/// on any plane (value bits, quality, source, writer, override flag; a newer time stamp
/// alone is no change), and not for the rest of the table's traffic, so a thread that reacts
/// to a few signals sleeps while can-rx writes hundreds and rewrites the same values.
///
///   signals::SignalWatch watch = table.watch(myIndexes);
///   for (;;) { const auto epoch = watch.epoch(); react(); (void)watch.wait(epoch, 250ms); }
///
/// @note restricted thread-safe: one waiting thread. Move-only; destroy it before the
///       SignalTable it came from is unmapped.
class SignalWatch {
 public:
  SignalWatch() = default;
  SignalWatch(SignalWatch&& other) noexcept;
  SignalWatch& operator=(SignalWatch&& other) noexcept;
  SignalWatch(const SignalWatch&) = delete;
  SignalWatch& operator=(const SignalWatch&) = delete;
  /// Clears its bits from the watched slots and frees its entry.
  ~SignalWatch();

  /// true when it owns a watch entry; false when it fell back to the table's epoch (no free
  /// entry, or a default-constructed watch): then every write wakes it. Correct either way.
  [[nodiscard]] bool dedicated() const noexcept { return m_entry >= 0; }
  /// The entry it owns (0..31), -1 when not dedicated.
  [[nodiscard]] int entry() const noexcept { return m_entry; }
  /// The watch's change epoch (31 bits, wrapping).
  [[nodiscard]] std::uint32_t epoch() const noexcept;
  /// Sleeps until epoch() != lastEpoch or `timeout` passed; returns epoch(). Also renews the
  /// entry's lease (see SignalTable::watch).
  std::uint32_t wait(std::uint32_t lastEpoch, std::chrono::nanoseconds timeout) noexcept;

 private:
  friend class SignalTable;
  void release() noexcept;

  detail::TableHeader* m_header{nullptr};
  detail::Slot* m_slots{nullptr};
  std::vector<SignalIndex> m_indexes;  ///< watched, in range, for release()
  int m_entry{-1};
};

class SignalTable {
 public:
  /// Attaches to (or creates, see OpenMode) the table "/openvcu-<instance>" for `catalog`.
  /// `instance`: letters, digits, '-' and '_' (1..64 characters). Errors: a bad instance
  /// name, a table of another configuration ("table 'openvcu-hhea' was created from
  /// another configuration (layout 0x..., 812 signals; this process: 0x..., 815): stop
  /// every service of this instance or run `vcu table reset`"), a missing table in
  /// AttachOnly mode, and operating-system failures (permissions, no /dev/shm).
  /// @note start-up only: allocates, makes system calls, may wait (at most ~5 s) for a
  ///       process that is creating the table.
  static Result<SignalTable> open(const Catalog& catalog, std::string_view instance,
                                  OpenMode mode = OpenMode::CreateOrAttach,
                                  Permissions permissions = Permissions::OwnerOnly);

  /// Removes the names of an instance's table and lock file (tests, `vcu table reset`).
  /// Attached processes keep their mappings. Not an error when nothing exists.
  static Status remove(std::string_view instance);

  /// Succeeds when `instance` is a valid instance name; else an error giving the rule.
  static Status checkInstanceName(std::string_view instance);

  /// "/dev/shm/openvcu-<instance>" and "/dev/shm/openvcu-<instance>.lock".
  [[nodiscard]] static std::string segmentPath(std::string_view instance);
  [[nodiscard]] static std::string lockPath(std::string_view instance);

  SignalTable(SignalTable&& other) noexcept;
  SignalTable& operator=(SignalTable&& other) noexcept;
  SignalTable(const SignalTable&) = delete;
  SignalTable& operator=(const SignalTable&) = delete;
  ~SignalTable();

  [[nodiscard]] std::size_t size() const noexcept { return m_slotCount; }
  [[nodiscard]] TableInfo info() const;

  // ---- writers --------------------------------------------------------------------------
  // Each write bumps the change epoch. Concurrent writes to one plane are ordered by the
  // ticket each takes first: the later ticket wins even if it finishes first.

  /// Bus plane: a decoded (or sent) value. False only for an index out of range.
  bool writeBus(SignalIndex index, double value, std::int64_t timestampNs, std::uint16_t source,
                Quality quality) noexcept;
  /// Sets the quality of the bus value currently visible (value, timestamp, source and the
  /// update counter stay). If a new value arrives meanwhile, the mark does not apply to
  /// it: a fresh value carries its own quality. False for an index out of range, a plane
  /// never written, or (extremely rarely) when no complete value could be read.
  bool markBusQuality(SignalIndex index, Quality quality) noexcept;
  /// Command plane. False only for an index out of range.
  bool writeCommand(SignalIndex index, double value, std::int64_t timestampNs, WriterId writer) noexcept;
  /// Override plane: active override with `value`. False only for an index out of range.
  bool setOverride(SignalIndex index, double value, std::int64_t timestampNs, WriterId writer) noexcept;
  /// Override plane: inactive (value 0), recording who cleared it and when.
  bool clearOverride(SignalIndex index, std::int64_t timestampNs, WriterId writer) noexcept;

  // ---- readers --------------------------------------------------------------------------
  // Each returns the newest complete write of the plane (wait-free: a bounded number of
  // loads). Empty for an index out of range, or when the 4 newest writes of the plane were
  // all unfinished (in progress or killed) during 3 attempts; the caller keeps its
  // previous value and reads again next cycle.

  [[nodiscard]] std::optional<BusValue> readBus(SignalIndex index) const noexcept;
  [[nodiscard]] std::optional<CommandValue> readCommand(SignalIndex index) const noexcept;
  [[nodiscard]] std::optional<OverrideValue> readOverride(SignalIndex index) const noexcept;
  /// All three planes (empty if any of them is).
  [[nodiscard]] std::optional<SlotSnapshot> read(SignalIndex index) const noexcept;

  // ---- change notification --------------------------------------------------------------

  /// A counter (31 bits, wrapping) that every write and quality mark increases.
  [[nodiscard]] std::uint32_t changeEpoch() const noexcept;
  /// Sleeps until changeEpoch() != lastEpoch or `timeout` passed; returns changeEpoch().
  /// Typical loop: `auto epoch = t.changeEpoch(); for (;;) { scan(); epoch = t.waitForChange(epoch, 100ms); }`.
  /// @note blocks (futex), so not for a real-time loop. Writers make one FUTEX_WAKE system
  ///       call for the first change after a waiter went to sleep and none otherwise.
  std::uint32_t waitForChange(std::uint32_t lastEpoch, std::chrono::nanoseconds timeout) const noexcept;

  /// A watch on `indexes` (indexes out of range are ignored): woken only by changes of
  /// those signals (a write whose value bits or aux differ from the write before it, or a
  /// quality mark that changes the quality; the table's epoch moves for every write). Takes one of the table's 32 watch entries: a free
  /// one, or one whose owner is gone (its pid no longer exists) and has not waited for
  /// WATCH_LEASE. Clears the bits a previous owner
  /// left in every slot, then sets its own. With no entry free the watch falls back to the
  /// table's epoch (dedicated() false). Writers pay one load per write for watches, plus one
  /// atomic add per watch of the written slot (and a wake-up only for a sleeping watch).
  /// @note start-up only: allocates, walks every slot once.
  SignalWatch watch(std::span<const SignalIndex> indexes);

  // ---- damage (docs/design/signal-table.md, "Damage") ------------------------------------
  // A truncated segment makes accesses to its lost pages raise SIGBUS. The table library
  // handles SIGBUS for its mappings: the faulting process restores the segment's size and
  // header (every process sees the restored, now empty table) and the access completes;
  // no process is killed. The values are lost: writers must write theirs again.

  /// Changes (grows) whenever this process meets damage: a SIGBUS absorbed in this table, a
  /// header found wiped or overwritten (restored on the spot), or a restoration by another
  /// process (a new generation in the header). A consumer that must re-publish its state
  /// compares it with the value it saw last, e.g. once per loop iteration.
  /// @note thread-safe; noexcept, lock-free, no system call, a few loads.
  [[nodiscard]] std::uint64_t damageCount() const noexcept;
  /// true while damage met by this process has not yet been reported by checkAndRepair().
  /// @note thread-safe; noexcept, lock-free, no system call.
  [[nodiscard]] bool damaged() const noexcept;
  /// Looks for damage and repairs it: restores a short segment's size and the header, maps
  /// the segment again where private pages stood in, and reports what happened since the
  /// last call (empty when nothing did). Meant for the service's 1 s heartbeat tick: log
  /// the report's describe() as one line.
  /// @note restricted thread-safe: one thread calls it (others may use the table meanwhile);
  ///       noexcept, no allocation; system calls (fstat, maybe ftruncate and mmap).
  [[nodiscard]] std::optional<TableDamage> checkAndRepair() noexcept;

 private:
  SignalTable(int lockFd, int segmentFd, void* base, std::size_t bytes, std::uint64_t layoutHash,
              std::uint32_t slotCount, std::uint64_t generation, std::string name, bool created) noexcept;
  void release() noexcept;
  /// Moves the table's epoch; and the epochs of the plane's watches when `changed`.
  void notify(detail::Plane& plane, bool changed) noexcept;

  int m_lockFd{-1};  ///< holds LOCK_SH on the lock file for as long as we are attached
  int m_segmentFd{-1};  ///< the segment, read-write: restores its size after a truncation
  detail::GuardEntry* m_guard{nullptr};  ///< this mapping's entry in the SIGBUS guard (may be null)
  void* m_base{nullptr};
  std::size_t m_bytes{};
  detail::TableHeader* m_header{nullptr};
  detail::Slot* m_slots{nullptr};
  std::uint32_t m_slotCount{};
  std::string m_name;
  bool m_created{};
};

}  // namespace openvcu::signals
