#include "vcu_test_support.hpp"

using namespace openvcu::cli::test;

TEST_CASE("--version prints the tool name and version and exits 0") {
  const RunResult result = runVcu({"--version"});

  CHECK(result.exitCode == EXIT_OK);
  CHECK(result.out.rfind("vcu (openvcu) ", 0) == 0);
  CHECK(result.err.empty());
}

TEST_CASE("--help is the manual: it lists the command groups and the exit codes") {
  const RunResult result = runVcu({"--help"});

  CHECK(result.exitCode == EXIT_OK);
  CHECK(contains(result.out, "dbc"));
  CHECK(contains(result.out, "Exit codes"));
}

TEST_CASE("a subcommand's --help describes its output format") {
  const RunResult result = runVcu({"dbc", "decode", "--help"});

  CHECK(result.exitCode == EXIT_OK);
  CHECK(contains(result.out, "t,bus,id,ext,msg,signal,raw,physical"));
}

TEST_CASE("an unknown command is a usage error with exit code 2") {
  const RunResult result = runVcu({"frobnicate"});

  CHECK(result.exitCode == EXIT_USAGE);
  CHECK(contains(result.err, "vcu: error: "));
  CHECK(contains(result.err, "frobnicate"));
}

TEST_CASE("a command group without a subcommand prints its menu and exits 2") {
  const RunResult result = runVcu({"dbc"});

  CHECK(result.exitCode == EXIT_USAGE);
  CHECK(contains(result.err, "check"));
  CHECK(contains(result.err, "decode"));
}

TEST_CASE("no arguments at all prints the top-level menu and exits 2") {
  const RunResult result = runVcu({});

  CHECK(result.exitCode == EXIT_USAGE);
  CHECK(contains(result.err, "Usage: vcu"));
}
