// Issue 19: logs that are not regular files, long reads that a SIGTERM must end, ASC
// frames with unreadable identifiers, and diagnostics quoting control characters. Every
// input is made by the test.

#include <doctest/doctest.h>
#include <sys/stat.h>

#include <chrono>
#include <string>

#include "../core/pending_signal.hpp"
#include "../core/temp_folder.hpp"
#include "log_test_support.hpp"
#include "openvcu/can/log_reader.hpp"
#include "openvcu/can/replay_link.hpp"

using namespace openvcu::can;
using openvcu::can::test::readAll;
using openvcu::can::test::readText;

namespace {

constexpr auto PROMPTLY = std::chrono::seconds(1);

LinkOptions replayOptions() {
  LinkOptions options;
  options.replaySpeed = 0.0;
  return options;
}

}  // namespace

TEST_CASE("a log that is a directory, a FIFO or /dev/zero is refused at open, naming what it is (#19)") {
  const openvcu::test::TempFolder folder;
  const std::string fifo = folder.path("fifo.log");
  REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
  const auto started = std::chrono::steady_clock::now();

  const auto directory = LogReader::open(folder.path(""));
  const auto pipe = LogReader::open(fifo);
  const auto zero = LogReader::open("/dev/zero");

  REQUIRE_FALSE(directory.ok());
  CHECK(directory.error().toString() == folder.path("") + ": not a regular file (directory)");
  REQUIRE_FALSE(pipe.ok());
  CHECK(pipe.error().toString() == fifo + ": not a regular file (FIFO)");
  REQUIRE_FALSE(zero.ok());
  CHECK(zero.error().toString() == "/dev/zero: not a regular file (character device)");
  CHECK(std::chrono::steady_clock::now() - started < PROMPTLY);
}

TEST_CASE("a replay: link on /dev/zero fails at once instead of spinning (#19)") {
  const auto started = std::chrono::steady_clock::now();

  const auto sut = ReplayLink::open("/dev/zero", replayOptions());

  REQUIRE_FALSE(sut.ok());
  CHECK(sut.error().toString() == "replay:/dev/zero: not a regular file (character device)");
  CHECK(std::chrono::steady_clock::now() - started < PROMPTLY);
}

TEST_CASE("a pending SIGTERM ends reading a log that holds no line end, with an error saying so (#19)") {
  const openvcu::test::TempFolder folder;
  constexpr std::size_t SIZE = 4 * 1024 * 1024;  // many read chunks, not one line end
  const std::string path = folder.write("no-newline.log", std::string(SIZE, 'A'));
  auto openResult = LogReader::open(path);
  REQUIRE(openResult.ok());
  const openvcu::test::PendingSigterm pending;

  const auto result = readAll(*openResult);

  CHECK(result.records.empty());
  REQUIRE(result.errors.size() == 1);
  CHECK(result.errors[0].toString() == path + ": reading stopped: SIGTERM is pending");
}

TEST_CASE("a replay: link whose first frame lies behind a long stretch stops at a pending SIGTERM (#19)") {
  const openvcu::test::TempFolder folder;
  constexpr std::size_t SIZE = 4 * 1024 * 1024;
  const std::string path = folder.write("late.log", std::string(SIZE, 'A') + "\n(1.0) can0 123#11\n");
  const openvcu::test::PendingSigterm pending;

  const auto sut = ReplayLink::open(path, replayOptions());

  REQUIRE_FALSE(sut.ok());
  CHECK(sut.error().toString().find("reading stopped: SIGTERM is pending") != std::string::npos);
}

TEST_CASE("ASC frame lines with an unreadable or out-of-range identifier are reported, other events are not (#19)") {
  const auto result = readText("date Fri Mar 1 00:00:00.000 2024\n"
                               "base hex  timestamps absolute\n"
                               "   0.001 1  ZZZ             Rx   d 1 11\n"
                               "   0.002 1  800             Rx   d 1 22\n"
                               "   0.003 1  20000000x       Tx   r 1\n"
                               "   0.004 1  Statistic: D 0 R 0 XD 0 XR 0 E 0 O 0 B 0.00%\n"
                               "   0.005 1  123             Rx   d 1 33\n"
                               "   0.006 CANFD   1 Rx  G12  1 0 1 1 44  1000 200 1000 0 0 0 0 0\n",
                               LogFormat::Auto);

  REQUIRE(result.records.size() == 1);
  CHECK(result.records[0].frame.id == 0x123);
  REQUIRE(result.errors.size() == 4);
  CHECK(result.errors[0].toString() == "test.log:3:13: invalid CAN identifier 'ZZZ'");
  CHECK(result.errors[1].toString() == "test.log:4:13: standard identifier '800' exceeds 0x7FF (a 29-bit one ends in 'x')");
  CHECK(result.errors[2].toString() == "test.log:5:13: extended identifier '20000000x' exceeds 0x1FFFFFFF");
  CHECK(result.errors[3].toString() == "test.log:8:24: invalid CAN identifier 'G12'");
}

TEST_CASE("a log diagnostic quoting a CR from the middle of a line keeps it printable (#19)") {
  const auto result = readText("(1.0) can0 12\r3#11\n", LogFormat::Candump);

  REQUIRE(result.errors.size() == 1);
  CHECK(result.errors[0].message.find('\r') == std::string::npos);
  CHECK(result.errors[0].message.find("\\r") != std::string::npos);
}
