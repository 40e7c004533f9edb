#pragma once
// vcu-web's settings ("web" in vehicle.json; HHEA: config/hhea/web.json). Reference:
// docs/config.md, "web.json"; design: docs/design/web.md.
//
//   {"listen": "127.0.0.1:8080", "dataFolder": "/var/lib/openvcu",
//    "usersFile": "/etc/openvcu/web-users.json", "maxUpdatesPerSecond": 20,
//    "maxClients": 32, "maxConnections": 64, "maxUploadMB": 256, "sessionMinutes": 60}
//
// Every member is optional (the defaults above); relative paths are relative to the file.
// Checked, each error with the file and JSON path: unknown keys, an address that is not an
// IPv4 address with a port, limits out of their ranges. A listen address other than loopback
// is allowed (the configuration says so) and warned about: the VCU is then reachable from
// its network.

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "openvcu/core/error.hpp"
#include "openvcu/core/result.hpp"

namespace openvcu::config {

inline constexpr std::string_view DEFAULT_WEB_ADDRESS = "127.0.0.1";
inline constexpr std::uint16_t DEFAULT_WEB_PORT = 8080;

struct WebConfig {
  std::string address{DEFAULT_WEB_ADDRESS};  ///< IPv4 dotted quad
  std::uint16_t port{DEFAULT_WEB_PORT};      ///< 0: any free port
  std::string dataFolder{"/var/lib/openvcu"};
  std::string usersFile{"/etc/openvcu/web-users.json"};
  double maxUpdatesPerSecond{20};  ///< per live page, 1..50
  std::size_t maxClients{32};      ///< live pages at once, 1..256
  std::size_t maxConnections{64};  ///< HTTP connections at once, 4..1024
  std::uint64_t maxUploadBytes{256ull << 20};  ///< "maxUploadMB", 1..4096 MB
  std::int64_t sessionMinutes{60};             ///< a login ends this long after its last use, 1..1440
  /// Origins besides vcu-web's own whose pages may send POSTs: the public address of a TLS
  /// reverse proxy ("https://vcu.example"); each "http(s)://host[:port]", lower case, no path.
  std::vector<std::string> trustedOrigins;
};

/// "127.0.0.1:8080" -> address and port; an error for anything else ("a.b:80", ":80", "1.2.3.4:99999").
Result<std::pair<std::string, std::uint16_t>> parseListenAddress(std::string_view text);
/// True for 127.0.0.0/8.
[[nodiscard]] bool isLoopbackAddress(std::string_view address) noexcept;

/// Loads and checks a web.json; `warnings` (optional) gets the non-loopback warning.
Result<WebConfig> loadWebConfig(const std::string& path, std::vector<Error>* warnings = nullptr);
Result<WebConfig> parseWebConfig(std::string_view text, const std::string& source, const std::string& directory,
                                 std::vector<Error>* warnings = nullptr);

}  // namespace openvcu::config
