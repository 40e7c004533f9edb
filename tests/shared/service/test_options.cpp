// The command line every service shares: --config (or OPENVCU_CONFIG), --instance,
// --log-level, --help, --version, and a service's own options.

#include <doctest/doctest.h>

#include <string>
#include <vector>

#include "openvcu/service/options.hpp"

namespace ipc = openvcu::ipc;
namespace service = openvcu::service;

namespace {

service::ServiceInfo testInfo() {
  service::ServiceInfo info;
  info.name = "demo";
  info.description = "a service for the option tests";
  info.version = "9.8.7";
  return info;
}

}  // namespace

TEST_CASE("the common options give the configuration, the instance and the log level") {
  service::CommandLine sut(testInfo());

  const auto outcome =
      sut.parse(std::vector<std::string>{"--config", "vehicle.json", "--instance", "bench2", "--log-level", "debug"});

  CHECK_FALSE(outcome.exitCode.has_value());
  CHECK(sut.options().configPath == "vehicle.json");
  CHECK(sut.options().instance == "bench2");
  CHECK(sut.options().logLevel == ipc::LogLevel::Debug);
}

TEST_CASE("without --instance and --log-level the configuration's instance and level info apply") {
  service::CommandLine sut(testInfo());

  const auto outcome = sut.parse(std::vector<std::string>{"-c", "vehicle.json"});

  CHECK_FALSE(outcome.exitCode.has_value());
  CHECK(sut.options().instance.empty());
  CHECK(sut.options().logLevel == ipc::LogLevel::Info);
}

TEST_CASE("OPENVCU_CONFIG stands in for a missing --config, and --config wins over it") {
  service::CommandLine fromEnvironment(testInfo());
  service::CommandLine explicitOne(testInfo());

  const auto first = fromEnvironment.parse(std::vector<std::string>{}, std::string("env.json"));
  const auto second = explicitOne.parse(std::vector<std::string>{"--config", "arg.json"}, std::string("env.json"));

  CHECK_FALSE(first.exitCode.has_value());
  CHECK(fromEnvironment.options().configPath == "env.json");
  CHECK_FALSE(second.exitCode.has_value());
  CHECK(explicitOne.options().configPath == "arg.json");
}

TEST_CASE("no configuration at all is a usage error with exit code 2 and one line") {
  service::CommandLine sut(testInfo());

  const auto outcome = sut.parse(std::vector<std::string>{});

  REQUIRE(outcome.exitCode);
  CHECK(*outcome.exitCode == 2);
  CHECK(outcome.isError);
  CHECK(outcome.text == "vcu-demo: error: no configuration: give --config FILE or set OPENVCU_CONFIG (see --help)\n");
}

TEST_CASE("--help prints the options and exits with 0 without needing a configuration") {
  service::CommandLine sut(testInfo());

  const auto outcome = sut.parse(std::vector<std::string>{"--help"});

  REQUIRE(outcome.exitCode);
  CHECK(*outcome.exitCode == 0);
  CHECK_FALSE(outcome.isError);
  CHECK(outcome.text.find("a service for the option tests") != std::string::npos);
  CHECK(outcome.text.find("--log-level") != std::string::npos);
  CHECK(outcome.text.find("READY=1") != std::string::npos);
}

TEST_CASE("--version prints the program name and version and exits with 0") {
  service::CommandLine sut(testInfo());

  const auto outcome = sut.parse(std::vector<std::string>{"--version"});

  REQUIRE(outcome.exitCode);
  CHECK(*outcome.exitCode == 0);
  CHECK(outcome.text == "vcu-demo (openvcu) 9.8.7\n");
}

TEST_CASE("an unknown option and an unknown log level are usage errors") {
  service::CommandLine unknownOption(testInfo());
  service::CommandLine unknownLevel(testInfo());

  const auto first = unknownOption.parse(std::vector<std::string>{"--config", "v.json", "--bogus"});
  const auto second = unknownLevel.parse(std::vector<std::string>{"--config", "v.json", "--log-level", "loud"});

  REQUIRE(first.exitCode);
  CHECK(*first.exitCode == 2);
  CHECK(first.text.find("--bogus") != std::string::npos);
  REQUIRE(second.exitCode);
  CHECK(*second.exitCode == 2);
  CHECK(second.text.find("loud") != std::string::npos);
}

TEST_CASE("a service's own options and flags are parsed together with the common ones") {
  service::CommandLine sut(testInfo());
  std::string fsmFile;
  double rate = 0.0;
  std::int64_t count = 0;
  bool dryRun = false;
  sut.addOption("--fsm-file", fsmFile, "FSM file");
  sut.addOption("--rate", rate, "rate");
  sut.addOption("--count", count, "count");
  sut.addFlag("--dry-run", dryRun, "do nothing");

  const auto outcome = sut.parse(std::vector<std::string>{"--config", "v.json", "--fsm-file", "fsm.json", "--rate",
                                                          "2.5", "--count", "7", "--dry-run"});

  CHECK_FALSE(outcome.exitCode.has_value());
  CHECK(fsmFile == "fsm.json");
  CHECK(rate == 2.5);
  CHECK(count == 7);
  CHECK(dryRun);
}

TEST_CASE("the program name is vcu-<name> unless the service names it") {
  service::ServiceInfo info = testInfo();
  CHECK(info.programName() == "vcu-demo");
  info.program = "vcu-fixture-service";
  CHECK(info.programName() == "vcu-fixture-service");
}

TEST_CASE("log level names round-trip, and 'warn' is accepted for warning") {
  for (const auto level : {ipc::LogLevel::Trace, ipc::LogLevel::Debug, ipc::LogLevel::Info, ipc::LogLevel::Warning,
                           ipc::LogLevel::Error, ipc::LogLevel::Critical}) {
    CHECK(service::parseLogLevel(service::logLevelName(level)) == level);
  }
  CHECK(service::parseLogLevel("warn") == ipc::LogLevel::Warning);
  CHECK_FALSE(service::parseLogLevel("verbose").has_value());
}
