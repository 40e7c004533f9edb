#include "process_finder.hpp"

#include <dirent.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <ctime>
#include <fstream>
#include <optional>
#include <sstream>

namespace openvcu::watchdog {
namespace {

constexpr std::string_view DELETED_SUFFIX = " (deleted)";
constexpr std::int64_t NS_PER_S = 1'000'000'000;

struct StatLine {
  char state{};
  pid_t parent{};
  std::uint64_t startTicks{};
};

/// /proc/<pid>/stat: "pid (comm) state ppid ... starttime(22) ..."; comm may hold spaces
/// and parentheses, so the fields are counted from the last ')'.
std::optional<StatLine> readStat(const std::string& path) {
  std::ifstream file(path);
  std::string text;
  if (!file || !std::getline(file, text)) return std::nullopt;
  const std::size_t close = text.rfind(')');
  if (close == std::string::npos) return std::nullopt;
  std::istringstream fields(text.substr(close + 1));
  StatLine stat;
  std::string skip;
  fields >> stat.state >> stat.parent;
  for (int field = 5; field < 22 && fields; ++field) fields >> skip;  // fields 5..21
  fields >> stat.startTicks;
  if (!fields) return std::nullopt;
  return stat;
}

/// CLOCK_MONOTONIC of a start time given in clock ticks after boot (CLOCK_BOOTTIME).
std::int64_t monotonicOfBootTicks(std::uint64_t ticks) noexcept {
  static const long TICKS_PER_S = ::sysconf(_SC_CLK_TCK);
  timespec boot{};
  timespec mono{};
  ::clock_gettime(CLOCK_BOOTTIME, &boot);
  ::clock_gettime(CLOCK_MONOTONIC, &mono);
  const std::int64_t bootNs = std::int64_t(boot.tv_sec) * NS_PER_S + boot.tv_nsec;
  const std::int64_t monoNs = std::int64_t(mono.tv_sec) * NS_PER_S + mono.tv_nsec;
  const std::int64_t startBootNs = std::int64_t(ticks) * (NS_PER_S / (TICKS_PER_S > 0 ? TICKS_PER_S : 100));
  return monoNs - (bootNs - startBootNs);
}

}  // namespace

std::string_view executableName(std::string_view exeLink) noexcept {
  if (exeLink.size() > DELETED_SUFFIX.size() && exeLink.ends_with(DELETED_SUFFIX)) {
    exeLink.remove_suffix(DELETED_SUFFIX.size());
  }
  const std::size_t slash = exeLink.rfind('/');
  return slash == std::string_view::npos ? exeLink : exeLink.substr(slash + 1);
}

FindResult ProcessFinder::find(std::string_view program, pid_t parent, pid_t self) const {
  FindResult result;
  DIR* dir = ::opendir(m_procRoot.c_str());
  if (dir == nullptr) return result;
  while (const dirent* entry = ::readdir(dir)) {
    pid_t pid{};
    const std::string_view name(entry->d_name);
    const auto [end, error] = std::from_chars(name.data(), name.data() + name.size(), pid);
    if (error != std::errc() || end != name.data() + name.size() || pid == self) continue;
    const std::string base = m_procRoot + "/" + std::string(name);
    const auto maybeStat = readStat(base + "/stat");
    if (!maybeStat || maybeStat->parent != parent || maybeStat->state == 'Z' || maybeStat->state == 'X') continue;
    char link[4096];
    const ssize_t length = ::readlink((base + "/exe").c_str(), link, sizeof link - 1);
    if (length < 0) {
      if (errno == EACCES || errno == EPERM) ++result.unreadable;
      continue;
    }
    if (executableName(std::string_view(link, static_cast<std::size_t>(length))) != program) continue;
    result.processes.push_back(FoundProcess{pid, monotonicOfBootTicks(maybeStat->startTicks), maybeStat->state});
  }
  ::closedir(dir);
  return result;
}

}  // namespace openvcu::watchdog
