#include "vcu_test_support.hpp"

using namespace openvcu::cli::test;

TEST_CASE("info lists every message with its J1939 fields, cycle time and comment on one line") {
  const RunResult result = runVcu({"dbc", "info", dataPath("vehicle.dbc")});

  REQUIRE(result.exitCode == EXIT_OK);
  const std::vector<std::string> lines = splitLines(result.out);
  REQUIRE(lines.size() > 8);
  CHECK(lines[0] == dataPath("vehicle.dbc") + ": 4 messages, 11 signals, 3 nodes");
  CHECK(lines[4].rfind("ID          IDE  MESSAGE    LEN  TX      PGN             PRIO  SA    DA", 0) == 0);
  CHECK(lines[5] ==
        "0x0CF004FE  ext  EEC1       8    Engine  0xF004 (61444)  3     0xFE  -     10 ms   ExtendedCAN  "
        "Electronic engine controller 1 second line of the comment");
  CHECK(lines[7].rfind("0x0C040BFE  ext  XBR        8    Vcu     0x0400 (1024)   3     0xFE  0x0B  -", 0) == 0);
  CHECK(lines[8].rfind("0x123       std  VcuStatus  8    Vcu     -", 0) == 0);
}

TEST_CASE("info shows each signal's layout, scaling, range, mux role and receivers") {
  const RunResult result = runVcu({"dbc", "info", dataPath("vehicle.dbc")});

  REQUIRE(result.exitCode == EXIT_OK);
  CHECK(contains(result.out,
                 "  EngSpd/EngineSpeedWithALongName  24|16@1+  int   0.125   0       [0|8031.875]  rpm   -    -       "
                 "Vcu,Brakes\n"));
  CHECK(contains(result.out, "  Voltage      8|16@1+   int      0.01    0       [0|655.35]        V     m1   -"));
  CHECK(contains(result.out, "  Ratio        24|32@1-  float32  1"));
  CHECK(
      contains(result.out, "  ParkingBrake  2|2@1+   int   1           0       [0|3]        -     -    4       Vcu\n"));
}

TEST_CASE("info --message shows only that message") {
  const RunResult result = runVcu({"dbc", "info", dataPath("vehicle.dbc"), "--message", "XBR"});

  REQUIRE(result.exitCode == EXIT_OK);
  CHECK(contains(result.out, "XBR 0x0C040BFE ext, 1 signal\n"));
  CHECK_FALSE(contains(result.out, "EEC1"));
}

TEST_CASE("info --message also takes the message's ID") {
  const RunResult result = runVcu({"dbc", "info", dataPath("vehicle.dbc"), "-m", "0x123"});

  REQUIRE(result.exitCode == EXIT_OK);
  CHECK(contains(result.out, "VcuStatus 0x123 std, 5 signals\n"));
}

TEST_CASE("info --message with an unknown name exits 1 and suggests the closest name") {
  const RunResult result = runVcu({"dbc", "info", dataPath("vehicle.dbc"), "--message", "EEC"});

  CHECK(result.exitCode == EXIT_INPUT_ERROR);
  CHECK(contains(result.err, "error: no message 'EEC'; did you mean 'EEC1'?"));
  CHECK(result.out.empty());
}

TEST_CASE("info refuses a file with errors and prints them") {
  const RunResult result = runVcu({"dbc", "info", dataPath("broken.dbc")});

  CHECK(result.exitCode == EXIT_INPUT_ERROR);
  CHECK(contains(result.err, "broken.dbc:11:20: error: "));
  CHECK(result.out.empty());
}
