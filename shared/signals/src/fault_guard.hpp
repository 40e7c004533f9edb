#pragma once
// Survival of a damaged table segment (docs/design/signal-table.md, "Damage: a truncated or
// overwritten segment"). Truncating /dev/shm/openvcu-<instance> under running processes makes
// every access to the lost pages raise SIGBUS, whose default action kills the process. The
// table library installs one SIGBUS handler per process (chaining the one it replaces) that
// looks the faulting address up among the guarded mappings below and, when it lies in one:
//   1. the segment is shorter than the table: ftruncate it back to full size (the lost pages
//      come back as zeros in every process that maps it), write the header again if it was
//      lost, give the table a new generation, and return: the access completes on the
//      restored, shared segment;
//   2. the size is right (another process restored it, or tmpfs had no page to give): return
//      once so the access is retried; when the same page faults again, map a private zero
//      page over it (MAP_FIXED) so the access completes harmlessly, and mark the mapping
//      detached until SignalTable::checkAndRepair() maps the segment again.
// The handler is (re)installed by every open() where it is not the current SIGBUS action.
// Every absorbed fault counts as damage for SignalTable::damaged() / damageCount().
// Faults outside every guarded mapping go to the previous handler (or the default action).
//
// The registry is a fixed array in static storage; the handler only loads and stores
// lock-free atomics and makes async-signal-safe system calls (fstat, ftruncate, mmap,
// clock_gettime, getpid).

#include <atomic>
#include <cstddef>
#include <cstdint>

namespace openvcu::signals::detail {

/// Guarded mappings per process (tables, plus the short-lived mappings of open()).
inline constexpr std::size_t MAX_GUARDED_MAPPINGS = 64;

/// Bits of GuardEntry::events: what happened since the last report.
inline constexpr std::uint32_t EVENT_SIZE_RESTORED = 1u << 0;
inline constexpr std::uint32_t EVENT_HEADER_RESTORED = 1u << 1;
inline constexpr std::uint32_t EVENT_RESTORED_ELSEWHERE = 1u << 2;
inline constexpr std::uint32_t EVENT_PRIVATE_PAGES = 1u << 3;

/// One guarded mapping. Process-local; every field is a lock-free atomic because the SIGBUS
/// handler reads and updates it on whatever thread faulted.
struct GuardEntry {
  std::atomic<std::uintptr_t> begin{0};  ///< 0: the entry is free
  std::atomic<std::size_t> bytes{0};
  std::atomic<int> fd{-1};        ///< the segment (read-write); -1: the size cannot be restored
  std::atomic<bool> table{false};  ///< a complete table: the header may be written again
  std::atomic<std::uint64_t> layoutHash{0};
  std::atomic<std::uint32_t> slotCount{0};
  std::atomic<std::uint64_t> generation{0};  ///< the header generation this process accepted
  std::atomic<std::uint64_t> damage{0};      ///< damage this process met (faults, restorations seen)
  std::atomic<std::uint64_t> reported{0};    ///< `damage` at the last SignalTable::checkAndRepair()
  std::atomic<std::uint64_t> faults{0};      ///< SIGBUS absorbed since the last report
  std::atomic<std::int64_t> foundBytes{-1};  ///< the segment's size when this process found it short
  std::atomic<std::uint32_t> events{0};      ///< EVENT_* since the last report
  std::atomic<bool> detached{false};         ///< private zero pages back part of the mapping
  std::atomic<std::uintptr_t> lastFaultPage{0};
};
static_assert(std::atomic<std::uintptr_t>::is_always_lock_free && std::atomic<std::size_t>::is_always_lock_free &&
              std::atomic<int>::is_always_lock_free && std::atomic<bool>::is_always_lock_free &&
              std::atomic<std::uint64_t>::is_always_lock_free && std::atomic<std::int64_t>::is_always_lock_free &&
              std::atomic<std::uint32_t>::is_always_lock_free);

/// What a complete table's header must say (the values this process attached with).
struct GuardedHeader {
  std::uint64_t layoutHash{};
  std::uint32_t slotCount{};
  std::uint64_t generation{};  ///< the generation found at attachment
};

/// Guards [base, base + bytes): installs the SIGBUS handler unless it is the current SIGBUS
/// action (chaining the one it replaces) and claims a registry entry. `fd` is the segment (or -1); `header` is non-null for a
/// complete table. Returns nullptr when every entry is taken: the mapping stays unguarded
/// (a damaged segment then kills the process as before).
/// @note start-up only (sigaction); thread-safe.
[[nodiscard]] GuardEntry* guardMapping(void* base, std::size_t bytes, int fd, const GuardedHeader* header) noexcept;

/// Frees the entry; call before unmapping. Null is ignored.
void unguardMapping(GuardEntry* entry) noexcept;

/// Checks the header of a guarded table against what this process attached with. Writes it
/// again when it was wiped or overwritten (and gives the table a new generation); adopts a
/// new generation set by another process. Either counts as damage. True when it found any.
/// @note lock-free, no system call except clock_gettime/getpid when it restores; async-signal-safe.
bool checkHeader(GuardEntry& entry) noexcept;

/// Restores the segment's size when it is short (fstat, ftruncate, fallocate), then the
/// header and a new generation. True when it was short.
/// @note system calls; async-signal-safe.
bool restoreSize(GuardEntry& entry) noexcept;

/// Maps the segment over the whole range again when private pages were used. True when it did.
/// @note system calls (mmap).
bool reattach(GuardEntry& entry) noexcept;

/// A fresh non-zero generation (time, pid and a process-local counter).
[[nodiscard]] std::uint64_t freshGeneration() noexcept;

/// Guards a short-lived mapping of open() (probe, creation) for its scope.
class ScopedGuard {
 public:
  ScopedGuard(void* base, std::size_t bytes, int fd) noexcept : m_entry(guardMapping(base, bytes, fd, nullptr)) {}
  ScopedGuard(const ScopedGuard&) = delete;
  ScopedGuard& operator=(const ScopedGuard&) = delete;
  ~ScopedGuard() { unguardMapping(m_entry); }

 private:
  GuardEntry* m_entry;
};

}  // namespace openvcu::signals::detail
