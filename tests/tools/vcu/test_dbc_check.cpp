#include "vcu_test_support.hpp"

using namespace openvcu::cli::test;

TEST_CASE("check exits 0 and prints one summary line for a clean file") {
  const std::string path = dataPath("vehicle.dbc");

  const RunResult result = runVcu({"dbc", "check", path});

  CHECK(result.exitCode == EXIT_OK);
  CHECK(result.out == path + ": 4 messages, 11 signals, 3 nodes, 0 errors, 0 warnings\n");
  CHECK(result.err.empty());
}

TEST_CASE("check exits 1 and prints the error with file, line and column") {
  const std::string path = dataPath("broken.dbc");

  const RunResult result = runVcu({"dbc", "check", path});

  CHECK(result.exitCode == EXIT_INPUT_ERROR);
  CHECK(result.err.rfind(path + ":11:20: error: ", 0) == 0);
  CHECK(contains(result.out, "1 error, 0 warnings"));
}

TEST_CASE("check prints warnings with their location and still exits 0") {
  const std::string path = dataPath("warning.dbc");

  const RunResult result = runVcu({"dbc", "check", path});

  CHECK(result.exitCode == EXIT_OK);
  CHECK(result.err.rfind(path + ":12:1: warning: ", 0) == 0);
  CHECK(contains(result.out, "0 errors, 1 warning\n"));
}

TEST_CASE("check --quiet hides warnings but still counts them") {
  const RunResult result = runVcu({"dbc", "check", "--quiet", dataPath("warning.dbc")});

  CHECK(result.exitCode == EXIT_OK);
  CHECK(result.err.empty());
  CHECK(contains(result.out, "1 warning"));
}

TEST_CASE("check exits 1 with the OS reason when a file is missing") {
  const std::string path = dataPath("no_such_file.dbc");

  const RunResult result = runVcu({"dbc", "check", path});

  CHECK(result.exitCode == EXIT_INPUT_ERROR);
  CHECK(result.err == path + ": error: cannot open: No such file or directory\n");
}

TEST_CASE("check reports a directory given as a DBC file as not a regular file") {
  const RunResult result = runVcu({"dbc", "check", std::string(VCU_TEST_DATA)});

  CHECK(result.exitCode == EXIT_INPUT_ERROR);
  CHECK(result.err == std::string(VCU_TEST_DATA) + ": error: not a regular file (directory)\n");
}

TEST_CASE("check of /dev/zero is refused at once naming the file, not an internal error (#19)") {
  const RunResult result = runVcu({"dbc", "check", "/dev/zero"});

  CHECK(result.exitCode == EXIT_INPUT_ERROR);
  CHECK(result.err == "/dev/zero: error: not a regular file (character device)\n");
}

TEST_CASE("check refuses an empty or VERSION-only DBC: a database without messages is an error") {
  const std::string empty = writeScratchFile("empty.dbc", "");
  const std::string versionOnly = writeScratchFile("version_only.dbc", "VERSION \"1.0\"\n");

  for (const std::string& path : {empty, versionOnly}) {
    const RunResult result = runVcu({"dbc", "check", path});

    CHECK_MESSAGE(result.exitCode == EXIT_INPUT_ERROR, path);
    CHECK(result.err == path + ": error: no messages (no BO_ line): a DBC describes at least one message\n");
    CHECK(result.out == path + ": 0 messages, 0 signals, 0 nodes, 1 error, 0 warnings\n");
  }
}

TEST_CASE("check of several files warns about one without messages and passes when the merge has some") {
  const std::string nodesOnly = writeScratchFile("nodes_only.dbc", "VERSION \"\"\n\nBU_: Tool\n");

  const RunResult result = runVcu({"dbc", "check", dataPath("vehicle.dbc"), nodesOnly});

  CHECK(result.exitCode == EXIT_OK);
  CHECK(contains(result.err, nodesOnly + ": warning: no messages (no BO_ line): "));
  CHECK(contains(result.out, nodesOnly + ": 0 messages, 0 signals, 1 node, 0 errors, 1 warning\n"));

  const RunResult noneAtAll = runVcu({"dbc", "check", nodesOnly, nodesOnly});
  CHECK(noneAtAll.exitCode == EXIT_INPUT_ERROR);
  CHECK(contains(noneAtAll.err, "merged (2 files): no messages (no BO_ line)"));
}

TEST_CASE("check of files that agree prints a summary of the merged database") {
  const RunResult result = runVcu({"dbc", "check", dataPath("vehicle.dbc"), dataPath("body.dbc")});

  CHECK(result.exitCode == EXIT_OK);
  CHECK(contains(result.out, "merged (2 files): 5 messages, 13 signals, 4 nodes, 0 errors, 0 warnings\n"));
}

TEST_CASE("check reports a message defined differently in two files as a merge conflict") {
  const std::string conflicting = dataPath("conflicting.dbc");

  const RunResult result = runVcu({"dbc", "check", dataPath("vehicle.dbc"), conflicting});

  CHECK(result.exitCode == EXIT_INPUT_ERROR);
  CHECK(result.err.rfind(conflicting + ":9: error: message 'EEC1'", 0) == 0);
  CHECK(contains(result.out, "1 conflicting file left out"));
}

TEST_CASE("check without a file is a usage error") {
  const RunResult result = runVcu({"dbc", "check"});

  CHECK(result.exitCode == EXIT_USAGE);
  CHECK(result.out.empty());
}
