#pragma once
// The POSIX side of a signal table: the shared-memory segment, its lock file and the
// create / attach / re-create protocol's building blocks (docs/design/signal-table.md,
// "Creation and attachment"). Start-up code only: allocates and makes system calls.

#include <sys/types.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "openvcu/core/result.hpp"

namespace openvcu::signals::detail {

/// An owned file descriptor (closed on destruction; closing drops our flock locks).
class UniqueFd {
 public:
  UniqueFd() = default;
  explicit UniqueFd(int fd) noexcept : m_fd(fd) {}
  UniqueFd(UniqueFd&& other) noexcept : m_fd(other.release()) {}
  UniqueFd& operator=(UniqueFd&& other) noexcept;
  UniqueFd(const UniqueFd&) = delete;
  UniqueFd& operator=(const UniqueFd&) = delete;
  ~UniqueFd();

  [[nodiscard]] int get() const noexcept { return m_fd; }
  [[nodiscard]] int release() noexcept {
    const int fd = m_fd;
    m_fd = -1;
    return fd;
  }

 private:
  int m_fd{-1};
};

/// An owned MAP_SHARED mapping (unmapped on destruction).
class Mapping {
 public:
  Mapping() = default;
  Mapping(void* base, std::size_t bytes) noexcept : m_base(base), m_bytes(bytes) {}
  Mapping(Mapping&& other) noexcept;
  Mapping& operator=(Mapping&& other) noexcept;
  Mapping(const Mapping&) = delete;
  Mapping& operator=(const Mapping&) = delete;
  ~Mapping();

  [[nodiscard]] void* base() const noexcept { return m_base; }
  [[nodiscard]] std::size_t bytes() const noexcept { return m_bytes; }
  /// Gives up ownership (the caller unmaps base() with bytes()).
  void* release() noexcept;

 private:
  void* m_base{nullptr};
  std::size_t m_bytes{};
};

struct Names {
  std::string display;      ///< "openvcu-hhea" (messages)
  std::string shmName;      ///< "/openvcu-hhea" (shm_open)
  std::string segmentPath;  ///< "/dev/shm/openvcu-hhea"
  std::string lockPath;     ///< "/dev/shm/openvcu-hhea.lock"
};
[[nodiscard]] Names namesFor(std::string_view instance);

/// What this process expects the table to be.
struct Expected {
  std::uint64_t layoutHash{};
  std::uint32_t slotCount{};
};

/// Opens the lock file (creating it with `mode` when `create`) and takes LOCK_SH, waiting at
/// most a few seconds for a process that holds LOCK_EX (a creator). Retries when the path was
/// replaced under us, so the lock we hold is always the one the path names.
[[nodiscard]] Result<UniqueFd> lockShared(const Names& names, bool create, mode_t mode);

/// LOCK_EX | LOCK_NB on a descriptor that holds LOCK_SH: true when no other process holds
/// the lock. On failure the descriptor may have lost its LOCK_SH (Linux converts by
/// unlocking first): the caller must close it.
[[nodiscard]] bool tryLockExclusive(int fd) noexcept;

enum class SegmentState : std::uint8_t {
  Missing,     ///< no segment of this name
  Incomplete,  ///< left half-built by a killed creator, or not a signal table
  Mismatch,    ///< a complete table of another layout or format version
  Ready,       ///< complete and matches `Expected`: mapped
};

struct Probe {
  SegmentState state{SegmentState::Missing};
  Mapping mapping;     ///< Ready only
  UniqueFd segment;    ///< Ready only: the segment, read-write (kept to restore its size after damage)
  std::uint64_t generation{};  ///< Ready only: the header's generation (0: a table of an older build)
  ino_t inode{};       ///< the segment's inode when it exists
  std::string reason;  ///< Missing / Incomplete / Mismatch: a sentence for the user
};

/// Opens and checks the segment; the caller holds LOCK_SH (so nobody re-creates it meanwhile).
[[nodiscard]] Result<Probe> probeSegment(const Names& names, const Expected& expected);

/// Builds a fresh table under the segment name (removing the old name first) and returns
/// its inode. The caller holds LOCK_EX. Killed half-way, it leaves an Incomplete segment.
[[nodiscard]] Result<ino_t> createSegment(const Names& names, const Expected& expected, mode_t mode);

/// Unlinks the segment and lock file names (missing names are fine).
[[nodiscard]] Status unlinkNames(const Names& names);

/// "No such file or directory (errno 2)".
[[nodiscard]] std::string errnoText(int error);

}  // namespace openvcu::signals::detail
