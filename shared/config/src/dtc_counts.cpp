// Persistence of the DTC occurrence counts (diagnostics.hpp): read at start, written
// atomically when a count changes; a bad file is set aside whole, never half applied.
#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <set>
#include <string_view>
#include <system_error>
#include <utility>

#include "openvcu/core/output_file.hpp"
#include "openvcu/config/diagnostics.hpp"
#include "openvcu/config/json.hpp"

namespace openvcu::config {
namespace {

constexpr int COUNTS_FORMAT = 1;

/// The counts of a parsed file, or the first problem (with file and JSON path).
Result<std::vector<j1939::Dtc>> parseCounts(const Json& root, const std::string& path) {
  JsonChecker check(path);
  std::vector<j1939::Dtc> counts;
  if (!check.isObject(root, "")) return check.firstError();
  check.onlyKeys(root, "", {"format", "comment", "counts"});
  if (auto format = check.number(root, "", "format"); format && *format != COUNTS_FORMAT) {
    check.error("/format", "unknown format " + formatNumber(*format) + "; this build reads format 1");
  }
  std::set<std::pair<std::uint32_t, std::uint8_t>> seen;
  if (const Json* list = check.array(root, "", "counts")) {
    for (std::size_t i = 0; i < list->size(); ++i) {
      const std::string where = JsonChecker::join("/counts", i);
      const Json& item = (*list)[i];
      if (!check.isObject(item, where)) continue;
      check.onlyKeys(item, where, {"spn", "fmi", "count"});
      const auto whole = [&](std::string_view key, double maximum) -> std::optional<double> {
        const auto value = check.number(item, where, key);
        if (value && (!(*value >= 0 && *value <= maximum) || *value != std::floor(*value))) {
          check.error(JsonChecker::join(where, key), "must be a whole number from 0 to " + formatNumber(maximum));
          return std::nullopt;
        }
        return value;
      };
      const auto spn = whole("spn", j1939::DTC_MAX_SPN);
      const auto fmi = whole("fmi", j1939::DTC_MAX_FMI);
      const auto count = whole("count", j1939::DTC_MAX_COUNTED_OCCURRENCES);
      if (!spn || !fmi || !count) continue;
      const j1939::Dtc dtc{static_cast<std::uint32_t>(*spn), static_cast<std::uint8_t>(*fmi),
                           static_cast<std::uint8_t>(*count), false};
      if (!seen.emplace(dtc.spn, dtc.fmi).second) {
        check.error(where, "SPN " + std::to_string(dtc.spn) + " FMI " + std::to_string(dtc.fmi) + " is given twice");
        continue;
      }
      counts.push_back(dtc);
    }
  }
  if (!check.ok()) return check.firstError();
  return counts;
}

}  // namespace

DtcCountsLoad loadDtcCounts(const std::string& path) {
  DtcCountsLoad load;
  std::error_code existsError;
  if (!std::filesystem::exists(path, existsError)) return load;  // first start: all counts 0
  auto json = readJsonFile(path);
  Result<std::vector<j1939::Dtc>> parsed =
      json ? parseCounts(*json, path) : Result<std::vector<j1939::Dtc>>(json.error());
  if (parsed) {
    load.counts = std::move(*parsed);
    return load;
  }
  const std::string rejected = path + ".rejected";
  std::error_code renameError;
  std::filesystem::rename(path, rejected, renameError);
  Error error = parsed.error();
  error.message += "; the occurrence counts start at 0 and the file was " +
                   (renameError ? "not moved aside (" + renameError.message() + ")" : "moved to " + rejected);
  load.rejected = std::move(error);
  return load;
}

Status saveDtcCounts(const std::string& path, std::span<const j1939::Dtc> counts) {
  Json root = Json::object();
  root["format"] = COUNTS_FORMAT;
  root["comment"] =
      "occurrence counts of the VCU's own DTCs (J1939-73), kept across restarts "
      "(docs/design/j1939-diagnostics.md)";
  Json list = Json::array();
  for (const j1939::Dtc& dtc : counts) {
    list.push_back(Json{{"spn", dtc.spn}, {"fmi", dtc.fmi}, {"count", dtc.occurrenceCount}});
  }
  root["counts"] = std::move(list);
  const std::string text = root.dump(2) + "\n";

  return output::writeFileAtomically(path, text, "DTC counts");
}

}  // namespace openvcu::config
