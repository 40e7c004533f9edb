#include "openvcu/config/telemetry.hpp"

#include <arpa/inet.h>

#include <algorithm>
#include <charconv>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "openvcu/config/json.hpp"

namespace openvcu::config {
namespace {

constexpr std::size_t MAX_TELEMETRY_FILE_BYTES = 1024 * 1024;
constexpr std::size_t MAX_VEHICLE_ID = 64;
constexpr double MAX_RATE_HZ = 100;
constexpr double MAX_QUEUE_MB = 4096;

std::string relativeTo(const std::string& directory, const std::string& file) {
  const std::filesystem::path path(file);
  if (path.is_absolute() || directory.empty()) return file;
  return (std::filesystem::path(directory) / path).lexically_normal().string();
}

bool isHostCharacter(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' || c == '.';
}

/// A path member that must not be empty, resolved relative to the file; empty when absent or wrong.
std::string pathMember(JsonChecker& check, const Json& object, const std::string& path, std::string_view key,
                       const std::string& directory) {
  const auto value = check.string(object, path, key, false);
  if (!value) return {};
  if (value->empty()) {
    check.error(JsonChecker::join(path, key), "must not be empty");
    return {};
  }
  return relativeTo(directory, *value);
}

void loadSignals(JsonChecker& check, const Json& root, TelemetryConfig& result) {
  const Json* signals = check.array(root, "", "signals", false);
  if (!signals) return;
  std::set<std::string> seen;
  for (std::size_t i = 0; i < signals->size(); ++i) {
    const std::string path = JsonChecker::join("/signals", i);
    const Json& item = (*signals)[i];
    if (!check.isObject(item, path)) continue;
    check.onlyKeys(item, path, {"name", "maxRateHz", "deadband", "comment"});
    TelemetrySignal signal;
    if (const auto name = check.string(item, path, "name")) {
      if (name->empty()) check.error(path + "/name", "must not be empty");
      else if (!seen.insert(*name).second) check.error(path + "/name", "'" + *name + "' is listed twice");
      signal.name = *name;
    }
    if (const auto rate = check.number(item, path, "maxRateHz", false)) {
      if (*rate <= 0 || *rate > MAX_RATE_HZ) check.error(path + "/maxRateHz", "must be above 0 and at most 100");
      else signal.maxRateHz = *rate;
    }
    if (const auto deadband = check.number(item, path, "deadband", false)) {
      if (*deadband < 0) check.error(path + "/deadband", "must be 0 or more");
      else signal.deadband = *deadband;
    }
    result.signals.push_back(std::move(signal));
  }
}

void loadRemoteCommands(JsonChecker& check, const Json& root, TelemetryConfig& result) {
  const Json* commands = check.member(root, "", "remoteCommands", false);
  if (!commands || !check.isObject(*commands, "/remoteCommands")) return;
  check.onlyKeys(*commands, "/remoteCommands", {"enabled", "keys", "comment"});
  if (const auto enabled = check.boolean(*commands, "/remoteCommands", "enabled", false)) {
    result.remoteCommandsEnabled = *enabled;
  }
  if (const Json* keys = check.array(*commands, "/remoteCommands", "keys", false)) {
    std::set<std::string> seen;
    for (std::size_t i = 0; i < keys->size(); ++i) {
      const std::string path = JsonChecker::join("/remoteCommands/keys", i);
      const Json& key = (*keys)[i];
      if (!key.is_string() || key.get<std::string>().empty()) {
        check.error(path, "must be a signal key (a non-empty string)");
        continue;
      }
      if (!seen.insert(key.get<std::string>()).second) {
        check.error(path, "'" + key.get<std::string>() + "' is listed twice");
        continue;
      }
      result.remoteCommandKeys.push_back(key.get<std::string>());
    }
  }
  if (result.remoteCommandsEnabled && result.remoteCommandKeys.empty()) {
    check.warning("/remoteCommands/keys", "remote commands are enabled but no key is listed: every command is refused");
  }
}

}  // namespace

Result<BrokerAddress> parseBrokerUrl(std::string_view url) {
  const std::string quoted = "'" + std::string(url) + "'";
  BrokerAddress address;
  std::string_view rest;
  if (url.starts_with("mqtt://")) {
    rest = url.substr(7);
  } else if (url.starts_with("mqtts://")) {
    rest = url.substr(8);
    address.tls = true;
    address.port = DEFAULT_MQTTS_PORT;
  } else {
    return Error{quoted + ": expected mqtt://HOST[:PORT] or mqtts://HOST[:PORT]"};
  }
  if (!rest.empty() && rest.back() == '/') rest.remove_suffix(1);
  if (rest.find_first_of("/?#@") != std::string_view::npos) {
    return Error{quoted + ": only a host and a port (no user, path or query; credentials go in username/passwordFile)"};
  }
  std::string_view host = rest;
  std::string_view port;
  if (rest.starts_with("[")) {  // [IPv6]:port
    const auto close = rest.find(']');
    if (close == std::string_view::npos) return Error{quoted + ": an IPv6 address lacks its ']'"};
    host = rest.substr(1, close - 1);
    const std::string_view after = rest.substr(close + 1);
    if (!after.empty() && !after.starts_with(":")) return Error{quoted + ": expected ':PORT' after the IPv6 address"};
    if (!after.empty()) port = after.substr(1);
    in6_addr parsed{};
    if (inet_pton(AF_INET6, std::string(host).c_str(), &parsed) != 1) return Error{quoted + ": not an IPv6 address"};
  } else {
    if (const auto colon = rest.rfind(':'); colon != std::string_view::npos) {
      host = rest.substr(0, colon);
      port = rest.substr(colon + 1);
      if (port.empty()) return Error{quoted + ": a ':' without a port"};
    }
    if (host.empty() || !std::all_of(host.begin(), host.end(), isHostCharacter) || host.starts_with('-') ||
        host.starts_with('.')) {
      return Error{quoted + ": expected a host name or an IPv4 address"};
    }
  }
  if (host.empty()) return Error{quoted + ": no host"};
  if (!port.empty()) {
    unsigned number = 0;
    const auto [end, code] = std::from_chars(port.data(), port.data() + port.size(), number);
    if (code != std::errc{} || end != port.data() + port.size() || number == 0 || number > 65535) {
      return Error{quoted + ": the port must be 1-65535"};
    }
    address.port = static_cast<std::uint16_t>(number);
  }
  address.host = std::string(host);
  return address;
}

bool isValidVehicleId(std::string_view id) noexcept {
  if (id.empty() || id.size() > MAX_VEHICLE_ID) return false;
  return std::all_of(id.begin(), id.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' || c == '_';
  });
}

Result<TelemetryConfig> parseTelemetryConfig(std::string_view text, const std::string& source,
                                             const std::string& directory, std::vector<Error>* warnings) {
  auto jsonResult = parseJson(text, source);
  if (!jsonResult) return jsonResult.error();
  const Json& root = *jsonResult;
  JsonChecker check(source);
  TelemetryConfig result;
  if (!check.isObject(root, "")) return check.firstError();
  if (root.contains("password")) {
    check.error("/password", "not in this file: put the password in a file of its own and name it with passwordFile");
  }
  check.onlyKeys(root, "", {"broker", "vehicleId", "username", "passwordFile", "tls", "queueFolder", "maxQueueMB",
                            "signals", "remoteCommands", "comment", "password"});
  if (const auto url = check.string(root, "", "broker")) {
    auto parsed = parseBrokerUrl(*url);
    if (!parsed) check.error("/broker", parsed.error().message);
    else result.broker = *parsed;
    result.brokerUrl = *url;
  }
  if (const auto id = check.string(root, "", "vehicleId")) {
    if (!isValidVehicleId(*id)) {
      check.error("/vehicleId", "'" + *id + "': 1 to 64 letters, digits, '-' or '_' (it is one MQTT topic level)");
    }
    result.vehicleId = *id;
  }
  if (const auto user = check.string(root, "", "username", false)) {
    if (user->empty()) check.error("/username", "must not be empty (leave it out for none)");
    result.username = *user;
  }
  result.passwordFile = pathMember(check, root, "", "passwordFile", directory);
  if (!result.passwordFile.empty() && result.username.empty()) {
    check.error("/passwordFile", "a password file needs a username");
  }
  if (const Json* tls = check.member(root, "", "tls", false); tls && check.isObject(*tls, "/tls")) {
    check.onlyKeys(*tls, "/tls", {"caFile", "certFile", "keyFile", "comment"});
    TelemetryTls files;
    files.caFile = pathMember(check, *tls, "/tls", "caFile", directory);
    files.certFile = pathMember(check, *tls, "/tls", "certFile", directory);
    files.keyFile = pathMember(check, *tls, "/tls", "keyFile", directory);
    if (files.certFile.empty() != files.keyFile.empty()) {
      check.error(files.certFile.empty() ? "/tls/certFile" : "/tls/keyFile",
                  "a client certificate needs both certFile and keyFile");
    }
    if (!result.broker.tls && !result.brokerUrl.empty()) check.error("/tls", "TLS files need an mqtts:// broker");
    result.tls = files;
  }
  if (result.broker.tls && !result.tls) result.tls = TelemetryTls{};
  if (const auto folder = pathMember(check, root, "", "queueFolder", directory); !folder.empty()) {
    result.queueFolder = folder;
  }
  if (const auto megabytes = check.number(root, "", "maxQueueMB", false)) {
    if (*megabytes < 1 || *megabytes > MAX_QUEUE_MB || *megabytes != static_cast<double>(static_cast<std::int64_t>(*megabytes))) {
      check.error("/maxQueueMB", "must be a whole number from 1 to 4096");
    } else {
      result.maxQueueBytes = static_cast<std::uint64_t>(*megabytes) << 20;
    }
  }
  loadSignals(check, root, result);
  loadRemoteCommands(check, root, result);
  const bool clientCertificate = result.tls && !result.tls->certFile.empty();
  if (result.remoteCommandsEnabled && result.username.empty() && !clientCertificate) {
    check.error("/remoteCommands/enabled",
                "remote commands need a broker that authenticates: give a username and passwordFile or a TLS client certificate");
  }
  if (!result.passwordFile.empty() && !result.broker.tls && !result.broker.host.empty() &&
      !result.broker.host.starts_with("127.") && result.broker.host != "localhost" && result.broker.host != "::1") {
    check.warning("/broker", "the password goes to " + result.broker.host + " unencrypted: use mqtts://");
  }
  if (!check.ok()) return check.firstError();
  if (warnings) {
    for (const Error& diagnostic : check.diagnostics()) {
      if (diagnostic.severity != Severity::Error) warnings->push_back(diagnostic);
    }
  }
  return result;
}

Result<TelemetryConfig> loadTelemetryConfig(const std::string& path, std::vector<Error>* warnings) {
  std::error_code code;
  const auto size = std::filesystem::file_size(path, code);
  if (code) return Error{path + ": cannot read: " + code.message()};
  if (size > MAX_TELEMETRY_FILE_BYTES) return Error{path + ": larger than 1 MiB; not a telemetry.json"};
  std::ifstream in(path, std::ios::binary);
  if (!in) return Error{path + ": cannot read"};
  std::ostringstream text;
  text << in.rdbuf();
  return parseTelemetryConfig(text.str(), path, std::filesystem::path(path).parent_path().string(), warnings);
}

}  // namespace openvcu::config
