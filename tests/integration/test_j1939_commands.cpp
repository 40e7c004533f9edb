// `vcu j1939` against the sandbox (issue 24). The test stands in for the services: it
// publishes vcu-can-tx's J1939 view on LCM, takes the Request from can-tx's send stream
// and answers on can-rx's rx stream, as a node on the bus would. The configuration is
// tests/data/integration's with a DBC whose nodes have J1939 addresses (VCU 0x27, BMS 0x21)
// and a "j1939" object on the bus (preferred address 0x28), written into the sandbox's /tmp.

#include <unistd.h>

#include <array>
#include <fstream>
#include <string_view>

#include "integration_support.hpp"
#include "openvcu/ipc/event_bus.hpp"
#include "openvcu/ipc/frame_stream.hpp"
#include "openvcu/ipc/runtime.hpp"
#include "openvcu/ipc/waiter.hpp"

namespace {

constexpr std::uint8_t VCU_ADDRESS = 0x27;
constexpr std::uint8_t BMS_ADDRESS = 0x21;
/// industry group 2, arbitrary address capable, function 130, manufacturer 250, identity 1
constexpr std::uint64_t VCU_NAME = 0xA00082001F400001;
constexpr std::uint64_t BMS_NAME = 0x8000A00000200007;  // identity 7, manufacturer 1, function 160
constexpr auto ANSWER_TIMEOUT = std::chrono::milliseconds(5000);

/// small.dbc with NmStationAddress for both nodes, and a vehicle.json on it (instance itest,
/// sim:vehicle with a "j1939" object: VCU_NAME, preferred address 0x28); returns the
/// vehicle.json path.
std::string writeJ1939Config() {
  const fs::path folder = fs::temp_directory_path() / ("vcu-j1939-" + std::to_string(::getpid()));
  fs::create_directories(folder);
  std::ofstream(folder / "j1939.dbc") << R"(VERSION ""

NS_ :

BS_:

BU_: VCU BMS

BO_ 2566844961 Status: 8 BMS
 SG_ SOC : 0|8@1+ (0.5,0) [0|100] "%" VCU
 SG_ Mode : 8|2@1+ (1,0) [0|3] "" VCU

BO_ 2566845223 Command: 8 VCU
 SG_ Enable : 0|2@1+ (1,0) [0|3] "" BMS

BA_DEF_ BU_ "NmStationAddress" INT 0 255;
BA_ "NmStationAddress" BU_ VCU 39;
BA_ "NmStationAddress" BU_ BMS 33;
VAL_ 2566844961 Mode 0 "Off" 1 "Normal" 2 "Fault" ;
)";
  std::ofstream(folder / "vehicle.json") << R"({
  "instance": "itest",
  "node": "VCU",
  "dbc": "j1939.dbc",
  "buses": [{"name": "vehicle", "link": "sim:vehicle", "bitrate": 250000, "messages": "all",
             "j1939": {"name": {"identityNumber": 1, "manufacturerCode": 250, "function": 130,
                                "vehicleSystem": 0, "industryGroup": 2, "arbitraryAddressCapable": true},
                       "preferredAddress": 40}}]
})";
  return (folder / "vehicle.json").string();
}

ipc::J1939Network vcuView() {
  ipc::J1939Network view;
  view.service = "vcu-can-tx";
  view.instance = INSTANCE;
  view.pid = 4242;
  view.bus = "vehicle";
  view.claimState = ipc::ClaimState::Claimed;
  view.address = VCU_ADDRESS;
  view.name = VCU_NAME;
  view.nodes = {{BMS_ADDRESS, BMS_NAME}, {0x80, 0x0000000000000055}};
  view.dtcs = {{"contactor_weld", 4000, 7, 2, true}, {"precharge_timeout", 520200, 14, 1, false}};
  view.lamps = 0x04;  // amber warning on
  return view;
}

/// Starts `vcu ARGUMENTS... --config CONFIG` in the background with its output captured.
harness::Process& startVcu(harness::Harness& sut, std::vector<std::string> arguments, const std::string& config) {
  std::vector<std::string> argv{VCU};
  argv.insert(argv.end(), arguments.begin(), arguments.end());
  argv.emplace_back("--config");
  argv.push_back(config);
  auto process = sut.start({.name = "vcu-j1939", .argv = argv, .captureOutput = true});
  REQUIRE_STATUS(process);
  return **process;
}

/// Everything an exited process wrote: reads its pipe to the end first.
std::string fullOutput(harness::Process& process) {
  while (process.readLine(std::chrono::milliseconds(500))) {
  }
  return process.output();
}

/// Publishes `view` every 100 ms (LCM has no subscription handshake) until `vcu` exits.
std::optional<harness::ExitStatus> publishUntilExit(harness::Process& vcu, const ipc::J1939Network& view) {
  auto events = ipc::EventBus::open(ipc::DEFAULT_EVENT_URL, INSTANCE);
  REQUIRE_STATUS(events);
  for (int round = 0; round < 50; ++round) {
    REQUIRE(events->publish(view));
    if (auto exit = vcu.waitForExit(std::chrono::milliseconds(100))) return exit;
  }
  return std::nullopt;
}

/// The test as can-tx (subscribed to the send stream) and can-rx (publishing on rx).
struct BusPeer {
  std::optional<ipc::FrameSubscriber> sendRequests;
  std::optional<ipc::FramePublisher> received;
  std::optional<ipc::Waiter> waiter;

  BusPeer() {
    if (!ipc::Runtime::initialized()) REQUIRE_STATUS(ipc::Runtime::init("test-j1939-peer", 5s));
    auto subscriber = ipc::FrameSubscriber::create({INSTANCE, "vehicle", ipc::FrameStream::SendRequest});
    REQUIRE_STATUS(subscriber);
    sendRequests.emplace(std::move(*subscriber));
    auto publisher = ipc::FramePublisher::create({INSTANCE, "vehicle", ipc::FrameStream::Received});
    REQUIRE_STATUS(publisher);
    received.emplace(std::move(*publisher));
    auto created = ipc::Waiter::create();
    REQUIRE_STATUS(created);
    waiter.emplace(std::move(*created));
    REQUIRE_STATUS(waiter->attach(*sendRequests, 0));
  }

  /// The next frame on the send stream, or empty after `timeout`.
  std::optional<can::Frame> nextRequest(std::chrono::milliseconds timeout) {
    const auto end = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < end) {
      if (auto sample = sendRequests->take()) return sample->frame;
      waiter->waitFor(end - std::chrono::steady_clock::now());
    }
    return std::nullopt;
  }

  /// Waits until the tool's rx subscription is connected, then publishes each frame.
  void answer(std::initializer_list<can::Frame> frames) {
    REQUIRE(received->waitForSubscribers(std::chrono::milliseconds(2000)));
    for (const can::Frame& frame : frames) {
      ipc::FrameSample sample{};
      sample.frame = frame;
      REQUIRE(received->publish(sample));
    }
  }
};

can::Frame extendedFrame(std::uint32_t id, std::initializer_list<std::uint8_t> data) {
  can::Frame frame;
  frame.id = id;
  frame.flags = can::FLAG_EXTENDED;
  frame.length = static_cast<std::uint8_t>(data.size());
  std::copy(data.begin(), data.end(), frame.data.begin());
  return frame;
}

}  // namespace

TEST_CASE("vcu j1939 --json prints can-tx's view: claim, NAME fields, nodes with their DBC node, DTCs and lamps") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;
  const std::string config = writeJ1939Config();
  harness::Process& vcu = startVcu(sut, {"j1939", "--json", "--timeout", "5"}, config);

  const auto exit = publishUntilExit(vcu, vcuView());

  REQUIRE_MESSAGE(exit, vcu.output());
  CHECK_MESSAGE(exit->code == 0, vcu.output());
  const std::string output = fullOutput(vcu);
  const nlohmann::json document = nlohmann::json::parse(output.substr(output.find('{')));
  REQUIRE(document["buses"].size() == 1);
  const nlohmann::json& bus = document["buses"][0];
  CHECK(bus["bus"] == "vehicle");
  CHECK(bus["claimState"] == "claimed");
  CHECK(bus["address"] == VCU_ADDRESS);
  CHECK(bus["name"] == "0xA00082001F400001");
  CHECK(bus["nameFields"]["manufacturerCode"] == 250);
  CHECK(bus["nameFields"]["function"] == 130);
  CHECK(bus["nameFields"]["industryGroup"] == 2);
  CHECK(bus["nameFields"]["arbitraryAddressCapable"] == true);
  REQUIRE(bus["nodes"].size() == 2);
  CHECK(bus["nodes"][0]["address"] == BMS_ADDRESS);
  CHECK(bus["nodes"][0]["name"] == "0x8000A00000200007");
  CHECK(bus["nodes"][0]["dbcNode"] == "BMS");
  CHECK(bus["nodes"][1]["dbcNode"].is_null());
  REQUIRE(bus["dtcs"].size() == 2);
  CHECK(
      bus["dtcs"][0] ==
      nlohmann::json::parse(R"({"name": "contactor_weld", "spn": 4000, "fmi": 7, "occurrences": 2, "active": true})"));
  CHECK(bus["dtcs"][1]["active"] == false);
  CHECK(bus["lamps"]["amberWarning"] == "On");
  CHECK(bus["lamps"]["redStop"] == "Off");
}

TEST_CASE("vcu j1939 prints the view as text and, without one, exits 1 saying what to check") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;
  const std::string config = writeJ1939Config();
  harness::Process& vcu = startVcu(sut, {"j1939", "--timeout", "5"}, config);

  const auto exit = publishUntilExit(vcu, vcuView());
  const auto silent = sut.run({VCU, "j1939", "--timeout", "0.3", "--config", config});

  REQUIRE_MESSAGE(exit, vcu.output());
  CHECK(exit->code == 0);
  const std::string output = fullOutput(vcu);
  CHECK_MESSAGE(contains(output, "bus vehicle: claimed, address 0x27 (39), NAME 0xA00082001F400001\n"), output);
  CHECK_MESSAGE(contains(output, "manufacturer code 250, ECU instance 0, function instance 0, function 130"), output);
  CHECK_MESSAGE(contains(output, "0x21 (33)   0x8000A00000200007  BMS"), output);
  CHECK_MESSAGE(contains(output, "DM1 lamps: protect Off, amber warning On, red stop Off, malfunction Off"), output);
  CHECK_MESSAGE(contains(output, "contactor_weld     4000    7    2            active"), output);
  CHECK_MESSAGE(contains(output, "precharge_timeout  520200  14   1            previously active"), output);
  CHECK_MESSAGE(silent.exitCode() == 1, silent.describe());
  CHECK_MESSAGE(contains(silent.err,
                         "no J1939 view from vcu-can-tx within 0.3 s on OPENVCU_ITEST_J1939: is it "
                         "running, does vehicle.json give a bus a \"j1939\" object?"),
                silent.err);
}

TEST_CASE("vcu j1939 request sends the Request through can-tx and decodes the single-frame answer by the DBC") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;
  REQUIRE_STATUS(sut.startRoudi());
  const std::string config = writeJ1939Config();
  BusPeer peer;
  harness::Process& vcu = startVcu(sut, {"j1939", "request", "0xFEF2", "--to", "33", "--from", "0xF9"}, config);

  const auto request = peer.nextRequest(ANSWER_TIMEOUT);
  REQUIRE_MESSAGE(request, vcu.output());
  CHECK(request->id == 0x18EA21F9u);  // Request, priority 6, to 0x21 from 0xF9
  CHECK(request->extended());
  REQUIRE(request->length == 3);
  CHECK(request->data[0] == 0xF2);
  CHECK(request->data[1] == 0xFE);
  CHECK(request->data[2] == 0x00);
  peer.answer({extendedFrame(0x18FEF222, {9, 9, 9, 9, 9, 9, 9, 9}),  // the same PGN from another node
               extendedFrame(0x18FEF221, {1, 2, 3, 4, 5, 6, 7, 8})});
  const auto exit = vcu.waitForExit(ANSWER_TIMEOUT);

  REQUIRE_MESSAGE(exit, vcu.output());
  CHECK_MESSAGE(exit->code == 0, vcu.output());
  const std::string output = fullOutput(vcu);
  CHECK_MESSAGE(contains(output,
                         "PGN 0x0FEF2 (65266) from 0x21 (33) BMS, 8 bytes: 01 02 03 04 05 06 07 08\n"
                         "  Status: SOC=0.5 %, Mode=2 \"Fault\"\n"),
                output);
  CHECK_MESSAGE(!contains(output, "09 09"), output);
}

TEST_CASE(
    "vcu j1939 request from the bus's preferred address reassembles a BAM answer and splits identification fields") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;
  REQUIRE_STATUS(sut.startRoudi());
  const std::string config = writeJ1939Config();
  BusPeer peer;
  // No --from and no J1939 view: the bus's j1939.preferredAddress (0x28) after 1.2 s of listening.
  harness::Process& vcu = startVcu(sut, {"j1939", "request", "65259", "--to", "0x21"}, config);

  const auto request = peer.nextRequest(ANSWER_TIMEOUT);
  REQUIRE_MESSAGE(request, vcu.output());
  CHECK(request->id == 0x18EA2128u);
  // Component Identification, 20 bytes "ACME*VCU1*SN4242*U7*" by BAM: 3 packets.
  peer.answer({extendedFrame(0x1CECFF21, {0x20, 20, 0, 3, 0xFF, 0xEB, 0xFE, 0x00}),
               extendedFrame(0x1CEBFF21, {1, 'A', 'C', 'M', 'E', '*', 'V', 'C'}),
               extendedFrame(0x1CEBFF21, {2, 'U', '1', '*', 'S', 'N', '4', '2'}),
               extendedFrame(0x1CEBFF21, {3, '4', '2', '*', 'U', '7', '*', 0xFF})});
  const auto exit = vcu.waitForExit(ANSWER_TIMEOUT);

  REQUIRE_MESSAGE(exit, vcu.output());
  CHECK_MESSAGE(exit->code == 0, vcu.output());
  const std::string output = fullOutput(vcu);
  CHECK_MESSAGE(contains(output,
                         "PGN 0x0FEEB (65259) from 0x21 (33) BMS, 20 bytes by BAM: 41 43 4D 45 2A 56 43 55 "
                         "31 2A 53 4E 34 32 34 32 2A 55 37 2A\n"
                         "  component identification: make \"ACME\", model \"VCU1\", serial number "
                         "\"SN4242\", unit number \"U7\"\n"),
                output);
}

TEST_CASE("vcu j1939 request prints a NACK and exits 1, and says so when nothing answers") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;
  REQUIRE_STATUS(sut.startRoudi());
  const std::string config = writeJ1939Config();
  BusPeer peer;
  harness::Process& vcu = startVcu(sut, {"j1939", "request", "65242", "--to", "0x21", "--from", "0xF9"}, config);

  REQUIRE_MESSAGE(peer.nextRequest(ANSWER_TIMEOUT), vcu.output());
  peer.answer({extendedFrame(0x18E8FF21, {0x01, 0xFF, 0xFF, 0xFF, 0xF9, 0xDA, 0xFE, 0x00})});
  const auto exit = vcu.waitForExit(ANSWER_TIMEOUT);
  const auto silent = sut.run(
      {VCU, "j1939", "request", "65242", "--to", "0x22", "--from", "0xF9", "--timeout", "0.3", "--config", config});

  REQUIRE_MESSAGE(exit, vcu.output());
  const std::string output = fullOutput(vcu);
  CHECK_MESSAGE(exit->code == 1, output);
  CHECK_MESSAGE(contains(output, "NACK from 0x21 (33) BMS for PGN 0x0FEDA (65242)\n"), output);
  CHECK_MESSAGE(silent.exitCode() == 1, silent.describe());
  CHECK_MESSAGE(contains(silent.err,
                         "vcu: error: no answer to the request for PGN 0x0FEDA (65242) to 0x22 (34) "
                         "from 0xF9 (249) within 0.3 s on openvcu/itest.vehicle/rx"),
                silent.err);
}
