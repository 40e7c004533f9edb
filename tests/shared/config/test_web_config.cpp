// web.json (shared/config/web.hpp): vcu-web's settings, defaults, ranges and JSON paths.
#include <doctest/doctest.h>

#include "openvcu/config/web.hpp"

namespace {

using namespace openvcu;

std::string errorOf(std::string_view text) {
  auto parsed = config::parseWebConfig(text, "web.json", "/etc/openvcu");
  REQUIRE_FALSE(parsed);
  return parsed.error().toString();
}

}  // namespace

TEST_CASE("an empty web.json gives loopback port 8080 and the installed paths") {
  auto sut = config::parseWebConfig("{}", "web.json", "/etc/openvcu");
  REQUIRE(sut);
  CHECK(sut->address == "127.0.0.1");
  CHECK(sut->port == 8080);
  CHECK(sut->dataFolder == "/var/lib/openvcu");
  CHECK(sut->maxUpdatesPerSecond == 20);
}

TEST_CASE("web.json paths are relative to its folder and limits are taken") {
  auto sut = config::parseWebConfig(
      R"({"listen": "127.0.0.1:0", "dataFolder": "data", "usersFile": "/srv/users.json", "maxUploadMB": 8,
          "maxClients": 10, "sessionMinutes": 5})",
      "web.json", "/etc/openvcu");
  REQUIRE(sut);
  CHECK(sut->port == 0);
  CHECK(sut->dataFolder == "/etc/openvcu/data");
  CHECK(sut->usersFile == "/srv/users.json");
  CHECK(sut->maxUploadBytes == 8u << 20);
  CHECK(sut->maxClients == 10);
  CHECK(sut->sessionMinutes == 5);
}

TEST_CASE("web.json errors name the JSON path and the reason") {
  CHECK(errorOf(R"({"listen": "localhost:80"})").find("/listen") != std::string::npos);
  CHECK(errorOf(R"({"listen": "127.0.0.1:99999"})").find("the port must be 0-65535") != std::string::npos);
  CHECK(errorOf(R"({"maxUpdatesPerSecond": 500})").find("/maxUpdatesPerSecond: must be from 1 to 50") != std::string::npos);
  CHECK(errorOf(R"({"maxClients": 2.5})").find("/maxClients: must be a whole number from 1 to 256") != std::string::npos);
  CHECK(errorOf(R"({"listn": "127.0.0.1:80"})").find("listn") != std::string::npos);
}

TEST_CASE("a listen address beyond loopback is taken with a warning") {
  std::vector<Error> warnings;
  auto sut = config::parseWebConfig(R"({"listen": "0.0.0.0:8080"})", "web.json", "/etc/openvcu", &warnings);
  REQUIRE(sut);
  CHECK(sut->address == "0.0.0.0");
  REQUIRE(warnings.size() == 1);
  CHECK(warnings[0].toString().find("reachable from its network") != std::string::npos);
}

TEST_CASE("web.json trustedOrigins takes browser origins and names a malformed one by its index") {
  auto sut = config::parseWebConfig(R"({"trustedOrigins": ["https://vcu.example", "http://10.0.0.5:8443"]})", "web.json",
                                    "/etc/openvcu");
  REQUIRE(sut);
  CHECK(sut->trustedOrigins == std::vector<std::string>{"https://vcu.example", "http://10.0.0.5:8443"});
  CHECK(errorOf(R"({"trustedOrigins": ["https://vcu.example/"]})").find("/trustedOrigins/0: 'https://vcu.example/'") !=
        std::string::npos);
  CHECK(errorOf(R"({"trustedOrigins": ["ok", 1]})").find("/trustedOrigins/0") != std::string::npos);
  CHECK(errorOf(R"({"trustedOrigins": ["https://a.b", 1]})").find("/trustedOrigins/1: expected a string") != std::string::npos);
  CHECK(errorOf(R"({"trustedOrigins": ["ftp://vcu.example"]})").find("/trustedOrigins/0") != std::string::npos);
  CHECK(errorOf(R"({"trustedOrigins": ["https://VCU.example"]})").find("lower case") != std::string::npos);
  CHECK(errorOf(R"({"trustedOrigins": "https://vcu.example"})").find("/trustedOrigins") != std::string::npos);
}
