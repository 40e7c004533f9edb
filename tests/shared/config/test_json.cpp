#include "openvcu/config/json.hpp"

#include <doctest/doctest.h>

using namespace openvcu;
using namespace openvcu::config;

TEST_CASE("a JSON syntax error names line and column") {
  const auto sut = parseJson("{\n  \"a\": 1,\n  \"b\": ,\n}", "x.json");
  REQUIRE_FALSE(sut.ok());
  CHECK(sut.error().location.file == "x.json");
  CHECK(sut.error().location.line == 3);
  CHECK(sut.error().location.column == 8);
  CHECK(sut.error().toString().find("invalid JSON") != std::string::npos);
}

TEST_CASE("JSON comments are accepted") {
  const auto sut = parseJson("{ // note\n \"a\": 1 /* more */ }", "x.json");
  REQUIRE(sut.ok());
  CHECK((*sut)["a"] == 1);
}

TEST_CASE("a missing file is an error naming the file and the reason") {
  const auto sut = readJsonFile("/nonexistent/openvcu.json");
  REQUIRE_FALSE(sut.ok());
  CHECK(sut.error().toString().find("/nonexistent/openvcu.json") == 0);
  CHECK(sut.error().message.find("No such file") != std::string::npos);
}

TEST_CASE("an unknown key is an error with a did-you-mean suggestion and its JSON path") {
  JsonChecker sut("v.json");
  const Json document = Json::parse(R"({"instnace": "x", "node": "VCU"})");
  sut.onlyKeys(document, "", {"instance", "node"});
  REQUIRE_FALSE(sut.ok());
  CHECK(sut.firstError().toString() == "v.json: /instnace: unknown key 'instnace'; did you mean 'instance'?");
}

TEST_CASE("typed getters report the wrong type with the path and return empty") {
  JsonChecker sut("v.json");
  const Json document = Json::parse(R"({"rate": "fast", "on": 1, "name": 3})");
  CHECK_FALSE(sut.number(document, "/bus", "rate").has_value());
  CHECK_FALSE(sut.boolean(document, "/bus", "on").has_value());
  CHECK_FALSE(sut.string(document, "/bus", "name").has_value());
  CHECK_FALSE(sut.string(document, "/bus", "absent").has_value());
  CHECK(sut.string(document, "/bus", "optional", false) == std::nullopt);
  REQUIRE(sut.diagnostics().size() == 4);
  CHECK(sut.diagnostics()[0].toString() == "v.json: /bus/rate: must be a number, not a string");
  CHECK(sut.diagnostics()[3].toString() == "v.json: /bus/absent: missing (required)");
}
