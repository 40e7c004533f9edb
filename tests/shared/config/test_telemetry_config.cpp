// telemetry.json (shared/config/telemetry.hpp): vcu-telemetry's settings, the broker URL,
// authentication rules, defaults, ranges and JSON paths.
#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <unistd.h>

#include "openvcu/config/telemetry.hpp"

namespace {

using namespace openvcu;

constexpr std::string_view MINIMAL = R"({"broker": "mqtt://127.0.0.1:1883", "vehicleId": "hhea-01"})";

std::string errorOf(std::string_view text) {
  auto parsed = config::parseTelemetryConfig(text, "telemetry.json", "/etc/openvcu");
  REQUIRE_FALSE(parsed);
  return parsed.error().toString();
}

}  // namespace

TEST_CASE("broker URLs give scheme, host and port, with the default port of each scheme") {
  auto plain = config::parseBrokerUrl("mqtt://broker.local");
  REQUIRE(plain);
  CHECK_FALSE(plain->tls);
  CHECK(plain->host == "broker.local");
  CHECK(plain->port == config::DEFAULT_MQTT_PORT);
  auto secure = config::parseBrokerUrl("mqtts://10.0.0.7");
  REQUIRE(secure);
  CHECK(secure->tls);
  CHECK(secure->port == config::DEFAULT_MQTTS_PORT);
  auto explicitPort = config::parseBrokerUrl("mqtt://127.0.0.1:11883/");
  REQUIRE(explicitPort);
  CHECK(explicitPort->port == 11883);
  auto v6 = config::parseBrokerUrl("mqtts://[::1]:8884");
  REQUIRE(v6);
  CHECK(v6->host == "::1");
  CHECK(v6->port == 8884);
}

TEST_CASE("broker URLs that are not mqtt:// or mqtts:// with a host and a port are refused with the reason") {
  auto reason = [](std::string_view url) {
    auto parsed = config::parseBrokerUrl(url);
    REQUIRE_FALSE(parsed);
    return parsed.error().message;
  };
  CHECK(reason("http://broker").find("expected mqtt://HOST[:PORT]") != std::string::npos);
  CHECK(reason("mqtt://").find("expected a host") != std::string::npos);
  CHECK(reason("mqtt://broker:0").find("port must be 1-65535") != std::string::npos);
  CHECK(reason("mqtt://broker:70000").find("port must be 1-65535") != std::string::npos);
  CHECK(reason("mqtt://broker:").find("without a port") != std::string::npos);
  CHECK(reason("mqtt://user:secret@broker").find("no user, path or query") != std::string::npos);
  CHECK(reason("mqtt://broker/topic").find("no user, path or query") != std::string::npos);
  CHECK(reason("mqtt://[::1").find("lacks its ']'") != std::string::npos);
  CHECK(reason("mqtt://[nonsense]:1").find("not an IPv6 address") != std::string::npos);
}

TEST_CASE("vehicle ids are one topic level of letters, digits, dash and underscore") {
  CHECK(config::isValidVehicleId("hhea-01"));
  CHECK(config::isValidVehicleId("Tractor_7"));
  CHECK_FALSE(config::isValidVehicleId(""));
  CHECK_FALSE(config::isValidVehicleId("a/b"));
  CHECK_FALSE(config::isValidVehicleId("fleet+"));
  CHECK_FALSE(config::isValidVehicleId("#"));
  CHECK_FALSE(config::isValidVehicleId(std::string(65, 'a')));
}

TEST_CASE("a minimal telemetry.json gives the installed queue folder, 64 MB, no signals and no remote commands") {
  auto sut = config::parseTelemetryConfig(MINIMAL, "telemetry.json", "/etc/openvcu");
  REQUIRE(sut);
  CHECK(sut->vehicleId == "hhea-01");
  CHECK(sut->broker.host == "127.0.0.1");
  CHECK_FALSE(sut->tls);
  CHECK(sut->queueFolder == "/var/lib/openvcu/telemetry");
  CHECK(sut->maxQueueBytes == 64ull << 20);
  CHECK(sut->signals.empty());
  CHECK_FALSE(sut->remoteCommandsEnabled);
}

TEST_CASE("a full telemetry.json is taken with its paths relative to the file") {
  auto sut = config::parseTelemetryConfig(
      R"({"broker": "mqtts://fleet.example.com", "vehicleId": "hhea-01", "username": "hhea-01",
          "passwordFile": "secrets/mqtt-password",
          "tls": {"caFile": "/etc/ssl/fleet-ca.crt", "certFile": "hhea-01.crt", "keyFile": "hhea-01.key"},
          "queueFolder": "queue", "maxQueueMB": 8,
          "signals": [{"name": "BMS.SOC", "maxRateHz": 2, "deadband": 0.5}, {"name": "internal.fsm.State"}],
          "remoteCommands": {"enabled": true, "keys": ["internal.operator.StartStop"]}})",
      "telemetry.json", "/etc/openvcu");
  REQUIRE(sut);
  CHECK(sut->broker.port == 8883);
  CHECK(sut->passwordFile == "/etc/openvcu/secrets/mqtt-password");
  REQUIRE(sut->tls);
  CHECK(sut->tls->caFile == "/etc/ssl/fleet-ca.crt");
  CHECK(sut->tls->certFile == "/etc/openvcu/hhea-01.crt");
  CHECK(sut->tls->keyFile == "/etc/openvcu/hhea-01.key");
  CHECK(sut->queueFolder == "/etc/openvcu/queue");
  CHECK(sut->maxQueueBytes == 8ull << 20);
  REQUIRE(sut->signals.size() == 2);
  CHECK(sut->signals[0].maxRateHz == 2);
  CHECK(sut->signals[0].deadband == 0.5);
  CHECK(sut->signals[1].maxRateHz == 1);  // the defaults
  CHECK(sut->signals[1].deadband == 0);
  CHECK(sut->remoteCommandsEnabled);
  REQUIRE(sut->remoteCommandKeys.size() == 1);
  CHECK(sut->remoteCommandKeys[0] == "internal.operator.StartStop");
}

TEST_CASE("telemetry.json errors name the file, the JSON path and the reason") {
  CHECK(errorOf(R"({"vehicleId": "v"})") == "telemetry.json: /broker: missing (required)");
  CHECK(errorOf(R"({"broker": "tcp://x", "vehicleId": "v"})").find("telemetry.json: /broker: 'tcp://x': expected mqtt://") == 0);
  CHECK(errorOf(R"({"broker": "mqtt://x", "vehicleId": "a/b"})").find("/vehicleId: 'a/b': 1 to 64 letters") != std::string::npos);
  CHECK(errorOf(R"({"broker": "mqtt://x", "vehicleId": "v", "password": "hunter2"})")
            .find("/password: not in this file") != std::string::npos);
  CHECK(errorOf(R"({"broker": "mqtt://x", "vehicleId": "v", "passwordFile": "p"})")
            .find("/passwordFile: a password file needs a username") != std::string::npos);
  CHECK(errorOf(R"({"broker": "mqtt://x", "vehicleId": "v", "tls": {"caFile": "ca.crt"}})")
            .find("/tls: TLS files need an mqtts:// broker") != std::string::npos);
  CHECK(errorOf(R"({"broker": "mqtts://x", "vehicleId": "v", "tls": {"certFile": "c.crt"}})")
            .find("/tls/keyFile: a client certificate needs both") != std::string::npos);
  CHECK(errorOf(R"({"broker": "mqtt://x", "vehicleId": "v", "maxQueueMB": 0.5})")
            .find("/maxQueueMB: must be a whole number from 1 to 4096") != std::string::npos);
  CHECK(errorOf(R"({"broker": "mqtt://x", "vehicleId": "v", "signals": [{"name": "A", "maxRateHz": 0}]})")
            .find("/signals/0/maxRateHz: must be above 0") != std::string::npos);
  CHECK(errorOf(R"({"broker": "mqtt://x", "vehicleId": "v", "signals": [{"name": "A", "deadband": -1}]})")
            .find("/signals/0/deadband: must be 0 or more") != std::string::npos);
  CHECK(errorOf(R"({"broker": "mqtt://x", "vehicleId": "v", "signals": [{"name": "A"}, {"name": "A"}]})")
            .find("/signals/1/name: 'A' is listed twice") != std::string::npos);
  CHECK(errorOf(R"({"broker": "mqtt://x", "vehicleId": "v", "signals": [{"nam": "A"}]})")
            .find("/signals/0/nam: unknown key 'nam'; did you mean 'name'?") != std::string::npos);
  CHECK(errorOf(R"({"broker": "mqtt://x", "vehicleId": "v", "remoteCommands": {"enabled": true, "keys": ["K", "K"]}})")
            .find("/remoteCommands/keys/1: 'K' is listed twice") != std::string::npos);
}

TEST_CASE("remote commands are refused over a connection the broker does not authenticate") {
  CHECK(errorOf(R"({"broker": "mqtt://127.0.0.1", "vehicleId": "v", "remoteCommands": {"enabled": true, "keys": ["K"]}})")
            .find("/remoteCommands/enabled: remote commands need a broker that authenticates") != std::string::npos);
  auto withCertificate = config::parseTelemetryConfig(
      R"({"broker": "mqtts://fleet", "vehicleId": "v", "tls": {"certFile": "c.crt", "keyFile": "c.key"},
          "remoteCommands": {"enabled": true, "keys": ["K"]}})",
      "telemetry.json", "/etc/openvcu");
  CHECK(withCertificate);
  auto disabled = config::parseTelemetryConfig(
      R"({"broker": "mqtt://127.0.0.1", "vehicleId": "v", "remoteCommands": {"enabled": false, "keys": ["K"]}})",
      "telemetry.json", "/etc/openvcu");
  CHECK(disabled);
}

TEST_CASE("odd but allowed settings are taken with a warning") {
  std::vector<Error> warnings;
  auto sut = config::parseTelemetryConfig(
      R"({"broker": "mqtt://fleet.example.com", "vehicleId": "v", "username": "v", "passwordFile": "p",
          "remoteCommands": {"enabled": true}})",
      "telemetry.json", "/etc/openvcu", &warnings);
  REQUIRE(sut);
  REQUIRE(warnings.size() == 2);
  INFO(warnings[0].toString() << " | " << warnings[1].toString());
  CHECK(warnings[0].toString().find("/remoteCommands/keys: warning: remote commands are enabled but no key") !=
        std::string::npos);
  CHECK(warnings[1].toString().find("/broker: warning: the password goes to fleet.example.com unencrypted") !=
        std::string::npos);
}

TEST_CASE("loadTelemetryConfig reads the file and names it in its errors") {
  const auto folder = std::filesystem::temp_directory_path() / ("openvcu-telemetry-config-" + std::to_string(::getpid()));
  std::filesystem::create_directories(folder);
  const std::string path = (folder / "telemetry.json").string();
  std::ofstream(path) << R"({"broker": "mqtt://127.0.0.1", "vehicleId": "v", "queueFolder": "q"})";
  auto loaded = config::loadTelemetryConfig(path);
  REQUIRE(loaded);
  CHECK(loaded->queueFolder == (folder / "q").string());
  std::ofstream(path) << R"({"broker": "mqtt://127.0.0.1", "vehicleId": "v", "maxQueueMB": 9999})";
  auto bad = config::loadTelemetryConfig(path);
  REQUIRE_FALSE(bad);
  CHECK(bad.error().toString() == path + ": /maxQueueMB: must be a whole number from 1 to 4096");
  auto missing = config::loadTelemetryConfig((folder / "none.json").string());
  REQUIRE_FALSE(missing);
  CHECK(missing.error().message.find("cannot read") != std::string::npos);
  std::filesystem::remove_all(folder);
}
