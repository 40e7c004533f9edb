#include "openvcu/config/web.hpp"

#include <arpa/inet.h>

#include <charconv>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>

#include "openvcu/config/json.hpp"

namespace openvcu::config {
namespace {

constexpr std::size_t MAX_WEB_FILE_BYTES = 64 * 1024;

std::string relativeTo(const std::string& directory, const std::string& file) {
  const std::filesystem::path path(file);
  if (path.is_absolute() || directory.empty()) return file;
  return (std::filesystem::path(directory) / path).lexically_normal().string();
}

/// A whole number in [low, high] at `key`, else an error naming the range.
template <typename T>
void boundedInteger(JsonChecker& check, const Json& root, std::string_view key, double low, double high, T& target) {
  const auto value = check.number(root, "", key, false);
  if (!value) return;
  if (*value < low || *value > high || *value != static_cast<double>(static_cast<std::int64_t>(*value))) {
    check.error("/" + std::string(key), "must be a whole number from " + formatNumber(low) + " to " + formatNumber(high));
    return;
  }
  target = static_cast<T>(*value);
}

/// Why `origin` is not an origin as a browser sends it ("https://vcu.example:8443"), if it is not.
std::optional<std::string> originProblem(const std::string& origin) {
  const std::string form = "'" + origin +
                           "': expected an origin as a browser sends it, \"http(s)://host[:port]\" in lower case, "
                           "without a path";
  const auto schemeEnd = origin.find("://");
  if (schemeEnd == std::string::npos) return form;
  const std::string scheme = origin.substr(0, schemeEnd);
  const std::string rest = origin.substr(schemeEnd + 3);
  if (scheme != "http" && scheme != "https") return form;
  if (rest.empty() || rest.find_first_of("/?#@ \\") != std::string::npos) return form;
  for (const char c : rest) {
    if (c >= 'A' && c <= 'Z') return form;
  }
  return std::nullopt;
}

}  // namespace

Result<std::pair<std::string, std::uint16_t>> parseListenAddress(std::string_view text) {
  const auto colon = text.rfind(':');
  const std::string form = "expected an IPv4 address and a port, e.g. \"127.0.0.1:8080\"";
  if (colon == std::string_view::npos || colon == 0 || colon + 1 >= text.size()) {
    return Error{"'" + std::string(text) + "': " + form};
  }
  const std::string address(text.substr(0, colon));
  in_addr parsed{};
  if (inet_pton(AF_INET, address.c_str(), &parsed) != 1) return Error{"'" + std::string(text) + "': " + form};
  const std::string_view portText = text.substr(colon + 1);
  unsigned port = 0;
  const auto [end, code] = std::from_chars(portText.data(), portText.data() + portText.size(), port);
  if (code != std::errc{} || end != portText.data() + portText.size() || port > 65535) {
    return Error{"'" + std::string(text) + "': the port must be 0-65535"};
  }
  return std::pair<std::string, std::uint16_t>{address, static_cast<std::uint16_t>(port)};
}

bool isLoopbackAddress(std::string_view address) noexcept { return address.starts_with("127."); }

Result<WebConfig> parseWebConfig(std::string_view text, const std::string& source, const std::string& directory,
                                 std::vector<Error>* warnings) {
  auto jsonResult = parseJson(text, source);
  if (!jsonResult) return jsonResult.error();
  const Json& root = *jsonResult;
  JsonChecker check(source);
  WebConfig result;
  if (!check.isObject(root, "")) return check.firstError();
  check.onlyKeys(root, "", {"listen", "dataFolder", "usersFile", "maxUpdatesPerSecond", "maxClients", "maxConnections",
                            "maxUploadMB", "sessionMinutes", "trustedOrigins", "comment"});
  if (const auto listen = check.string(root, "", "listen", false)) {
    auto parsed = parseListenAddress(*listen);
    if (!parsed) {
      check.error("/listen", parsed.error().message);
    } else {
      result.address = parsed->first;
      result.port = parsed->second;
      if (!isLoopbackAddress(result.address)) {
        check.warning("/listen", "vcu-web listens on " + *listen +
                                     ": the VCU's pages are reachable from its network (logins still guard the commands)");
      }
    }
  }
  if (const auto folder = check.string(root, "", "dataFolder", false)) {
    if (folder->empty()) check.error("/dataFolder", "must not be empty");
    else result.dataFolder = relativeTo(directory, *folder);
  }
  if (const auto users = check.string(root, "", "usersFile", false)) {
    if (users->empty()) check.error("/usersFile", "must not be empty");
    else result.usersFile = relativeTo(directory, *users);
  }
  if (const auto rate = check.number(root, "", "maxUpdatesPerSecond", false)) {
    if (*rate < 1 || *rate > 50) check.error("/maxUpdatesPerSecond", "must be from 1 to 50");
    else result.maxUpdatesPerSecond = *rate;
  }
  boundedInteger(check, root, "maxClients", 1, 256, result.maxClients);
  boundedInteger(check, root, "maxConnections", 4, 1024, result.maxConnections);
  std::uint64_t uploadMb = result.maxUploadBytes >> 20;
  boundedInteger(check, root, "maxUploadMB", 1, 4096, uploadMb);
  result.maxUploadBytes = uploadMb << 20;
  boundedInteger(check, root, "sessionMinutes", 1, 1440, result.sessionMinutes);
  if (const Json* origins = check.array(root, "", "trustedOrigins", false)) {
    for (std::size_t i = 0; i < origins->size(); ++i) {
      const std::string path = JsonChecker::join("/trustedOrigins", i);
      const Json& origin = (*origins)[i];
      if (!origin.is_string()) {
        check.error(path, "expected a string such as \"https://vcu.example\"");
        continue;
      }
      if (auto problem = originProblem(origin.get<std::string>())) check.error(path, *problem);
      else result.trustedOrigins.push_back(origin.get<std::string>());
    }
  }
  if (!check.ok()) return check.firstError();
  if (warnings) {
    for (const Error& diagnostic : check.diagnostics()) {
      if (diagnostic.severity != Severity::Error) warnings->push_back(diagnostic);
    }
  }
  return result;
}

Result<WebConfig> loadWebConfig(const std::string& path, std::vector<Error>* warnings) {
  std::error_code code;
  const auto size = std::filesystem::file_size(path, code);
  if (code) return Error{path + ": cannot read: " + code.message()};
  if (size > MAX_WEB_FILE_BYTES) return Error{path + ": larger than 64 KiB; not a web.json"};
  std::ifstream in(path, std::ios::binary);
  if (!in) return Error{path + ": cannot read"};
  std::ostringstream text;
  text << in.rdbuf();
  return parseWebConfig(text.str(), path, std::filesystem::path(path).parent_path().string(), warnings);
}

}  // namespace openvcu::config
