#pragma once
// vcu-telemetry's store-and-forward queue (docs/design/telemetry.md, "Store and forward"):
// messages wait here, in order, until the broker has confirmed them (PUBACK), across link
// outages and restarts. Append-only segment files in one folder, bounded by bytes, chosen
// over SQLite by measurement (docs/benchmarks.md, "Telemetry queue").
//
//   auto queue = DiskQueue::open({.folder = "/var/lib/openvcu/telemetry", .maxBytes = 64 << 20});
//   queue->appendBatch(payloads);          // sequence numbers 41..50, fdatasync'ed once
//   auto next = queue->peek(10, 1 << 20);  // records 41..50, oldest first
//   queue->ack(50);                        // the broker confirmed up to 50: gone
//
// Files: seg-<first sequence, 20 digits>.q (records), ack.state (the last acked sequence,
// two CRC-guarded slots written in turn). A record on disk:
//   u32 magic "OVQR" | u32 payload length | u64 sequence | u32 CRC-32C of length, sequence
//   and payload | payload   (little endian, 20 bytes of header)
//
// Segments: a batch goes into the segment being written when it fits there whole, else it
// starts a new segment; a batch larger than a segment is split between records over as many
// new segments as it needs (a record is never split: one larger than a segment is refused).
//
// Durability (fsync policy: per batch): appendBatch() writes the batch with one write and one
// fdatasync() per segment it goes into (one for a batch that fits a segment), each segment
// synced before the next is created, all before it returns; so a power cut or SIGKILL loses at
// most the batch being written, and of a batch split over segments what survives is its first
// records, whole, without a hole. ack() writes its slot without syncing; it reaches the disk with the next
// batch's sync, so a power cut may send a few confirmed
// records again, with their old sequence numbers (MQTT QoS 1 is at-least-once anyway;
// consumers drop a sequence number they have seen).
//
// Bounded: when a batch would take the segment files past maxBytes, whole segments are
// dropped, oldest first, before any of it is written; what they held that was not yet acked is counted (stats()) and
// reported once (takeDrops()).
//
// Never crashes on a damaged folder: open() reads every record, stops a segment at the
// first record that is truncated or fails its CRC, truncates it there and says so (file and
// byte offset) in `warnings`; later segments with good records are kept.
//
// @note not thread-safe: one owner (vcu-telemetry's publisher thread). One process per folder
// (an flock on the folder's lock file refuses a second).

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "openvcu/core/error.hpp"
#include "openvcu/core/result.hpp"

namespace openvcu::telemetry {

struct DiskQueueOptions {
  std::string folder;                      ///< created if missing
  std::uint64_t maxBytes{64ull << 20};     ///< all segment files together, at least 4 segments' worth
  std::uint64_t segmentBytes{0};           ///< 0: maxBytes / 16, at least 64 KiB and at most 4 MiB
};

struct QueueRecord {
  std::uint64_t sequence{};
  std::string payload;
};

/// Records dropped at the byte limit before the broker confirmed them.
struct QueueDrop {
  std::uint64_t firstSequence{};
  std::uint64_t lastSequence{};
  std::uint64_t records{};
};

struct QueueStats {
  std::uint64_t nextSequence{};    ///< the sequence number the next record gets (starts at 1)
  std::uint64_t ackedSequence{};   ///< every record up to here is confirmed (0: none yet)
  std::uint64_t pendingRecords{};  ///< appended, not acked, not dropped
  std::uint64_t diskBytes{};       ///< segment files together
  std::uint64_t droppedRecords{};  ///< since open(): unacked records dropped at the limit
  std::uint64_t droppedBytes{};    ///< since open(): segment bytes deleted at the limit
  std::size_t segments{};
};

class DiskQueue {
 public:
  /// Opens (or creates) the queue in options.folder, recovering what a crash left.
  /// Errors: the folder cannot be created or locked, options out of range, a file cannot be
  /// read or truncated. Damaged records are warnings, never errors.
  static Result<DiskQueue> open(const DiskQueueOptions& options, std::vector<Error>* warnings = nullptr);

  DiskQueue(DiskQueue&& other) noexcept;
  DiskQueue& operator=(DiskQueue&& other) noexcept;
  DiskQueue(const DiskQueue&) = delete;
  DiskQueue& operator=(const DiskQueue&) = delete;
  ~DiskQueue();

  /// Appends the payloads in order with consecutive sequence numbers, one write and one
  /// fdatasync per segment the batch goes into (one when it fits a segment); returns the first
  /// sequence number given. Drops the oldest segments when the limit needs it. Errors, with
  /// nothing of the batch stored: a record (with its 20-byte header) larger than a segment, a
  /// batch larger than maxBytes, or I/O (what was written of the batch is removed again).
  Result<std::uint64_t> appendBatch(std::span<const std::string_view> payloads);
  Result<std::uint64_t> append(std::string_view payload) { return appendBatch({&payload, 1}); }

  /// The oldest records not yet acked, in order: at most maxRecords and (beyond the first
  /// record) at most maxBytes of payload. Does not remove them. Empty when nothing waits.
  Result<std::vector<QueueRecord>> peek(std::size_t maxRecords, std::size_t maxBytes = SIZE_MAX);

  /// The broker confirmed every record up to `sequence`: they will not be peeked again and
  /// fully acked segments are deleted. Error: a sequence not yet given out.
  Status ack(std::uint64_t sequence);

  [[nodiscard]] QueueStats stats() const noexcept;
  /// Drops since the last call (each a contiguous range), then forgets them.
  std::vector<QueueDrop> takeDrops();

 private:
  struct Segment {
    std::string path;
    std::uint64_t firstSequence{};  ///< of its first record (or the next one when empty)
    std::uint64_t lastSequence{};   ///< of its last record; firstSequence - 1 when empty
    std::uint64_t bytes{};
  };

  DiskQueue() = default;
  Status openWriteSegment(std::uint64_t firstSequence);
  /// After a failed append: deletes the segments the batch created and cuts the first one it
  /// wrote to (m_segments[firstIndex]) back to firstBytes.
  void rollbackBatch(std::size_t firstIndex, std::uint64_t firstBytes, std::uint64_t firstLastSequence);
  /// Deletes the oldest segment; atLimit: for room (its unacked records count as dropped).
  Status dropOldestSegment(bool atLimit);
  Status writeAckState();
  Status deleteAckedSegments();
  void closeAll() noexcept;

  DiskQueueOptions m_options;
  std::vector<Segment> m_segments;  ///< oldest first; the last one is written
  int m_writeFd{-1};
  int m_lockFd{-1};
  int m_folderFd{-1};
  int m_ackFd{-1};
  std::uint64_t m_ackGeneration{};
  bool m_ackDirty{false};  ///< ack.state written since the last fdatasync
  std::uint64_t m_nextSequence{1};
  std::uint64_t m_acked{};
  // read cursor: the first unacked record is in m_segments[m_readSegment] at m_readOffset
  std::size_t m_readSegment{};
  std::uint64_t m_readOffset{};
  int m_readFd{-1};
  std::string m_readPath;
  QueueStats m_dropCounts;
  std::vector<QueueDrop> m_drops;
  std::string m_buffer;  ///< encode buffer, reused
  /// where each record of the batch ends in m_buffer
  std::vector<std::uint64_t> m_recordEnds;
};

/// CRC-32C (Castagnoli, reflected polynomial 0x82F63B78) over `data`, continuing from `crc`
/// (0 to start). "123456789" -> 0xE3069283.
[[nodiscard]] std::uint32_t crc32c(std::string_view data, std::uint32_t crc = 0) noexcept;

}  // namespace openvcu::telemetry
