#include "openvcu/service/process_stats.hpp"

#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

namespace openvcu::service {

std::int64_t processCpuTicks(std::int32_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string text;
  if (!std::getline(in, text)) return -1;
  // the command name (field 2) may hold spaces and parentheses: count from the last ')'
  const auto close = text.rfind(')');
  if (close == std::string::npos || close + 2 >= text.size()) return -1;
  std::istringstream fields(text.substr(close + 2));
  std::string field;
  std::int64_t total = 0;
  int seen = 0;
  for (int i = 3; i <= 15 && fields >> field; ++i) {
    if (i == 14 || i == 15) {
      total += std::strtoll(field.c_str(), nullptr, 10);
      ++seen;
    }
  }
  return seen == 2 ? total : -1;
}

double processRssMb(std::int32_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/statm");
  long pages = 0;
  long resident = 0;
  if (!(in >> pages >> resident)) return -1;
  return static_cast<double>(resident) * static_cast<double>(::sysconf(_SC_PAGESIZE)) / 1e6;
}

double clockTicksPerSecond() { return static_cast<double>(::sysconf(_SC_CLK_TCK)); }

}  // namespace openvcu::service
