#include "openvcu/config/dashboard.hpp"

#include <filesystem>
#include <fstream>
#include <sstream>

#include "openvcu/config/json.hpp"

namespace openvcu::config {
namespace {

std::string lastComponent(std::string_view key) {
  const auto dot = key.rfind('.');
  return std::string(dot == std::string_view::npos ? key : key.substr(dot + 1));
}

}  // namespace

bool isSafeNumberFormat(std::string_view format) noexcept {
  int conversions = 0;
  for (std::size_t i = 0; i < format.size(); ++i) {
    if (format[i] != '%') continue;
    if (i + 1 < format.size() && format[i + 1] == '%') {
      ++i;
      continue;
    }
    std::size_t j = i + 1;
    while (j < format.size() && std::string_view("-+ #0123456789.").find(format[j]) != std::string_view::npos) ++j;
    if (j >= format.size() || std::string_view("fFeEgG").find(format[j]) == std::string_view::npos) return false;
    ++conversions;
    i = j;
  }
  return conversions == 1 && format.size() < 32;
}

Result<DashboardConfig> parseDashboardConfig(std::string_view text, const std::string& source,
                                             const signals::Catalog& catalog) {
  auto jsonResult = config::parseJson(text, source);
  if (!jsonResult) return jsonResult.error();
  const Json& root = *jsonResult;
  JsonChecker check(source);
  DashboardConfig result;
  if (!check.isObject(root, "")) return check.firstError();
  check.onlyKeys(root, "", {"comment", "dials", "header", "status", "items", "staleAfterMs"});
  const auto knownKey = [&](const std::string& key, const std::string& path) {
    if (key.empty()) return;
    if (const auto found = catalog.find(key); !found) check.error(path, found.error().message);
  };
  if (const Json* dials = check.member(root, "", "dials", false); dials && check.isObject(*dials, "/dials")) {
    check.onlyKeys(*dials, "/dials", {"voltage", "current", "power"});
    // each dial: a key, or {"key": KEY, "min": NUMBER, "max": NUMBER}
    const auto dial = [&](const char* name, std::string& key, DialRange& range) {
      const std::string path = std::string("/dials/") + name;
      const Json* value = check.member(*dials, "/dials", name, false);
      if (value == nullptr) return;
      if (value->is_string()) {
        key = value->get<std::string>();
        knownKey(key, path);
        return;
      }
      if (!value->is_object()) {
        check.error(path, "must be a signal key or {\"key\": KEY, \"min\": NUMBER, \"max\": NUMBER}");
        return;
      }
      check.onlyKeys(*value, path, {"key", "min", "max", "comment"});
      key = check.string(*value, path, "key", false).value_or("");
      knownKey(key, path + "/key");
      const auto minimum = check.number(*value, path, "min", false);
      const auto maximum = check.number(*value, path, "max", false);
      const DialRange wanted{minimum.value_or(range.minimum), maximum.value_or(range.maximum)};
      if (!(wanted.minimum < wanted.maximum)) {
        check.error(path, "min must be below max");
        return;
      }
      range = wanted;
    };
    dial("voltage", result.voltageKey, result.voltageRange);
    dial("current", result.currentKey, result.currentRange);
    dial("power", result.powerKey, result.powerRange);
  }
  if (const Json* header = check.member(root, "", "header", false); header && check.isObject(*header, "/header")) {
    check.onlyKeys(*header, "/header", {"soc", "soh", "charger"});
    result.socKey = check.string(*header, "/header", "soc", false).value_or("");
    result.sohKey = check.string(*header, "/header", "soh", false).value_or("");
    result.chargerKey = check.string(*header, "/header", "charger", false).value_or("");
    knownKey(result.socKey, "/header/soc");
    knownKey(result.sohKey, "/header/soh");
    knownKey(result.chargerKey, "/header/charger");
  }
  if (const Json* status = check.array(root, "", "status", false)) {
    for (std::size_t i = 0; i < status->size(); ++i) {
      const std::string path = JsonChecker::join("/status", i);
      if (!(*status)[i].is_string()) {
        check.error(path, "must be a signal key (a string)");
        continue;
      }
      result.statusKeys.push_back((*status)[i].get<std::string>());
      knownKey(result.statusKeys.back(), path);
    }
  }
  if (const auto stale = check.number(root, "", "staleAfterMs", false)) {
    if (*stale < 100 || *stale > 3'600'000) {
      check.error("/staleAfterMs", "must be between 100 and 3600000 ms");
    } else {
      result.staleAfterMs = static_cast<std::int64_t>(*stale);
    }
  }
  if (const Json* items = check.array(root, "", "items", true)) {
    for (std::size_t i = 0; i < items->size(); ++i) {
      const std::string path = JsonChecker::join("/items", i);
      const Json& item = (*items)[i];
      if (!check.isObject(item, path)) continue;
      check.onlyKeys(item, path, {"key", "label", "unit", "format", "comment"});
      DashboardItem entry;
      entry.key = check.string(item, path, "key").value_or("");
      knownKey(entry.key, path + "/key");
      entry.label = check.string(item, path, "label", false).value_or(lastComponent(entry.key));
      const auto index = catalog.indexOf(entry.key);
      entry.unit = check.string(item, path, "unit", false).value_or(index ? catalog[*index].unit : "");
      entry.format = check.string(item, path, "format", false).value_or("%.1f");
      if (!isSafeNumberFormat(entry.format)) {
        check.error(path + "/format", "'" + entry.format + "' must be one printf number conversion, e.g. \"%.1f\"");
      }
      result.items.push_back(std::move(entry));
    }
  }
  if (!check.ok()) return check.firstError();
  return result;
}

Result<DashboardConfig> loadDashboardConfig(const std::string& path, const signals::Catalog& catalog) {
  std::ifstream in(path);
  if (!in) return Error{"cannot read the dashboard file", Location{path, 0, 0, {}}};
  std::ostringstream text;
  text << in.rdbuf();
  return parseDashboardConfig(text.str(), path, catalog);
}

std::string dashboardBeside(const std::string& vehiclePath) {
  const std::filesystem::path beside = std::filesystem::path(vehiclePath).parent_path() / "dashboard.json";
  std::error_code error;
  return std::filesystem::exists(beside, error) ? beside.string() : std::string();
}

}  // namespace openvcu::config
