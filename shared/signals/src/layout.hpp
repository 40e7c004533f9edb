#pragma once
// The shared-memory layout of a signal table and the lock-free protocol of one plane
// (docs/design/signal-table.md has the argument in full).
//
// Everything in this file lives in POSIX shared memory mapped by independent processes,
// any of which may be SIGKILLed at any instruction: fixed-size standard-layout structs,
// no pointers, no std::string, only always-lock-free atomics (STYLE.md 9). A freshly
// ftruncate()d, all-zero segment is a valid empty table; the creator only fills the
// header and stores the magic number last.
//
// Contract of a plane (bus value, commanded value or override of one signal):
//   writers: any number of processes and threads, lock-free (wait-free for a bounded
//            number of writers); a writer killed at any instruction leaves at most one
//            incomplete entry that readers skip and the ring later reuses.
//   readers: any number, wait-free (at most READ_ROUNDS * RING_SIZE entry probes); they
//            get the newest complete write among the last RING_SIZE tickets, whole
//            (value, timestamp, aux) or not at all.

#include <array>
#include <atomic>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <type_traits>

namespace openvcu::signals::detail {

inline constexpr std::size_t CACHE_LINE_BYTES = 64;

/// "OVCUSIGT" read as a little-endian 64-bit number.
inline constexpr std::uint64_t TABLE_MAGIC = 0x544749535543564fULL;

/// Entries per plane ring. A reader only fails when the RING_SIZE newest writes of a plane
/// are all unfinished (in progress or killed) at the same moment. Power of two so that
/// ticket % RING_SIZE stays consistent across the 2^64 wrap of the ticket counter.
inline constexpr std::size_t RING_SIZE = 4;
static_assert(std::has_single_bit(RING_SIZE));

/// Each entry word carries a 32-bit tag (the low half of the write's ticket) beside 32 bits
/// of payload: value low/high, timestamp low/high, aux. A reader accepts an entry only when
/// all five tags equal the ticket it looks for, so a triple is never assembled from two writes.
inline constexpr std::size_t ENTRY_WORDS = 5;
inline constexpr std::size_t WORD_VALUE_LOW = 0;
inline constexpr std::size_t WORD_VALUE_HIGH = 1;
inline constexpr std::size_t WORD_TIME_LOW = 2;
inline constexpr std::size_t WORD_TIME_HIGH = 3;
inline constexpr std::size_t WORD_AUX = 4;

/// How often a reader re-reads the head when the whole ring window is unfinished.
inline constexpr int READ_ROUNDS = 3;

using AtomicWord = std::atomic<std::uint64_t>;
static_assert(AtomicWord::is_always_lock_free);
static_assert(sizeof(AtomicWord) == sizeof(std::uint64_t));

/// One ring entry: five tagged words.
struct Entry {
  std::array<AtomicWord, ENTRY_WORDS> words;
};

/// One plane of one slot: a ticket counter, a ring of entries and (bus plane only) a
/// quality mark that markBusQuality() attaches to one particular write.
struct alignas(CACHE_LINE_BYTES) Plane {
  AtomicWord head;  ///< tickets handed out so far = the ticket of the newest started write
  AtomicWord mark;  ///< ticket << 8 | quality: the quality of write `ticket`, set afterwards
  /// Bit i: watch entry i (TableHeader::watches) is woken by writes of this plane. Set and
  /// cleared by SignalTable::watch and ~SignalWatch; read by every writer of the plane.
  AtomicWord watchers;
  std::array<Entry, RING_SIZE> ring;
};
static_assert(std::is_standard_layout_v<Plane>);
static_assert(sizeof(Plane) == 3 * CACHE_LINE_BYTES);

/// One signal: three independent planes, each on its own cache lines so that the bus
/// writer (can-rx) and the command writer (fsm) do not share a line.
struct Slot {
  Plane bus;
  Plane command;
  Plane override;
};
static_assert(std::is_standard_layout_v<Slot>);
static_assert(sizeof(Slot) == 9 * CACHE_LINE_BYTES);
static_assert(alignof(Slot) == CACHE_LINE_BYTES);

/// How many SignalWatch entries a table has (bits of Plane::watchers).
inline constexpr std::size_t MAX_WATCHES = 32;

/// One watch's change notification and its owner (SignalTable::watch). All three fields
/// are accessed through std::atomic_ref.
struct alignas(CACHE_LINE_BYTES) WatchEntry {
  std::uint32_t changeWord;  ///< futex word: epoch << 1 | waiters flag (notifier.hpp)
  std::int32_t ownerPid;     ///< 0: free
  std::int64_t aliveNs;      ///< CLOCK_MONOTONIC of the owner's claim or latest wait
};
static_assert(sizeof(WatchEntry) == CACHE_LINE_BYTES);

/// The segment starts with this header; the slots follow at offset sizeof(TableHeader).
/// All fields but `magic`, `generation` and `changeWord` are written once by the creator
/// before it stores `magic` (release) and are read-only afterwards, unless the segment was
/// damaged (truncated or overwritten): then an attached process writes the same values again
/// (fault_guard.cpp) through std::atomic_ref and stores `magic` last.
struct alignas(CACHE_LINE_BYTES) TableHeader {
  AtomicWord magic;                ///< TABLE_MAGIC once the table is complete
  std::uint32_t formatVersion;     ///< SIGNAL_TABLE_FORMAT_VERSION of the creator
  std::uint32_t headerBytes;       ///< sizeof(TableHeader) of the creator
  std::uint64_t layoutHash;        ///< Catalog::layoutHash() of the creator
  std::uint32_t slotCount;         ///< signals in the creator's catalog
  std::uint32_t slotBytes;         ///< sizeof(Slot) of the creator
  std::int64_t createdRealtimeNs;  ///< CLOCK_REALTIME at creation
  std::int32_t creatorPid;         ///< for `vcu table status`; may be long gone
  std::uint32_t reserved;
  /// Non-zero, random per creation and per restoration after damage (std::atomic_ref): an
  /// attached process that finds another value than the one it attached to knows the values
  /// were lost meanwhile. Lives in what was padding; tables of older builds hold 0 here.
  std::uint64_t generation;
  /// Change notification (futex word, on its own cache line): epoch << 1 | waiters flag.
  /// Accessed through std::atomic_ref because the kernel needs a plain 32-bit word.
  alignas(CACHE_LINE_BYTES) std::uint32_t changeWord;
  /// Watches: change notification for chosen signals only (SignalTable::watch).
  std::array<WatchEntry, MAX_WATCHES> watches;
};
static_assert(std::is_standard_layout_v<TableHeader>);
static_assert(sizeof(TableHeader) == (2 + MAX_WATCHES) * CACHE_LINE_BYTES);
static_assert(MAX_WATCHES <= 64);  // bits of Plane::watchers
static_assert(std::is_trivially_destructible_v<TableHeader> && std::is_trivially_destructible_v<Slot>);
static_assert(std::atomic_ref<std::uint32_t>::is_always_lock_free);
static_assert(offsetof(TableHeader, changeWord) % std::atomic_ref<std::uint32_t>::required_alignment == 0);
static_assert(offsetof(TableHeader, generation) == 48 && offsetof(TableHeader, changeWord) == CACHE_LINE_BYTES);
static_assert(std::atomic_ref<std::uint64_t>::is_always_lock_free);

/// Bytes of a table with `slotCount` slots.
[[nodiscard]] constexpr std::size_t tableBytes(std::size_t slotCount) noexcept {
  return sizeof(TableHeader) + slotCount * sizeof(Slot);
}

// ---- the plane protocol ------------------------------------------------------------------

/// What one write stores (before tagging).
struct Payload {
  std::uint64_t valueBits{};  ///< std::bit_cast<std::uint64_t>(double)
  std::int64_t timestampNs{};
  std::uint32_t aux{};  ///< plane-specific: source/quality, writer, writer/active
};

/// The newest complete write of a plane, as a reader found it.
struct Record {
  Payload payload;
  std::uint64_t ticket{};  ///< 1-based number of the write; 0: the plane was never written
};

[[nodiscard]] constexpr std::uint32_t tagOf(std::uint64_t ticket) noexcept {
  return static_cast<std::uint32_t>(ticket);
}
[[nodiscard]] constexpr std::uint32_t tagOfWord(std::uint64_t word) noexcept {
  return static_cast<std::uint32_t>(word >> 32);
}
[[nodiscard]] constexpr std::uint32_t payloadOfWord(std::uint64_t word) noexcept {
  return static_cast<std::uint32_t>(word);
}
/// Serial-number order on 32-bit tags (RFC 1982 style): true when `a` is after `b`.
/// Valid while the two writes are less than 2^31 tickets apart.
[[nodiscard]] constexpr bool tagIsNewer(std::uint32_t a, std::uint32_t b) noexcept {
  return static_cast<std::int32_t>(a - b) > 0;
}
static_assert(tagIsNewer(1, 0) && !tagIsNewer(0, 1) && !tagIsNewer(7, 7));
static_assert(tagIsNewer(0, 0xFFFFFFFFu));  // across the 2^32 wrap

[[nodiscard]] constexpr std::array<std::uint32_t, ENTRY_WORDS> chunksOf(const Payload& payload) noexcept {
  const auto time = static_cast<std::uint64_t>(payload.timestampNs);
  return {static_cast<std::uint32_t>(payload.valueBits), static_cast<std::uint32_t>(payload.valueBits >> 32),
          static_cast<std::uint32_t>(time), static_cast<std::uint32_t>(time >> 32), payload.aux};
}

[[nodiscard]] constexpr Payload payloadOf(const std::array<std::uint32_t, ENTRY_WORDS>& chunks) noexcept {
  const std::uint64_t time = std::uint64_t{chunks[WORD_TIME_HIGH]} << 32 | chunks[WORD_TIME_LOW];
  return {std::uint64_t{chunks[WORD_VALUE_HIGH]} << 32 | chunks[WORD_VALUE_LOW], static_cast<std::int64_t>(time),
          chunks[WORD_AUX]};
}

/// Step 1 of a write: a new ticket, unique among all writers of this plane.
[[nodiscard]] inline std::uint64_t claimTicket(Plane& plane) noexcept {
  // Relaxed: the tags, not the head, make entries safe to read; the head is sequenced
  // before this writer's release stores, so whoever sees the entry also sees the head.
  return plane.head.fetch_add(1, std::memory_order_relaxed) + 1;
}

/// Step 2 of a write, once per word: stores `chunk` tagged with `ticket` into word `index`
/// of the ticket's entry unless a newer ticket already wrote that word. Returns false when
/// the write is superseded (a newer write owns the entry): the caller stops, its value is
/// older than the one readers will see anyway. Tags in a word only ever grow, so a writer
/// that was delayed past its turn cannot damage a newer entry.
/// Bounded: each failed CAS means an older concurrent writer stored this word; each older
/// writer stores it at most once.
inline bool storeWord(Plane& plane, std::uint64_t ticket, std::size_t index, std::uint32_t chunk) noexcept {
  AtomicWord& word = plane.ring[ticket % RING_SIZE].words[index];
  const std::uint32_t tag = tagOf(ticket);
  const std::uint64_t desired = std::uint64_t{tag} << 32 | chunk;
  std::uint64_t current = word.load(std::memory_order_relaxed);
  while (tagIsNewer(tag, tagOfWord(current))) {
    // Release: a reader that sees this word also sees what this writer did before it.
    if (word.compare_exchange_strong(current, desired, std::memory_order_release, std::memory_order_relaxed)) {
      return true;
    }
  }
  return false;
}

/// Step 2 for all five words in order.
inline void storeEntry(Plane& plane, std::uint64_t ticket, const Payload& payload) noexcept {
  const auto chunks = chunksOf(payload);
  for (std::size_t i = 0; i < ENTRY_WORDS; ++i) {
    if (!storeWord(plane, ticket, i, chunks[i])) return;
  }
}

/// A whole write: claim a ticket, then store the five words in order.
inline void writePlane(Plane& plane, const Payload& payload) noexcept {
  storeEntry(plane, claimTicket(plane), payload);
}

/// The entry of `ticket` if all five words carry its tag.
[[nodiscard]] inline bool readEntry(const Plane& plane, std::uint64_t ticket, Record& out) noexcept {
  const Entry& entry = plane.ring[ticket % RING_SIZE];
  const std::uint32_t tag = tagOf(ticket);
  // Written out word by word so the payload is assembled in registers (a chunk array on
  // the stack cost a store-forwarding stall per read).
  const std::uint64_t valueLow = entry.words[WORD_VALUE_LOW].load(std::memory_order_acquire);
  if (tagOfWord(valueLow) != tag) return false;
  const std::uint64_t valueHigh = entry.words[WORD_VALUE_HIGH].load(std::memory_order_acquire);
  if (tagOfWord(valueHigh) != tag) return false;
  const std::uint64_t timeLow = entry.words[WORD_TIME_LOW].load(std::memory_order_acquire);
  if (tagOfWord(timeLow) != tag) return false;
  const std::uint64_t timeHigh = entry.words[WORD_TIME_HIGH].load(std::memory_order_acquire);
  if (tagOfWord(timeHigh) != tag) return false;
  const std::uint64_t aux = entry.words[WORD_AUX].load(std::memory_order_acquire);
  if (tagOfWord(aux) != tag) return false;
  out.payload.valueBits = std::uint64_t{payloadOfWord(valueHigh)} << 32 | payloadOfWord(valueLow);
  out.payload.timestampNs =
      static_cast<std::int64_t>(std::uint64_t{payloadOfWord(timeHigh)} << 32 | payloadOfWord(timeLow));
  out.payload.aux = payloadOfWord(aux);
  out.ticket = ticket;
  return true;
}

/// The newest complete write among the last RING_SIZE tickets; a never-written plane
/// yields ticket 0 and zeros. False only when READ_ROUNDS windows in a row held no
/// complete entry (RING_SIZE writes unfinished at once, or this reader lapped each time).
/// Wait-free: at most READ_ROUNDS * RING_SIZE * ENTRY_WORDS loads plus READ_ROUNDS head loads.
[[nodiscard]] inline bool readPlane(const Plane& plane, Record& out) noexcept {
  for (int round = 0; round < READ_ROUNDS; ++round) {
    const std::uint64_t head = plane.head.load(std::memory_order_acquire);
    if (head == 0) {
      out = Record{};
      return true;
    }
    const std::uint64_t oldest = head > RING_SIZE ? head - RING_SIZE + 1 : 1;
    for (std::uint64_t ticket = head; ticket >= oldest; --ticket) {
      if (readEntry(plane, ticket, out)) return true;
    }
  }
  return false;
}

/// The bus plane's quality mark: `quality` for write `ticket`. Marks only move forward
/// (a mark for an older write never replaces one for a newer write).
inline void markQuality(Plane& plane, std::uint64_t ticket, std::uint8_t quality) noexcept {
  const std::uint64_t desired = ticket << 8 | quality;
  std::uint64_t current = plane.mark.load(std::memory_order_relaxed);
  while ((current >> 8) <= ticket) {
    if (plane.mark.compare_exchange_strong(current, desired, std::memory_order_release, std::memory_order_relaxed)) {
      return;
    }
  }
}

/// The quality mark for write `ticket`, if one was set for exactly that write.
[[nodiscard]] inline bool markedQuality(const Plane& plane, std::uint64_t ticket, std::uint8_t& quality) noexcept {
  const std::uint64_t mark = plane.mark.load(std::memory_order_acquire);
  if ((mark >> 8) != ticket || ticket == 0) return false;
  quality = static_cast<std::uint8_t>(mark);
  return true;
}

}  // namespace openvcu::signals::detail
