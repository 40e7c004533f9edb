#pragma once
// vcu-telemetry's settings (telemetry.json, named by vehicle.json's "telemetry"; design:
// docs/design/telemetry.md).
//
//   {"broker": "mqtts://fleet.example.com:8883", "vehicleId": "hhea-01",
//    "username": "hhea-01", "passwordFile": "mqtt-password",
//    "tls": {"caFile": "fleet-ca.crt", "certFile": "hhea-01.crt", "keyFile": "hhea-01.key"},
//    "queueFolder": "/var/lib/openvcu/telemetry", "maxQueueMB": 64,
//    "signals": [{"name": "BMS.SOC", "maxRateHz": 1, "deadband": 0.5}],
//    "remoteCommands": {"enabled": false, "keys": ["internal.operator.StartStop"]}}
//
// "broker" and "vehicleId" are required, the rest optional (defaults below); relative paths
// are relative to the file. Checked, each error with the file, JSON path and reason: the URL
// (mqtt:// or mqtts://, a host, a port 1-65535), the vehicle id (one MQTT topic level: letters,
// digits, '-' and '_'), a password only through a file, TLS files only with mqtts:// and a
// certificate only with its key, limits, duplicate signals and keys, remote commands only
// over an authenticated connection (a username or a client certificate). Whether a signal
// or command key exists is checked against the catalog by the service, not here.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "openvcu/core/error.hpp"
#include "openvcu/core/result.hpp"

namespace openvcu::config {

inline constexpr std::uint16_t DEFAULT_MQTT_PORT = 1883;   ///< IANA "mqtt"
inline constexpr std::uint16_t DEFAULT_MQTTS_PORT = 8883;  ///< IANA "secure-mqtt"

struct BrokerAddress {
  bool tls{false};  ///< mqtts://
  std::string host;  ///< a name, an IPv4 address or an IPv6 address (without its brackets)
  std::uint16_t port{DEFAULT_MQTT_PORT};
};

struct TelemetryTls {
  std::string caFile;    ///< empty: the system's store (/etc/ssl/certs)
  std::string certFile;  ///< client certificate; empty: none (username and password then)
  std::string keyFile;   ///< its private key; given exactly when certFile is
};

struct TelemetrySignal {
  std::string name;        ///< a catalog key ("BMS.SOC")
  double maxRateHz{1};     ///< at most this many values per second, (0, 100]
  double deadband{0};      ///< a value closer than this to the last one sent is not sent, >= 0
};

struct TelemetryConfig {
  std::string brokerUrl;  ///< as written
  BrokerAddress broker;
  std::string vehicleId;
  std::string username;      ///< empty: no username
  std::string passwordFile;  ///< one line, the password; only with a username
  std::optional<TelemetryTls> tls;  ///< set exactly for mqtts://
  std::string queueFolder{"/var/lib/openvcu/telemetry"};
  std::uint64_t maxQueueBytes{64ull << 20};  ///< "maxQueueMB", 1..4096
  std::vector<TelemetrySignal> signals;
  bool remoteCommandsEnabled{false};
  std::vector<std::string> remoteCommandKeys;  ///< the only keys a remote command may name
};

/// "mqtt://host:port" / "mqtts://host" -> the address (port defaults 1883 / 8883); an error
/// naming the problem for anything else ("http://x", "mqtt://", "mqtt://h:0", "mqtt://u@h").
Result<BrokerAddress> parseBrokerUrl(std::string_view url);
/// True when `id` can be one MQTT topic level of ours: 1-64 of [A-Za-z0-9_-].
[[nodiscard]] bool isValidVehicleId(std::string_view id) noexcept;

/// Loads and checks a telemetry.json; `warnings` (optional) gets what is allowed but odd
/// (remote commands enabled with no keys, a plain mqtt:// broker beyond loopback with a password).
Result<TelemetryConfig> loadTelemetryConfig(const std::string& path, std::vector<Error>* warnings = nullptr);
Result<TelemetryConfig> parseTelemetryConfig(std::string_view text, const std::string& source,
                                             const std::string& directory, std::vector<Error>* warnings = nullptr);

}  // namespace openvcu::config
