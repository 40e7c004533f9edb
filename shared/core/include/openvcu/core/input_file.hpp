#pragma once
// One rule for every input file openvcu reads by name: DBC files, CAN logs (candump,
// ASC, `replay:` links), configuration text (issue 19).
//
//   1. only a regular file (a symlink to one is fine): a directory, FIFO, socket or
//      device is refused before a byte is read, naming what it is
//        "/dev/zero: not a regular file (character device)"
//   2. at most the kind's size limit (FileKind below), checked at open and again while
//      reading (a file may grow meanwhile)
//        "big.dbc: too large: 70000000 bytes (a DBC file may have at most 64 MiB)"
//   3. opened without blocking (O_NONBLOCK: a FIFO never stalls the open) and read in
//      chunks; between chunks a pending SIGTERM or SIGINT ends the read
//        "huge.log: reading stopped: SIGTERM is pending"
//      (services block both signals and take them from a signalfd, so a long read at
//      start-up would otherwise delay the stop until it ends).
//
// @note thread-safe (no shared state); start-up and loading only (allocates, blocks on
//       disk reads).

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>

#include "openvcu/core/result.hpp"

namespace openvcu::input {

/// What a file is, for messages, and how large it may be.
struct FileKind {
  std::string_view name;   ///< "DBC file": used in "a DBC file may have at most 64 MiB"
  std::uint64_t maxBytes;  ///< the size limit
};

/// DBC files are read whole and parsed in memory (the largest public DBC in the team kit's
/// corpus is under 1 MiB; openvcu.s own about 110 KiB).
inline constexpr FileKind DBC_FILE{"DBC file", std::uint64_t{64} << 20};
/// CAN logs are streamed in constant memory, so the limit only bounds the time a read can
/// take: 64 GiB holds a day of four busses at 3,500 frames/s each in candump -L (52-byte
/// lines, 59 GiB).
inline constexpr FileKind CAN_LOG{"CAN log", std::uint64_t{64} << 30};
/// JSON, CSV and other configuration text read whole (text::readFile).
inline constexpr FileKind TEXT_FILE{"configuration file", std::uint64_t{64} << 20};

/// "regular file", "directory", "character device", "block device", "FIFO", "socket",
/// "symbolic link" or "unknown file type" for a stat st_mode.
[[nodiscard]] std::string_view fileTypeName(unsigned int mode) noexcept;

/// true when SIGTERM or SIGINT is pending for this thread or process (they are pending
/// only while blocked, as in every service: service::ShutdownSignals).
/// @note async-signal-safe, one system call; no allocation.
[[nodiscard]] bool stopSignalPending() noexcept;

/// An open regular file within its kind's size limit; closes on destruction.
/// @note not thread-safe (one reader at a time); read() allocates nothing.
class InputFile {
 public:
  /// Opens `path` under the rules above. Errors carry Location{path}.
  [[nodiscard]] static Result<InputFile> open(const std::string& path, FileKind kind);

  InputFile(InputFile&& other) noexcept;
  InputFile& operator=(InputFile&& other) noexcept;
  InputFile(const InputFile&) = delete;
  InputFile& operator=(const InputFile&) = delete;
  ~InputFile();

  /// The size when opened, in bytes.
  [[nodiscard]] std::uint64_t size() const noexcept { return m_size; }
  /// Bytes read so far.
  [[nodiscard]] std::uint64_t bytesRead() const noexcept { return m_read; }

  enum class ReadStatus : std::uint8_t {
    Data,         ///< `count` bytes were read
    End,          ///< end of the file
    TooLarge,     ///< the file grew beyond the kind's limit; nothing more is read
    StopPending,  ///< SIGTERM or SIGINT is pending; nothing more is read
    Failed,       ///< a read error; `error` holds errno
  };
  struct ReadOutcome {
    ReadStatus status{ReadStatus::End};
    std::size_t count{};
    int error{};
  };
  /// Reads up to `into.size()` bytes (retrying after EINTR). Checks for a pending stop
  /// signal before each read.
  [[nodiscard]] ReadOutcome read(std::span<char> into) noexcept;

  /// The Error for a failed read outcome: "PATH: reading stopped: SIGTERM is pending",
  /// "PATH: too large: more than N bytes (...)", "PATH: cannot read: <reason>".
  [[nodiscard]] Error describe(const ReadOutcome& outcome) const;

 private:
  InputFile(int fd, std::string path, FileKind kind, std::uint64_t size) noexcept;

  int m_fd{-1};
  std::string m_path;
  FileKind m_kind;
  std::uint64_t m_size{};
  std::uint64_t m_read{};
};

/// Reads a whole file of `kind` under the rules above (one allocation of its size).
[[nodiscard]] Result<std::string> readWholeFile(const std::string& path, FileKind kind);

}  // namespace openvcu::input
