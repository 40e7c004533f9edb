#include "replay_guard.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <utility>

#include "openvcu/core/text.hpp"

namespace openvcu::telemetry {
namespace {

constexpr std::string_view HEADER = "openvcu remote commands v1 floor ";
/// The file is rewritten when it holds more than this many lines beyond twice the live ones.
constexpr std::size_t REWRITE_SLACK_LINES = 64;

std::string systemError(const std::string& what, const std::string& path, int code = errno) {
  return path + ": " + what + ": " + std::strerror(code);
}

std::optional<std::int64_t> parseInteger(std::string_view text) {
  std::int64_t value = 0;
  const auto parsed = std::from_chars(text.data(), text.data() + text.size(), value);
  if (parsed.ec != std::errc{} || parsed.ptr != text.data() + text.size() || value < 0) return std::nullopt;
  return value;
}

/// A cmdId as the handler accepts it (1-64 of A-Z a-z 0-9 - _ .): anything else in the file is damage.
bool isCmdId(std::string_view id) {
  if (id.empty() || id.size() > 64) return false;
  return std::all_of(id.begin(), id.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' || c == '_' ||
           c == '.';
  });
}

bool writeAll(int fd, std::string_view bytes) {
  while (!bytes.empty()) {
    const ssize_t written = ::write(fd, bytes.data(), bytes.size());
    if (written < 0 && errno == EINTR) continue;
    if (written <= 0) return false;
    bytes.remove_prefix(static_cast<std::size_t>(written));
  }
  return true;
}

std::string entryLine(std::string_view cmdId, std::int64_t deadlineUnixMs) {
  return std::to_string(deadlineUnixMs) + ' ' + std::string(cmdId) + '\n';
}

}  // namespace

ReplayGuard::ReplayGuard(ReplayGuard&& other) noexcept
    : m_folder(std::move(other.m_folder)),
      m_path(std::move(other.m_path)),
      m_fd(std::exchange(other.m_fd, -1)),
      m_floorUnixMs(other.m_floorUnixMs),
      m_deadlines(std::move(other.m_deadlines)),
      m_fileLines(other.m_fileLines) {}

ReplayGuard& ReplayGuard::operator=(ReplayGuard&& other) noexcept {
  if (this != &other) {
    closeFile();
    m_folder = std::move(other.m_folder);
    m_path = std::move(other.m_path);
    m_fd = std::exchange(other.m_fd, -1);
    m_floorUnixMs = other.m_floorUnixMs;
    m_deadlines = std::move(other.m_deadlines);
    m_fileLines = other.m_fileLines;
  }
  return *this;
}

ReplayGuard::~ReplayGuard() {
  closeFile();
}

void ReplayGuard::closeFile() noexcept {
  if (m_fd >= 0) ::close(m_fd);
  m_fd = -1;
}

Result<ReplayGuard> ReplayGuard::open(const std::string& folder, std::vector<Error>* warnings) {
  ReplayGuard guard;
  guard.m_folder = folder;
  guard.m_path = folder + "/" + std::string(REPLAY_FILE_NAME);
  const auto warn = [&](std::uint32_t line, std::string message) {
    if (warnings != nullptr) warnings->push_back(Error{std::move(message), Location{guard.m_path, line, 0, {}}});
  };

  struct stat status {};
  if (::stat(guard.m_path.c_str(), &status) == 0) {
    std::string reason;
    const auto content = text::readFile(guard.m_path, &reason);
    if (!content) return Error{reason, Location{guard.m_path, 0, 0, {}}};
    std::string_view rest = *content;
    bool damaged = false;
    std::uint32_t lineNumber = 0;
    while (!rest.empty()) {
      ++lineNumber;
      const std::size_t newline = rest.find('\n');
      if (newline == std::string_view::npos) {  // cut by a crash while written: its command was never sent
        warn(lineNumber, "a last line without its end, from an interrupted write, dropped");
        break;
      }
      const std::string_view line = rest.substr(0, newline);
      rest.remove_prefix(newline + 1);
      if (lineNumber == 1) {
        const auto floor = line.starts_with(HEADER) ? parseInteger(line.substr(HEADER.size())) : std::nullopt;
        if (floor) {
          guard.m_floorUnixMs = *floor;
        } else {
          damaged = true;
        }
        continue;
      }
      const std::size_t space = line.find(' ');
      const auto deadline = space == std::string_view::npos ? std::nullopt : parseInteger(line.substr(0, space));
      const std::string_view cmdId = space == std::string_view::npos ? std::string_view{} : line.substr(space + 1);
      if (!deadline || !isCmdId(cmdId)) {
        damaged = true;
        continue;
      }
      auto& remembered = guard.m_deadlines[std::string(cmdId)];
      remembered = std::max(remembered, *deadline);
    }
    if (lineNumber == 0) damaged = true;  // an empty file: its header was never synced
    if (damaged) {
      // every cmdId a lost line named arrived before the file's last write, with a deadline at
      // most MAX_DEADLINE_AHEAD_MS after its arrival
      const std::int64_t modifiedUnixMs =
          static_cast<std::int64_t>(status.st_mtim.tv_sec) * 1000 + status.st_mtim.tv_nsec / 1'000'000;
      guard.m_floorUnixMs = std::max(guard.m_floorUnixMs, modifiedUnixMs + MAX_DEADLINE_AHEAD_MS);
      warn(0, "damaged: its good lines are kept and every remote command with a deadline up to " +
                  std::to_string(guard.m_floorUnixMs) + " (Unix ms; its last write plus " +
                  std::to_string(MAX_DEADLINE_AHEAD_MS) + " ms) is refused");
    }
  } else if (errno != ENOENT) {
    return Error{systemError("cannot read", guard.m_path)};
  }
  if (auto written = guard.rewrite(); !written) return written.error();
  return guard;
}

Status ReplayGuard::rewrite() {
  closeFile();
  const std::string temporary = m_path + ".tmp";
  const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
  if (fd < 0) return Error{systemError("cannot create", temporary)};
  std::string text = std::string(HEADER) + std::to_string(m_floorUnixMs) + '\n';
  for (const auto& [cmdId, deadline] : m_deadlines) text += entryLine(cmdId, deadline);
  const bool written = writeAll(fd, text) && ::fdatasync(fd) == 0;
  const int code = errno;
  ::close(fd);
  if (!written) {
    ::unlink(temporary.c_str());
    return Error{systemError("cannot write", temporary, code)};
  }
  if (::rename(temporary.c_str(), m_path.c_str()) != 0) return Error{systemError("cannot rename it to", m_path)};
  const int folderFd = ::open(m_folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (folderFd < 0 || ::fsync(folderFd) != 0) {
    const int folderCode = errno;
    if (folderFd >= 0) ::close(folderFd);
    return Error{systemError("cannot sync the folder", m_folder, folderCode)};
  }
  ::close(folderFd);
  m_fd = ::open(m_path.c_str(), O_WRONLY | O_APPEND | O_CLOEXEC);
  if (m_fd < 0) return Error{systemError("cannot open", m_path)};
  m_fileLines = m_deadlines.size();
  return {};
}

Status ReplayGuard::appendLine(const std::string& line) {
  if (!writeAll(m_fd, line) || ::fdatasync(m_fd) != 0) {
    const int code = errno;
    closeFile();  // the next admit() rewrites the file whole first: no half line stays before the next
    return Error{systemError("cannot write", m_path, code)};
  }
  ++m_fileLines;
  return {};
}

void ReplayGuard::forgetExpired(std::int64_t nowUnixMs) {
  for (auto it = m_deadlines.begin(); it != m_deadlines.end();) {
    if (it->second <= nowUnixMs) {
      m_floorUnixMs = std::max(m_floorUnixMs, it->second);
      it = m_deadlines.erase(it);
    } else {
      ++it;
    }
  }
}

std::optional<ReplayVerdict> ReplayGuard::admit(const std::string& cmdId, std::int64_t deadlineUnixMs,
                                                std::int64_t nowUnixMs) {
  forgetExpired(nowUnixMs);
  if (const auto seen = m_deadlines.find(cmdId); seen != m_deadlines.end()) {
    return ReplayVerdict{ReplayRefusal::Replayed,
                         "replayed: cmdId '" + cmdId + "' was received before (remembered until its deadline, " +
                             std::to_string(seen->second - nowUnixMs) +
                             " ms from now); a remote command runs at most once, its first answer stands"};
  }
  if (deadlineUnixMs <= m_floorUnixMs) {
    return ReplayVerdict{ReplayRefusal::BeforeFloor,
                         "/deadlineUnixMs: " + std::to_string(deadlineUnixMs) + " is not after " +
                             std::to_string(m_floorUnixMs) +
                             ", the latest deadline vcu-telemetry has forgotten (its clock went back, or its "
                             "memory of received commands was damaged); a remote command runs at most once"};
  }
  if (m_deadlines.size() >= MAX_REMEMBERED_COMMANDS) {
    std::int64_t soonest = deadlineUnixMs;
    for (const auto& entry : m_deadlines) soonest = std::min(soonest, entry.second);
    return ReplayVerdict{ReplayRefusal::Full, "busy: " + std::to_string(MAX_REMEMBERED_COMMANDS) +
                                                  " remote commands within their deadlines are remembered; the next "
                                                  "is forgotten in " +
                                                  std::to_string(soonest - nowUnixMs) + " ms"};
  }
  if (m_fd < 0 || m_fileLines > 2 * m_deadlines.size() + REWRITE_SLACK_LINES) {
    if (auto written = rewrite(); !written) {
      return ReplayVerdict{ReplayRefusal::Io, "cannot remember the cmdId (" + written.error().toString() +
                                                  "); refused, so that it cannot run twice"};
    }
  }
  if (auto written = appendLine(entryLine(cmdId, deadlineUnixMs)); !written) {
    return ReplayVerdict{ReplayRefusal::Io, "cannot remember the cmdId (" + written.error().toString() +
                                                "); refused, so that it cannot run twice"};
  }
  m_deadlines.emplace(cmdId, deadlineUnixMs);
  return std::nullopt;
}

}  // namespace openvcu::telemetry
