// `vcu send` and `vcu dump` against real iox-roudi and the simulated bus sim:vehicle of
// tests/data/integration/vehicle.json (instance itest, classic CAN, small.dbc), each case
// in its own sandbox. No CAN service runs: the dump listens on the sim bus itself
// (--stream wire), or stands in for can-tx on the send stream.

#include <chrono>
#include <cstdlib>
#include <exception>
#include <optional>
#include <string>
#include <vector>

#include "integration_support.hpp"

namespace {

/// An extended frame that small.dbc does not define.
constexpr const char* EXTENDED_FRAME = "18FEF121#0102030405060708";
/// small.dbc's Status (BO_ 2566844961 = 0x98FEF221): SOC = byte 0 x 0.5 %, Mode = bits 8..9.
constexpr const char* STATUS_FRAME = "18FEF221#0102030405060708";
/// The dump's readiness line for the simulated bus.
constexpr const char* LISTENING_ON_WIRE = "listening on openvcu/sim.vehicle/wire";
constexpr std::int64_t PLAUSIBLE_CLOCK_SKEW_S = 60;

/// Starts `vcu dump vehicle ARGUMENTS... --config CONFIG` and waits for its "listening on" line.
harness::Process& startDump(harness::Harness& sut, std::vector<std::string> arguments, const std::string& listening) {
  std::vector<std::string> argv{VCU, "dump", "vehicle"};
  argv.insert(argv.end(), arguments.begin(), arguments.end());
  argv.emplace_back("--config");
  argv.push_back(CONFIG);
  auto dump = sut.start({.name = "vcu-dump", .argv = argv, .captureOutput = true});
  REQUIRE_STATUS(dump);
  REQUIRE_MESSAGE((*dump)->waitForLine(listening, harness::READY_TIMEOUT), (*dump)->output());
  return **dump;
}

/// " vehicle 18FEF121#..." of "(1700000000.123456) vehicle 18FEF121#...": the line without its time.
std::string withoutTime(const std::string& line) {
  const std::size_t close = line.find(')');
  return close == std::string::npos ? line : line.substr(close + 1);
}

/// The seconds of "(1700000000.123456) ...", or -1.
std::int64_t secondsOf(const std::string& line) {
  if (line.empty() || line.front() != '(') return -1;
  try {
    return std::stoll(line.substr(1));
  } catch (const std::exception&) {
    return -1;
  }
}

std::int64_t nowSeconds() {
  return std::chrono::duration_cast<std::chrono::seconds>(std::chrono::system_clock::now().time_since_epoch()).count();
}

}  // namespace

TEST_CASE("vcu dump --stream wire prints exactly the candump line of a frame vcu send --direct put on the sim bus") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;
  REQUIRE_STATUS(sut.startRoudi());
  harness::Process& dump = startDump(sut, {"--stream", "wire", "--count", "1", "--timeout", "10"}, LISTENING_ON_WIRE);

  const auto send = vcu(sut, {"send", "--direct", "vehicle", EXTENDED_FRAME});
  const auto line = dump.waitForLine("vehicle", harness::READY_TIMEOUT);
  const auto exit = dump.waitForExit(harness::READY_TIMEOUT);

  CHECK_MESSAGE(send.exitCode() == 0, send.describe());
  CHECK(send.out == "sent 1 frame on sim:vehicle\n");
  REQUIRE_MESSAGE(line, dump.output());
  CHECK(withoutTime(*line) == std::string(" vehicle ") + EXTENDED_FRAME);
  CHECK_MESSAGE(std::abs(secondsOf(*line) - nowSeconds()) < PLAUSIBLE_CLOCK_SKEW_S, *line);
  REQUIRE(exit);
  CHECK(exit->exited);
  CHECK(exit->code == 0);
}

TEST_CASE("vcu dump --decode appends the DBC message and its signals with unit and value text") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;
  REQUIRE_STATUS(sut.startRoudi());
  harness::Process& dump =
      startDump(sut, {"--stream", "wire", "--decode", "--count", "1", "--timeout", "10"}, LISTENING_ON_WIRE);

  const auto send = vcu(sut, {"send", "--direct", "vehicle", STATUS_FRAME});
  const auto line = dump.waitForLine("vehicle", harness::READY_TIMEOUT);

  CHECK_MESSAGE(send.exitCode() == 0, send.describe());
  REQUIRE_MESSAGE(line, dump.output());
  CHECK(withoutTime(*line) == std::string(" vehicle ") + STATUS_FRAME + "  Status: SOC=0.5 %, Mode=2 \"Fault\"");
}

TEST_CASE("vcu send --repeat sends the whole list in order, N times, and --stream all prefixes the stream") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;
  REQUIRE_STATUS(sut.startRoudi());
  harness::Process& dump = startDump(sut, {"--stream", "all", "--count", "4", "--timeout", "10"},
                                     "openvcu/itest.vehicle/rx, openvcu/itest.vehicle/tx");

  const auto send = vcu(sut, {"send", "--direct", "vehicle", "123#01", "123#02", "--repeat", "2", "--interval", "5"});
  std::vector<std::string> wireFrames;
  while (wireFrames.size() < 4) {
    const auto line = dump.readLine(harness::READY_TIMEOUT);
    if (!line) break;
    if (line->rfind("wire (", 0) == 0) wireFrames.push_back(withoutTime(*line));
  }
  const auto exit = dump.waitForExit(harness::READY_TIMEOUT);

  CHECK_MESSAGE(send.exitCode() == 0, send.describe());
  CHECK(send.out == "sent 4 frames on sim:vehicle\n");
  const std::vector<std::string> inOrderTwice{" vehicle 123#01", " vehicle 123#02", " vehicle 123#01",
                                              " vehicle 123#02"};
  CHECK_MESSAGE(wireFrames == inOrderTwice, dump.output());
  REQUIRE(exit);
  CHECK(exit->code == 0);
}

TEST_CASE("vcu send publishes to can-tx's send stream when it has a subscriber") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;
  REQUIRE_STATUS(sut.startRoudi());
  // The dump on the send stream stands in for vcu-can-tx: any subscriber counts.
  harness::Process& dump = startDump(sut, {"--stream", "send", "--count", "1", "--timeout", "10"},
                                     "listening on openvcu/itest.vehicle/send");

  const auto send = vcu(sut, {"send", "vehicle", "123#DEADBEEF"});
  const auto line = dump.waitForLine("vehicle", harness::READY_TIMEOUT);

  CHECK_MESSAGE(send.exitCode() == 0, send.describe());
  CHECK(send.out == "sent 1 frame to can-tx on openvcu/itest.vehicle/send\n");
  REQUIRE_MESSAGE(line, dump.output());
  CHECK(withoutTime(*line) == " vehicle 123#DEADBEEF");
}

TEST_CASE("vcu send without a listening can-tx sends nothing, exits 1 and suggests --direct") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;
  REQUIRE_STATUS(sut.startRoudi());

  const auto send = vcu(sut, {"send", "vehicle", "123#00"});

  CHECK_MESSAGE(send.exitCode() == 1, send.describe());
  CHECK(send.out.empty());
  CHECK_MESSAGE(contains(send.err,
                         "nothing sent: nobody listens on openvcu/itest.vehicle/send (is vcu-can-tx "
                         "running?); --direct writes onto sim:vehicle without can-tx"),
                send.err);
}

TEST_CASE("vcu dump --timeout without any frame exits 1 and names the stream and its publisher") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;
  REQUIRE_STATUS(sut.startRoudi());

  const auto dump = vcu(sut, {"dump", "vehicle", "--timeout", "0.3"});

  CHECK_MESSAGE(dump.exitCode() == 1, dump.describe());
  CHECK(dump.out.empty());
  CHECK_MESSAGE(contains(dump.err, "listening on openvcu/itest.vehicle/rx (Ctrl-C to stop)"), dump.err);
  CHECK_MESSAGE(contains(dump.err,
                         "vcu: error: no frame on openvcu/itest.vehicle/rx for 0.3 s (is vcu-can-rx "
                         "running?)"),
                dump.err);
}

TEST_CASE("vcu dump stops with exit code 0 on SIGTERM") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;
  REQUIRE_STATUS(sut.startRoudi());
  harness::Process& dump = startDump(sut, {}, "listening on openvcu/itest.vehicle/rx");

  const auto exit = sut.stop(dump);

  REQUIRE(exit);
  CHECK(exit->exited);
  CHECK(exit->code == 0);
}

TEST_CASE("vcu send and dump name an unknown bus with a did-you-mean and a malformed frame with its column") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;
  // No iox-roudi: both answers come from vcu itself, before any IPC.

  const auto unknownBus = vcu(sut, {"send", "--direct", "vehicel", "123#00"});
  const auto unknownDumpBus = vcu(sut, {"dump", "vehicel"});
  const auto malformed = vcu(sut, {"send", "--direct", "vehicle", "12G#00"});

  CHECK_MESSAGE(unknownBus.exitCode() == 1, unknownBus.describe());
  CHECK(unknownBus.err == "vcu: error: unknown bus 'vehicel' (did you mean 'vehicle'?)\n");
  CHECK_MESSAGE(unknownDumpBus.exitCode() == 1, unknownDumpBus.describe());
  CHECK(unknownDumpBus.err == "vcu: error: unknown bus 'vehicel' (did you mean 'vehicle'?)\n");
  CHECK_MESSAGE(malformed.exitCode() == 2, malformed.describe());
  CHECK(malformed.err == "vcu: error: '12G#00': not a hexadecimal digit at column 3\n");
}

TEST_CASE("vcu send --direct and vcu dump say so when iox-roudi is not running") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;

  const auto send = vcu(sut, {"send", "--direct", "vehicle", "123#00"});
  const auto dump = vcu(sut, {"dump", "vehicle", "--stream", "wire"});

  CHECK_MESSAGE(send.exitCode() == 1, send.describe());
  CHECK_MESSAGE(contains(send.err, "iox-roudi is not running"), send.err);
  CHECK_MESSAGE(dump.exitCode() == 1, dump.describe());
  CHECK_MESSAGE(contains(dump.err, "iox-roudi is not running"), dump.err);
}
