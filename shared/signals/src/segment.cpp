#include "segment.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cinttypes>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <new>

#include "fault_guard.hpp"
#include "layout.hpp"
#include "openvcu/signals/catalog.hpp"

namespace openvcu::signals::detail {

namespace {

constexpr std::int64_t LOCK_WAIT_NS = 5'000'000'000;  // longest wait for a creator's LOCK_EX
constexpr int LOCK_PATH_ATTEMPTS = 20;                // path replaced under us this often: give up
constexpr std::int64_t NS_PER_SECOND = 1'000'000'000;
constexpr std::int64_t FIRST_POLL_NS = 100'000;
constexpr std::int64_t LONGEST_POLL_NS = 10'000'000;

const char* const RESET_ADVICE = "stop every service of this instance or run `vcu table reset`";

std::int64_t clockNs(clockid_t clock) noexcept {
  timespec now{};
  clock_gettime(clock, &now);
  return static_cast<std::int64_t>(now.tv_sec) * NS_PER_SECOND + now.tv_nsec;
}

void sleepNs(std::int64_t ns) noexcept {
  timespec duration{static_cast<time_t>(ns / NS_PER_SECOND), static_cast<long>(ns % NS_PER_SECOND)};
  while (nanosleep(&duration, &duration) != 0 && errno == EINTR) {
  }
}

std::string hex64(std::uint64_t value) {
  char text[24];
  std::snprintf(text, sizeof text, "0x%016" PRIx64, value);
  return text;
}

Error systemError(const std::string& what, const std::string& path, int error) {
  std::string message = what + " " + path + ": " + errnoText(error);
  if (error == EACCES || error == EPERM) {
    message +=
        " (it belongs to another user; run every service of the instance as one user, or "
        "open with Permissions::OwnerAndGroup for a shared group)";
  }
  return Error{std::move(message)};
}

/// Takes LOCK_SH on `fd`, polling so that a stopped creator yields an error, not a hang.
Status waitShared(int fd, const std::string& path) {
  const std::int64_t deadline = clockNs(CLOCK_MONOTONIC) + LOCK_WAIT_NS;
  std::int64_t pollNs = FIRST_POLL_NS;
  for (;;) {
    if (flock(fd, LOCK_SH | LOCK_NB) == 0) return {};
    if (errno == EINTR) continue;
    if (errno != EWOULDBLOCK) return systemError("cannot lock", path, errno);
    if (clockNs(CLOCK_MONOTONIC) >= deadline) {
      return Error{"table lock " + path + " has been held by a creating process for more than " +
                   std::to_string(LOCK_WAIT_NS / NS_PER_SECOND) + " s (is it stopped?)"};
    }
    sleepNs(pollNs);
    pollNs = std::min(pollNs * 2, LONGEST_POLL_NS);
  }
}

}  // namespace

UniqueFd& UniqueFd::operator=(UniqueFd&& other) noexcept {
  if (this != &other) {
    if (m_fd >= 0) ::close(m_fd);
    m_fd = other.release();
  }
  return *this;
}

UniqueFd::~UniqueFd() {
  if (m_fd >= 0) ::close(m_fd);
}

Mapping::Mapping(Mapping&& other) noexcept : m_base(other.m_base), m_bytes(other.m_bytes) {
  other.m_base = nullptr;
  other.m_bytes = 0;
}

Mapping& Mapping::operator=(Mapping&& other) noexcept {
  if (this != &other) {
    if (m_base != nullptr) munmap(m_base, m_bytes);
    m_base = other.m_base;
    m_bytes = other.m_bytes;
    other.m_base = nullptr;
    other.m_bytes = 0;
  }
  return *this;
}

Mapping::~Mapping() {
  if (m_base != nullptr) munmap(m_base, m_bytes);
}

void* Mapping::release() noexcept {
  void* base = m_base;
  m_base = nullptr;
  m_bytes = 0;
  return base;
}

std::string errnoText(int error) {
  return std::string(std::strerror(error)) + " (errno " + std::to_string(error) + ")";
}

Names namesFor(std::string_view instance) {
  Names names;
  names.display = "openvcu-" + std::string(instance);
  names.shmName = "/" + names.display;
  names.segmentPath = "/dev/shm/" + names.display;
  names.lockPath = names.segmentPath + ".lock";
  return names;
}

Result<UniqueFd> lockShared(const Names& names, bool create, mode_t mode) {
  for (int attempt = 0; attempt < LOCK_PATH_ATTEMPTS; ++attempt) {
    UniqueFd lock;
    if (create) {
      lock = UniqueFd(::open(names.lockPath.c_str(), O_RDONLY | O_CLOEXEC | O_CREAT | O_EXCL, mode));
      if (lock.get() >= 0) {
        if (fchmod(lock.get(), mode) != 0) return systemError("cannot set the mode of", names.lockPath, errno);
      } else if (errno != EEXIST) {
        return systemError("cannot create", names.lockPath, errno);
      }
    }
    if (lock.get() < 0) {
      lock = UniqueFd(::open(names.lockPath.c_str(), O_RDONLY | O_CLOEXEC));
      if (lock.get() < 0) {
        if (errno == ENOENT && create) continue;  // removed between our two opens
        if (errno == ENOENT) {
          return Error{"no signal table '" + names.display + "': no service of this instance has created it yet"};
        }
        return systemError("cannot open", names.lockPath, errno);
      }
    }
    if (auto lockStatus = waitShared(lock.get(), names.lockPath); !lockStatus) return lockStatus.error();
    // The lock only protects the table if the path still names the file we locked (a
    // `vcu table reset` may have replaced it while we waited).
    struct stat locked {};
    struct stat named {};
    if (fstat(lock.get(), &locked) != 0) return systemError("cannot stat", names.lockPath, errno);
    if (stat(names.lockPath.c_str(), &named) == 0 && named.st_dev == locked.st_dev && named.st_ino == locked.st_ino) {
      return lock;
    }
  }
  return Error{"table lock " + names.lockPath + " keeps being replaced; is `vcu table reset` running in a loop?"};
}

bool tryLockExclusive(int fd) noexcept {
  for (;;) {
    if (flock(fd, LOCK_EX | LOCK_NB) == 0) return true;
    if (errno != EINTR) return false;
  }
}

Result<Probe> probeSegment(const Names& names, const Expected& expected) {
  Probe probe;
  UniqueFd segment(shm_open(names.shmName.c_str(), O_RDWR | O_CLOEXEC, 0));
  if (segment.get() < 0) {
    if (errno != ENOENT) return systemError("cannot open", names.segmentPath, errno);
    probe.state = SegmentState::Missing;
    probe.reason = "no signal table '" + names.display + "': no service of this instance has created it yet";
    return probe;
  }
  struct stat status {};
  if (fstat(segment.get(), &status) != 0) return systemError("cannot stat", names.segmentPath, errno);
  probe.inode = status.st_ino;
  const auto bytes = static_cast<std::size_t>(status.st_size);
  probe.state = SegmentState::Incomplete;
  probe.reason = "table '" + names.display +
                 "' is incomplete (its creator stopped half-way, or it is not a signal table): start any "
                 "service of this instance to re-create it, or run `vcu table reset`";
  if (bytes < sizeof(TableHeader)) return probe;

  void* base = mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_SHARED | MAP_POPULATE, segment.get(), 0);
  if (base == MAP_FAILED) return systemError("cannot map", names.segmentPath, errno);
  Mapping mapping(base, bytes);
  // Truncated while we look: the reads below see zeros (an incomplete table), not SIGBUS.
  const ScopedGuard guard(base, bytes, -1);
  // Attachers see the objects the creator constructed in the shared segment.
  const auto* header = std::launder(static_cast<const TableHeader*>(base));
  if (header->magic.load(std::memory_order_acquire) != TABLE_MAGIC) return probe;

  if (header->formatVersion != SIGNAL_TABLE_FORMAT_VERSION || header->headerBytes != sizeof(TableHeader) ||
      header->slotBytes != sizeof(Slot)) {
    probe.state = SegmentState::Mismatch;
    probe.reason = "table '" + names.display + "' was created by another openvcu build (table format " +
                   std::to_string(header->formatVersion) +
                   "; this process: " + std::to_string(SIGNAL_TABLE_FORMAT_VERSION) + "): " + RESET_ADVICE;
    return probe;
  }
  if (bytes != tableBytes(header->slotCount)) return probe;  // damaged: treat like a half-built table
  if (header->layoutHash != expected.layoutHash || header->slotCount != expected.slotCount) {
    probe.state = SegmentState::Mismatch;
    probe.reason = "table '" + names.display + "' was created from another configuration (layout " +
                   hex64(header->layoutHash) + ", " + std::to_string(header->slotCount) +
                   " signals; this process: " + hex64(expected.layoutHash) + ", " + std::to_string(expected.slotCount) +
                   "): " + RESET_ADVICE;
    return probe;
  }
  probe.state = SegmentState::Ready;
  probe.reason.clear();
  probe.generation = std::atomic_ref<std::uint64_t>(const_cast<TableHeader*>(header)->generation)
                         .load(std::memory_order_acquire);
  probe.mapping = std::move(mapping);
  probe.segment = std::move(segment);
  return probe;
}

Result<ino_t> createSegment(const Names& names, const Expected& expected, mode_t mode) {
  if (shm_unlink(names.shmName.c_str()) != 0 && errno != ENOENT) {
    return systemError("cannot remove the old table", names.segmentPath, errno);
  }
  UniqueFd segment(shm_open(names.shmName.c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, mode));
  if (segment.get() < 0) return systemError("cannot create", names.segmentPath, errno);
  // shm_open applies the umask; set the exact mode we promise.
  if (fchmod(segment.get(), mode) != 0) return systemError("cannot set the mode of", names.segmentPath, errno);
  const std::size_t bytes = tableBytes(expected.slotCount);
  if (ftruncate(segment.get(), static_cast<off_t>(bytes)) != 0) {
    return systemError("cannot size", names.segmentPath, errno);
  }
  // Reserve the pages now: a full /dev/shm is an error here instead of a SIGBUS later.
  if (const int error = posix_fallocate(segment.get(), 0, static_cast<off_t>(bytes)); error != 0) {
    return systemError("cannot allocate", names.segmentPath, error);
  }
  void* base = mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_SHARED, segment.get(), 0);
  if (base == MAP_FAILED) return systemError("cannot map", names.segmentPath, errno);
  Mapping mapping(base, bytes);
  // Truncated while we build it: the size is restored and the stores land (the next probe
  // checks the result like any other table).
  const ScopedGuard guard(base, bytes, segment.get());

  // The pages are zero, which is the valid empty state of every slot; constructing the
  // objects starts their lifetime without changing a byte.
  auto* header = new (base) TableHeader{};
  auto* slots = reinterpret_cast<Slot*>(static_cast<unsigned char*>(base) + sizeof(TableHeader));
  for (std::uint32_t i = 0; i < expected.slotCount; ++i) new (&slots[i]) Slot{};
  header->formatVersion = SIGNAL_TABLE_FORMAT_VERSION;
  header->headerBytes = sizeof(TableHeader);
  header->layoutHash = expected.layoutHash;
  header->slotCount = expected.slotCount;
  header->slotBytes = sizeof(Slot);
  header->createdRealtimeNs = clockNs(CLOCK_REALTIME);
  header->creatorPid = static_cast<std::int32_t>(getpid());
  std::atomic_ref<std::uint64_t>(header->generation).store(freshGeneration(), std::memory_order_relaxed);
  // Last: the magic number says "complete". Release pairs with the attachers' acquire load.
  header->magic.store(TABLE_MAGIC, std::memory_order_release);

  struct stat status {};
  if (fstat(segment.get(), &status) != 0) return systemError("cannot stat", names.segmentPath, errno);
  return status.st_ino;
}

Status unlinkNames(const Names& names) {
  if (shm_unlink(names.shmName.c_str()) != 0 && errno != ENOENT) {
    return systemError("cannot remove", names.segmentPath, errno);
  }
  if (unlink(names.lockPath.c_str()) != 0 && errno != ENOENT) {
    return systemError("cannot remove", names.lockPath, errno);
  }
  return {};
}

}  // namespace openvcu::signals::detail
