#include "disk_queue.hpp"

#include <dirent.h>
#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <utility>

namespace openvcu::telemetry {
namespace {

static_assert(std::endian::native == std::endian::little, "the queue's files are written in the host's (little) byte order");

constexpr std::uint32_t RECORD_MAGIC = 0x5251564F;  // "OVQR"
constexpr std::uint32_t ACK_MAGIC = 0x4151564F;     // "OVQA"
constexpr std::size_t HEADER_BYTES = 20;
constexpr std::size_t ACK_SLOT_BYTES = 32;
constexpr std::uint64_t MIN_SEGMENT_BYTES = 64 * 1024;
constexpr std::uint64_t MAX_SEGMENT_BYTES = 4ull << 20;
// the largest record any configuration writes: a smaller limit after a restart must not cut
// the records written under a larger one
constexpr std::uint64_t MAX_RECORD_PAYLOAD = MAX_SEGMENT_BYTES;
constexpr std::uint64_t SEGMENTS_PER_LIMIT = 16;
constexpr std::uint64_t MIN_SEGMENTS_PER_LIMIT = 4;
constexpr std::string_view SEGMENT_PREFIX = "seg-";
constexpr std::string_view SEGMENT_SUFFIX = ".q";

constexpr std::array<std::uint32_t, 256> makeCrcTable() {
  std::array<std::uint32_t, 256> table{};
  for (std::uint32_t byte = 0; byte < 256; ++byte) {
    std::uint32_t crc = byte;
    for (int bit = 0; bit < 8; ++bit) crc = (crc & 1u) ? (crc >> 1) ^ 0x82F63B78u : crc >> 1;
    table[byte] = crc;
  }
  return table;
}
constexpr auto CRC_TABLE = makeCrcTable();

std::string systemError(const std::string& what, const std::string& path, int code = errno) {
  return path + ": " + what + ": " + std::strerror(code);
}

template <typename T>
void put(std::string& out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  out.append(bytes, sizeof(T));
}

template <typename T>
T get(const char* in) {
  T value;
  std::memcpy(&value, in, sizeof(T));
  return value;
}

std::string segmentName(std::uint64_t firstSequence) {
  char name[48];
  std::snprintf(name, sizeof name, "seg-%020llu.q", static_cast<unsigned long long>(firstSequence));
  return name;
}

/// pread of exactly `size` bytes: false on a short read or an error.
bool readExactly(int fd, char* out, std::size_t size, std::uint64_t offset) {
  std::size_t done = 0;
  while (done < size) {
    const ssize_t got = ::pread(fd, out + done, size - done, static_cast<off_t>(offset + done));
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0) return false;
    done += static_cast<std::size_t>(got);
  }
  return true;
}

bool writeAll(int fd, const char* data, std::size_t size) {
  std::size_t done = 0;
  while (done < size) {
    const ssize_t wrote = ::write(fd, data + done, size - done);
    if (wrote < 0 && errno == EINTR) continue;
    if (wrote <= 0) return false;
    done += static_cast<std::size_t>(wrote);
  }
  return true;
}

struct RecordHeader {
  std::uint32_t length{};
  std::uint64_t sequence{};
  std::uint32_t crc{};
};

std::uint32_t recordCrc(std::uint32_t length, std::uint64_t sequence, std::string_view payload) {
  char fields[12];
  std::memcpy(fields, &length, 4);
  std::memcpy(fields + 4, &sequence, 8);
  return crc32c(payload, crc32c({fields, sizeof fields}));
}

/// Reads and checks the record at `offset`: its payload, or the reason it is not a record.
Result<QueueRecord> readRecord(int fd, std::uint64_t offset, std::uint64_t fileBytes, std::uint64_t maxPayload) {
  if (fileBytes - offset < HEADER_BYTES) return Error{"truncated record header"};
  char header[HEADER_BYTES];
  if (!readExactly(fd, header, HEADER_BYTES, offset)) return Error{"cannot read the record header"};
  if (get<std::uint32_t>(header) != RECORD_MAGIC) return Error{"not a record (bad magic)"};
  const auto length = get<std::uint32_t>(header + 4);
  const auto sequence = get<std::uint64_t>(header + 8);
  const auto crc = get<std::uint32_t>(header + 16);
  if (length > maxPayload) return Error{"record length " + std::to_string(length) + " larger than any segment"};
  if (fileBytes - offset - HEADER_BYTES < length) return Error{"truncated record payload"};
  QueueRecord record{sequence, std::string(length, '\0')};
  if (length > 0 && !readExactly(fd, record.payload.data(), length, offset + HEADER_BYTES)) {
    return Error{"cannot read the record payload"};
  }
  if (recordCrc(length, sequence, record.payload) != crc) return Error{"CRC mismatch"};
  return record;
}

std::uint64_t unackedIn(std::uint64_t first, std::uint64_t last, std::uint64_t acked) {
  if (last < first || last <= acked) return 0;
  return last - std::max(first, acked + 1) + 1;
}

}  // namespace

std::uint32_t crc32c(std::string_view data, std::uint32_t crc) noexcept {
  crc = ~crc;
  for (const char c : data) crc = CRC_TABLE[(crc ^ static_cast<std::uint8_t>(c)) & 0xFFu] ^ (crc >> 8);
  return ~crc;
}

DiskQueue::DiskQueue(DiskQueue&& other) noexcept { *this = std::move(other); }

DiskQueue& DiskQueue::operator=(DiskQueue&& other) noexcept {
  if (this == &other) return *this;
  closeAll();
  m_options = std::move(other.m_options);
  m_segments = std::move(other.m_segments);
  m_writeFd = std::exchange(other.m_writeFd, -1);
  m_lockFd = std::exchange(other.m_lockFd, -1);
  m_folderFd = std::exchange(other.m_folderFd, -1);
  m_ackFd = std::exchange(other.m_ackFd, -1);
  m_ackGeneration = other.m_ackGeneration;
  m_ackDirty = other.m_ackDirty;
  m_nextSequence = other.m_nextSequence;
  m_acked = other.m_acked;
  m_readSegment = other.m_readSegment;
  m_readOffset = other.m_readOffset;
  m_readFd = std::exchange(other.m_readFd, -1);
  m_readPath = std::move(other.m_readPath);
  m_dropCounts = other.m_dropCounts;
  m_drops = std::move(other.m_drops);
  return *this;
}

DiskQueue::~DiskQueue() { closeAll(); }

void DiskQueue::closeAll() noexcept {
  for (int* fd : {&m_writeFd, &m_readFd, &m_ackFd, &m_folderFd, &m_lockFd}) {
    if (*fd >= 0) ::close(*fd);
    *fd = -1;
  }
}

Result<DiskQueue> DiskQueue::open(const DiskQueueOptions& options, std::vector<Error>* warnings) {
  DiskQueue queue;
  queue.m_options = options;
  if (options.folder.empty()) return Error{"telemetry queue: no folder given"};
  std::uint64_t& segmentBytes = queue.m_options.segmentBytes;
  if (segmentBytes == 0) {
    segmentBytes = std::clamp(options.maxBytes / SEGMENTS_PER_LIMIT, MIN_SEGMENT_BYTES, MAX_SEGMENT_BYTES);
  }
  if (segmentBytes < 2 * HEADER_BYTES || options.maxBytes < MIN_SEGMENTS_PER_LIMIT * segmentBytes) {
    return Error{options.folder + ": a queue limit of " + std::to_string(options.maxBytes) +
                 " bytes is less than 4 segments of " + std::to_string(segmentBytes) + " bytes"};
  }
  std::error_code code;
  std::filesystem::create_directories(options.folder, code);
  if (code) return Error{options.folder + ": cannot create the queue folder: " + code.message()};
  queue.m_folderFd = ::open(options.folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (queue.m_folderFd < 0) return Error{systemError("cannot open the queue folder", options.folder)};
  const std::string lockPath = options.folder + "/lock";
  queue.m_lockFd = ::open(lockPath.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0640);
  if (queue.m_lockFd < 0) return Error{systemError("cannot open", lockPath)};
  if (::flock(queue.m_lockFd, LOCK_EX | LOCK_NB) != 0) {
    return Error{options.folder + ": the queue is in use by another process (" + lockPath + " is locked)"};
  }
  auto warn = [&](std::string message) {
    if (warnings) warnings->push_back(Error{std::move(message), {}, Severity::Warning});
  };

  // the last acked sequence: the valid slot with the higher generation
  const std::string ackPath = options.folder + "/ack.state";
  queue.m_ackFd = ::open(ackPath.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0640);
  if (queue.m_ackFd < 0) return Error{systemError("cannot open", ackPath)};
  struct stat ackStat {};
  if (::fstat(queue.m_ackFd, &ackStat) != 0) return Error{systemError("cannot stat", ackPath)};
  bool anySlot = false;
  for (std::size_t slot = 0; slot < 2; ++slot) {
    char bytes[ACK_SLOT_BYTES];
    if (!readExactly(queue.m_ackFd, bytes, ACK_SLOT_BYTES, slot * ACK_SLOT_BYTES)) continue;
    if (get<std::uint32_t>(bytes) != ACK_MAGIC || crc32c({bytes, 24}) != get<std::uint32_t>(bytes + 24)) continue;
    const auto generation = get<std::uint64_t>(bytes + 8);
    if (!anySlot || generation > queue.m_ackGeneration) {
      queue.m_ackGeneration = generation;
      queue.m_acked = get<std::uint64_t>(bytes + 16);
    }
    anySlot = true;
  }
  if (!anySlot && ackStat.st_size > 0) {
    warn(ackPath + ": no valid slot; every queued record counts as not confirmed and is sent again");
  }

  // the segments, oldest first (20-digit names sort as numbers)
  std::vector<std::string> names;
  if (DIR* dir = ::opendir(options.folder.c_str())) {
    while (const dirent* entry = ::readdir(dir)) {
      const std::string_view name = entry->d_name;
      if (name.starts_with(SEGMENT_PREFIX) && name.ends_with(SEGMENT_SUFFIX)) names.emplace_back(name);
    }
    ::closedir(dir);
  } else {
    return Error{systemError("cannot list the queue folder", options.folder)};
  }
  std::sort(names.begin(), names.end());
  std::uint64_t lastSequence = 0;
  for (const std::string& name : names) {
    const std::string path = options.folder + "/" + name;
    const int fd = ::open(path.c_str(), O_RDWR | O_CLOEXEC);
    if (fd < 0) return Error{systemError("cannot open", path)};
    struct stat fileStat {};
    if (::fstat(fd, &fileStat) != 0) {
      const int error = errno;
      ::close(fd);
      return Error{systemError("cannot stat", path, error)};
    }
    const auto fileBytes = static_cast<std::uint64_t>(fileStat.st_size);
    Segment segment{path, 0, 0, 0};
    std::uint64_t offset = 0;
    std::uint64_t records = 0;
    while (offset < fileBytes) {
      auto record = readRecord(fd, offset, fileBytes, std::max(segmentBytes, MAX_RECORD_PAYLOAD));
      std::string problem;
      if (!record) problem = record.error().message;
      else if (record->sequence <= lastSequence) problem = "sequence " + std::to_string(record->sequence) + " out of order";
      else if (records > 0 && record->sequence != segment.lastSequence + 1) problem = "sequence gap inside the segment";
      if (!problem.empty()) {
        warn(path + ": byte offset " + std::to_string(offset) + ": " + problem + "; recovered " + std::to_string(records) +
             " records before it, cut the " + std::to_string(fileBytes - offset) + " bytes from there");
        if (::ftruncate(fd, static_cast<off_t>(offset)) != 0 || ::fdatasync(fd) != 0) {
          const int error = errno;
          ::close(fd);
          return Error{systemError("cannot truncate a damaged segment", path, error)};
        }
        break;
      }
      if (records == 0) segment.firstSequence = record->sequence;
      segment.lastSequence = record->sequence;
      lastSequence = record->sequence;
      offset += HEADER_BYTES + record->payload.size();
      ++records;
    }
    ::close(fd);
    segment.bytes = offset;
    if (records == 0) {
      ::unlink(path.c_str());
      continue;
    }
    queue.m_segments.push_back(std::move(segment));
  }
  queue.m_nextSequence = std::max(lastSequence, queue.m_acked) + 1;
  if (auto deleted = queue.deleteAckedSegments(); !deleted) return deleted.error();
  // the read cursor: the first record after the acked one
  queue.m_readSegment = 0;
  queue.m_readOffset = 0;
  if (!queue.m_segments.empty() && queue.m_segments.front().firstSequence <= queue.m_acked) {
    const Segment& front = queue.m_segments.front();
    const int fd = ::open(front.path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) return Error{systemError("cannot open", front.path)};
    while (queue.m_readOffset < front.bytes) {
      auto record = readRecord(fd, queue.m_readOffset, front.bytes, std::max(segmentBytes, MAX_RECORD_PAYLOAD));
      if (!record || record->sequence > queue.m_acked) break;
      queue.m_readOffset += HEADER_BYTES + record->payload.size();
    }
    ::close(fd);
  }
  return queue;
}

Status DiskQueue::openWriteSegment(std::uint64_t firstSequence) {
  if (m_writeFd >= 0) ::close(m_writeFd);
  m_writeFd = -1;
  Segment segment{m_options.folder + "/" + segmentName(firstSequence), firstSequence, firstSequence - 1, 0};
  m_writeFd = ::open(segment.path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_APPEND | O_CLOEXEC, 0640);
  if (m_writeFd < 0) return Error{systemError("cannot create a segment", segment.path)};
  m_segments.push_back(std::move(segment));  // listed at once: it exists and is the one written
  // the new name must survive a power cut too
  if (::fsync(m_folderFd) != 0) return Error{systemError("cannot sync the queue folder", m_options.folder)};
  return {};
}

Status DiskQueue::dropOldestSegment(bool atLimit) {
  const Segment dropped = m_segments.front();
  if (m_readFd >= 0 && m_readPath == dropped.path) {
    ::close(m_readFd);
    m_readFd = -1;
  }
  if (::unlink(dropped.path.c_str()) != 0) return Error{systemError("cannot delete a segment", dropped.path)};
  m_segments.erase(m_segments.begin());
  if (m_readSegment > 0) {
    --m_readSegment;
  } else {
    m_readOffset = 0;
  }
  const std::uint64_t lost = unackedIn(dropped.firstSequence, dropped.lastSequence, m_acked);
  if (atLimit) m_dropCounts.droppedBytes += dropped.bytes;
  if (lost > 0) {
    m_dropCounts.droppedRecords += lost;
    const std::uint64_t first = std::max(dropped.firstSequence, m_acked + 1);
    if (!m_drops.empty() && m_drops.back().lastSequence + 1 == first) {
      m_drops.back().lastSequence = dropped.lastSequence;
      m_drops.back().records += lost;
    } else {
      m_drops.push_back({first, dropped.lastSequence, lost});
    }
  }
  return {};
}

Status DiskQueue::deleteAckedSegments() {
  while (!m_segments.empty() && m_segments.front().lastSequence <= m_acked) {
    const bool isWriteSegment = m_writeFd >= 0 && m_segments.size() == 1;
    if (isWriteSegment) break;
    if (auto dropped = dropOldestSegment(false); !dropped) return dropped;
  }
  return {};
}

Status DiskQueue::writeAckState() {
  ++m_ackGeneration;
  std::string slot;
  put(slot, ACK_MAGIC);
  put(slot, std::uint32_t{0});
  put(slot, m_ackGeneration);
  put(slot, m_acked);
  put(slot, crc32c(slot));
  put(slot, std::uint32_t{0});
  const auto offset = static_cast<off_t>((m_ackGeneration % 2) * ACK_SLOT_BYTES);
  if (::pwrite(m_ackFd, slot.data(), slot.size(), offset) != static_cast<ssize_t>(slot.size())) {
    return Error{systemError("cannot write", m_options.folder + "/ack.state")};
  }
  m_ackDirty = true;
  return {};
}

Result<std::uint64_t> DiskQueue::appendBatch(std::span<const std::string_view> payloads) {
  if (payloads.empty()) return m_nextSequence;
  const std::uint64_t segmentBytes = m_options.segmentBytes;
  m_buffer.clear();
  m_recordEnds.clear();
  std::uint64_t sequence = m_nextSequence;
  for (std::size_t i = 0; i < payloads.size(); ++i) {
    const std::string_view payload = payloads[i];
    if (HEADER_BYTES + payload.size() > segmentBytes) {
      return Error{m_options.folder + ": record " + std::to_string(i + 1) + " of a batch of " +
                   std::to_string(payloads.size()) + " is " + std::to_string(HEADER_BYTES + payload.size()) +
                   " bytes with its header, larger than a segment (" + std::to_string(segmentBytes) +
                   " bytes); nothing of the batch is stored"};
    }
    const auto length = static_cast<std::uint32_t>(payload.size());
    put(m_buffer, RECORD_MAGIC);
    put(m_buffer, length);
    put(m_buffer, sequence);
    put(m_buffer, recordCrc(length, sequence, payload));
    m_buffer.append(payload);
    m_recordEnds.push_back(m_buffer.size());
    ++sequence;
  }
  const std::uint64_t batchBytes = m_buffer.size();
  if (batchBytes > m_options.maxBytes) {
    return Error{m_options.folder + ": a batch of " + std::to_string(batchBytes) + " bytes is larger than the queue limit (" +
                 std::to_string(m_options.maxBytes) + " bytes); nothing of it is stored"};
  }
  // a batch starts a new segment unless it fits whole into the one being written (or that one
  // is still empty); a batch larger than a segment then fills one segment after the other
  if (m_writeFd < 0 || (m_segments.back().bytes > 0 && m_segments.back().bytes + batchBytes > segmentBytes)) {
    if (auto opened = openWriteSegment(m_nextSequence); !opened) return opened.error();
  }
  // room for the whole batch before anything is written: whole segments, oldest first (the
  // segment being written stays; it holds at most a segment, the batch at most the limit)
  auto diskBytes = [&] {
    std::uint64_t total = 0;
    for (const Segment& segment : m_segments) total += segment.bytes;
    return total;
  };
  while (m_segments.size() > 1 && diskBytes() + batchBytes > m_options.maxBytes) {
    if (auto dropped = dropOldestSegment(true); !dropped) return dropped.error();
  }
  const std::size_t firstIndex = m_segments.size() - 1;
  const std::uint64_t firstBytes = m_segments.back().bytes;
  const std::uint64_t firstLastSequence = m_segments.back().lastSequence;
  const std::uint64_t first = m_nextSequence;
  std::size_t record = 0;
  std::uint64_t chunkBegin = 0;
  while (record < m_recordEnds.size()) {
    // the records that fit into this segment: at least one (each fits an empty segment)
    Segment& segment = m_segments.back();
    std::size_t end = record;
    while (end < m_recordEnds.size() && segment.bytes + (m_recordEnds[end] - chunkBegin) <= segmentBytes) ++end;
    const std::uint64_t chunkEnd = m_recordEnds[end - 1];
    // synced before the next segment is created: after a crash the batch is there up to a
    // record boundary, never with a hole
    if (!writeAll(m_writeFd, m_buffer.data() + chunkBegin, chunkEnd - chunkBegin) || ::fdatasync(m_writeFd) != 0) {
      const Error error{systemError("cannot append to", segment.path)};
      rollbackBatch(firstIndex, firstBytes, firstLastSequence);
      return error;
    }
    if (segment.bytes == 0) segment.firstSequence = first + record;
    segment.bytes += chunkEnd - chunkBegin;
    segment.lastSequence = first + end - 1;
    record = end;
    chunkBegin = chunkEnd;
    if (record < m_recordEnds.size()) {
      if (auto opened = openWriteSegment(first + record); !opened) {
        rollbackBatch(firstIndex, firstBytes, firstLastSequence);
        return opened.error();
      }
    }
  }
  if (m_ackDirty) {
    ::fdatasync(m_ackFd);
    m_ackDirty = false;
  }
  m_nextSequence = sequence;
  return first;
}

void DiskQueue::rollbackBatch(std::size_t firstIndex, std::uint64_t firstBytes, std::uint64_t firstLastSequence) {
  // the segments this batch created go; the first one it wrote to is cut back to its old length
  // (a cut that fails leaves whole records the next open() keeps; the disk is failing then)
  while (m_segments.size() > firstIndex + 1) {
    const Segment& created = m_segments.back();
    if (m_readFd >= 0 && m_readPath == created.path) {
      ::close(m_readFd);
      m_readFd = -1;
    }
    ::unlink(created.path.c_str());
    m_segments.pop_back();
    if (m_writeFd >= 0) ::close(m_writeFd);
    m_writeFd = -1;
  }
  Segment& segment = m_segments[firstIndex];
  if (m_writeFd >= 0) {
    if (::ftruncate(m_writeFd, static_cast<off_t>(firstBytes)) != 0) { /* see above */ }
  } else {
    if (::truncate(segment.path.c_str(), static_cast<off_t>(firstBytes)) != 0) { /* see above */ }
    if (firstBytes == 0) {  // no write segment any more: the next batch creates one under this name
      if (m_readFd >= 0 && m_readPath == segment.path) {
        ::close(m_readFd);
        m_readFd = -1;
      }
      ::unlink(segment.path.c_str());
      m_segments.pop_back();
      return;
    }
  }
  segment.bytes = firstBytes;
  segment.lastSequence = firstLastSequence;
}

Result<std::vector<QueueRecord>> DiskQueue::peek(std::size_t maxRecords, std::size_t maxBytes) {
  std::vector<QueueRecord> records;
  std::size_t payloadBytes = 0;
  std::size_t index = m_readSegment;
  std::uint64_t offset = m_readOffset;
  while (records.size() < maxRecords && index < m_segments.size()) {
    const Segment& segment = m_segments[index];
    if (offset >= segment.bytes) {
      ++index;
      offset = 0;
      continue;
    }
    if (m_readPath != segment.path || m_readFd < 0) {
      if (m_readFd >= 0) ::close(m_readFd);
      m_readPath = segment.path;
      m_readFd = ::open(segment.path.c_str(), O_RDONLY | O_CLOEXEC);
      if (m_readFd < 0) return Error{systemError("cannot open", segment.path)};
    }
    auto record = readRecord(m_readFd, offset, segment.bytes, std::max(m_options.segmentBytes, MAX_RECORD_PAYLOAD));
    if (!record) return Error{segment.path + ": byte offset " + std::to_string(offset) + ": " + record.error().message};
    if (!records.empty() && payloadBytes + record->payload.size() > maxBytes) break;
    offset += HEADER_BYTES + record->payload.size();
    payloadBytes += record->payload.size();
    if (record->sequence > m_acked) records.push_back(std::move(*record));
  }
  return records;
}

Status DiskQueue::ack(std::uint64_t sequence) {
  if (sequence >= m_nextSequence) {
    return Error{m_options.folder + ": ack of sequence " + std::to_string(sequence) + ", never given out (next is " +
                 std::to_string(m_nextSequence) + ")"};
  }
  if (sequence <= m_acked) return {};
  m_acked = sequence;
  // move the cursor past the acked records: whole segments at once, then record by record
  while (m_readSegment < m_segments.size()) {
    const Segment& segment = m_segments[m_readSegment];
    if (segment.lastSequence <= m_acked && m_readSegment + 1 < m_segments.size()) {
      ++m_readSegment;
      m_readOffset = 0;
      continue;
    }
    if (segment.lastSequence <= m_acked) {
      m_readOffset = segment.bytes;
      break;
    }
    if (m_readPath != segment.path || m_readFd < 0) {
      if (m_readFd >= 0) ::close(m_readFd);
      m_readPath = segment.path;
      m_readFd = ::open(segment.path.c_str(), O_RDONLY | O_CLOEXEC);
      if (m_readFd < 0) return Error{systemError("cannot open", segment.path)};
    }
    char header[HEADER_BYTES];
    while (m_readOffset < segment.bytes) {
      if (!readExactly(m_readFd, header, HEADER_BYTES, m_readOffset)) {
        return Error{systemError("cannot read", segment.path)};
      }
      if (get<std::uint64_t>(header + 8) > m_acked) break;
      m_readOffset += HEADER_BYTES + get<std::uint32_t>(header + 4);
    }
    break;
  }
  // the state first: a process killed in between must not find acked segments deleted while
  // ack.state still names an older sequence (the reopened queue would start after a hole)
  if (auto written = writeAckState(); !written) return written;
  return deleteAckedSegments();
}

QueueStats DiskQueue::stats() const noexcept {
  QueueStats result = m_dropCounts;
  result.nextSequence = m_nextSequence;
  result.ackedSequence = m_acked;
  result.segments = m_segments.size();
  for (const Segment& segment : m_segments) {
    result.diskBytes += segment.bytes;
    result.pendingRecords += unackedIn(segment.firstSequence, segment.lastSequence, m_acked);
  }
  return result;
}

std::vector<QueueDrop> DiskQueue::takeDrops() { return std::exchange(m_drops, {}); }

}  // namespace openvcu::telemetry
