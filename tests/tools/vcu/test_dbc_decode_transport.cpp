// `vcu dbc decode` and J1939-21 transport (issue 21): a 34-byte PGN 65251 by BAM decoded
// with a DBC message longer than 8 bytes, a DM1 with three DTCs, an aborted RTS/CTS session
// and one cut off by the end of the log, in JSONL and CSV.
#include <nlohmann/json.hpp>

#include <cstdio>
#include <string>
#include <vector>

#include "vcu_test_support.hpp"

using namespace openvcu::cli::test;
using nlohmann::json;

namespace {

using Bytes = std::vector<unsigned>;

/// EC1-like message of 34 bytes (PGN 0xFEE3 = 65251, DBC id 0x18FEE300 | extended flag):
/// one signal in the first frame's bytes, two beyond byte 8.
constexpr const char* TRANSPORT_DBC = R"(VERSION ""
BU_: ENG VCU
BO_ 2566841088 EngineConfig: 34 ENG
 SG_ IdleSpeed : 0|16@1+ (0.125,0) [0|8031.875] "rpm" VCU
 SG_ OverrideSpeed : 160|16@1+ (0.125,0) [0|8031.875] "rpm" VCU
 SG_ OverrideTime : 264|8@1+ (0.1,0) [0|25] "s" VCU
)";

constexpr std::uint32_t ENGINE_CONFIG_ID = 0x18FEE300;  // priority 6, PGN 0xFEE3, SA 0x00: 419357440
constexpr std::uint32_t DM1_FROM_21_ID = 0x18FECA21;    // 419351073
constexpr std::uint32_t COMPONENT_ID_FROM_20 = 0x18FEEB20;  // PGN 0xFEEB from 0x20 (PDU2): 419359520

std::string hex(const Bytes& bytes) {
  std::string text;
  char pair[4];
  for (const unsigned byte : bytes) {
    std::snprintf(pair, sizeof pair, "%02X", byte);
    text += pair;
  }
  return text;
}

std::string line(double seconds, const char* id, const Bytes& bytes) {
  char time[32];
  std::snprintf(time, sizeof time, "(%.6f)", seconds);
  return std::string(time) + " can0 " + id + "#" + hex(bytes) + "\n";
}

/// TP.DT packets of `message` sent as `id`, 50 ms apart from `start`.
std::string packets(double start, const char* id, const Bytes& message) {
  std::string text;
  for (std::size_t offset = 0, sequence = 1; offset < message.size(); offset += 7, ++sequence) {
    Bytes frame{static_cast<unsigned>(sequence)};
    for (std::size_t i = 0; i < 7; ++i) frame.push_back(offset + i < message.size() ? message[offset + i] : 0xFF);
    text += line(start + 0.05 * static_cast<double>(sequence), id, frame);
  }
  return text;
}

Bytes engineConfig() {
  Bytes message(34, 0);
  message[0] = 0x40;  // IdleSpeed raw 0x1F40 = 8000 -> 1000 rpm
  message[1] = 0x1F;
  message[20] = 0x80;  // OverrideSpeed raw 0x3E80 = 16000 -> 2000 rpm
  message[21] = 0x3E;
  message[33] = 25;  // OverrideTime 2.5 s
  return message;
}

// Amber lamp on; SPN 100 FMI 1 OC 3, SPN 110 FMI 0 OC 1, SPN 520192 FMI 31 OC 126 (CM 0).
const Bytes THREE_DTCS = {0x04, 0xFF, 0x64, 0x00, 0x01, 0x03, 0x6E, 0x00, 0x00, 0x01, 0x00, 0xF0, 0xFF, 0x7E};

std::string transportLog() {
  std::string log;
  log += line(1.0, "1CECFF00", {0x20, 34, 0x00, 5, 0xFF, 0xE3, 0xFE, 0x00});  // BAM 34 bytes, 5 packets
  log += packets(1.0, "1CEBFF00", engineConfig());                               // 1.05 .. 1.25
  log += line(2.0, "1CECFF21", {0x20, 14, 0x00, 2, 0xFF, 0xCA, 0xFE, 0x00});  // DM1 BAM 14 bytes
  log += packets(2.0, "1CEBFF21", THREE_DTCS);                                   // 2.05, 2.10
  log += line(3.0, "18FECA03", {0x10, 0xFF, 0xBE, 0x00, 0x02, 0x85, 0xFF, 0xFF});  // DM1 from 0x03: red stop, SPN 190 FMI 2 OC 5 CM 1
  log += line(4.0, "1CEC2120", {0x10, 20, 0x00, 3, 0xFF, 0xEB, 0xFE, 0x00});  // RTS 0x20 -> 0x21
  log += line(4.01, "1CEC2021", {0xFF, 1, 0xFD, 0xFF, 0xFF, 0xEB, 0xFE, 0x00});  // Abort by the responder, reason 1
  log += line(5.0, "1CECFF00", {0x20, 34, 0x00, 5, 0xFF, 0xE3, 0xFE, 0x00});  // BAM again ...
  log += line(5.05, "1CEBFF00", {1, 0x40, 0x1F, 0, 0, 0, 0, 0});               // ... cut off after 1 packet
  return log;
}

// Lines of the JSONL output.
constexpr std::size_t ENGINE_CONFIG_RECORD = 6;  // after BAM + 5 packets
constexpr std::size_t DM1_RECORD = 10;           // after BAM + 2 packets
constexpr std::size_t SINGLE_DM1 = 11;
constexpr std::size_t ABORT_RECORD = 14;         // after RTS + Abort
constexpr std::size_t INCOMPLETE_RECORD = 17;    // after BAM + 1 packet, at the end
constexpr std::size_t OUTPUT_LINES = 18;

}  // namespace

TEST_CASE("decode writes a reassembled BAM message decoded with a DBC message longer than 8 bytes") {
  const std::string dbc = writeScratchFile("transport.dbc", TRANSPORT_DBC);
  const std::string log = writeScratchFile("transport.log", transportLog());
  const RunResult result = runVcu({"dbc", "decode", "--stats", dbc, log});
  REQUIRE(result.exitCode == EXIT_OK);
  const std::vector<std::string> lines = splitLines(result.out);
  REQUIRE(lines.size() == OUTPUT_LINES);

  CHECK(lines[ENGINE_CONFIG_RECORD] ==
        R"({"t":1.250000,"bus":"can0","id":419357440,"ext":true,"msg":"EngineConfig",)"
        R"("signals":{"IdleSpeed":1000,"OverrideSpeed":2000,"OverrideTime":2.5},)"
        R"("raw":{"IdleSpeed":8000,"OverrideSpeed":16000,"OverrideTime":25},)"
        R"("tp":{"pgn":65251,"sa":0,"da":255,"size":34,"bam":true}})");
  // The TP frames themselves stay ordinary unknown frames.
  const json packet = json::parse(lines[ENGINE_CONFIG_RECORD - 1]);
  CHECK(packet["id"] == 0x1CEBFF00);
  CHECK(packet["msg"].is_null());
  CHECK_FALSE(packet.contains("tp"));

  const json dm1 = json::parse(lines[DM1_RECORD]);
  CHECK(dm1["id"] == DM1_FROM_21_ID);
  CHECK(dm1["t"].get<double>() == doctest::Approx(2.1));
  CHECK(dm1["msg"].is_null());
  CHECK(dm1["tp"] == json::parse(R"({"pgn":65226,"sa":33,"da":255,"size":14,"bam":true})"));
  CHECK(dm1["dm1"]["type"] == "DM1");
  CHECK(dm1["dm1"]["lamps"] ==
        json::parse(R"({"malfunction":"Off","redStop":"Off","amberWarning":"On","protect":"Off"})"));
  CHECK(dm1["dm1"]["dtcs"] == json::parse(R"([{"spn":100,"fmi":1,"oc":3,"cm":0},{"spn":110,"fmi":0,"oc":1,"cm":0},)"
                                          R"({"spn":520192,"fmi":31,"oc":126,"cm":0}])"));

  const json single = json::parse(lines[SINGLE_DM1]);
  CHECK(single["id"] == 0x18FECA03);
  CHECK_FALSE(single.contains("tp"));
  CHECK(single["dm1"]["lamps"]["redStop"] == "On");
  CHECK(single["dm1"]["dtcs"] == json::parse(R"([{"spn":190,"fmi":2,"oc":5,"cm":1}])"));

  const json aborted = json::parse(lines[ABORT_RECORD]);
  CHECK(aborted["id"] == COMPONENT_ID_FROM_20);
  CHECK(aborted["t"].get<double>() == doctest::Approx(4.01));
  CHECK(aborted["tp"] == json::parse(R"({"pgn":65259,"sa":32,"da":33,"size":20,"bam":false})"));
  CHECK(aborted["tp_end"]["outcome"] == "Aborted");
  CHECK(aborted["tp_end"]["reason"] == "by the responder, reason 1 AlreadyInSession");
  CHECK(aborted["tp_end"]["received"] == 0);
  CHECK(aborted["tp_end"]["packets"] == 3);
  CHECK(aborted["tp_end"]["start"].get<double>() == doctest::Approx(4.0));

  const json incomplete = json::parse(lines[INCOMPLETE_RECORD]);
  CHECK(incomplete["id"] == ENGINE_CONFIG_ID);
  CHECK(incomplete["msg"] == "EngineConfig");
  CHECK(incomplete["tp_end"]["outcome"] == "Incomplete");
  CHECK(incomplete["tp_end"]["reason"] == "the log ended");
  CHECK(incomplete["tp_end"]["received"] == 1);
  CHECK(incomplete["tp_end"]["packets"] == 5);

  CHECK(contains(result.err,
                 "J1939 TP: 2 messages reassembled, 2 Completed, 1 Aborted, 0 TimedOut, 0 Replaced, "
                 "0 ProtocolError, 1 Incomplete, 0 Refused"));
}

TEST_CASE("decode writes a timed-out session when the next frame comes after its deadline") {
  std::string log;
  log += line(1.0, "1CECFF00", {0x20, 34, 0x00, 5, 0xFF, 0xE3, 0xFE, 0x00});
  log += line(1.05, "1CEBFF00", {1, 0x40, 0x1F, 0, 0, 0, 0, 0});
  log += line(2.0, "18FEF100", {0, 0, 0, 0, 0, 0, 0, 0});  // 950 ms later: T1 (750 ms) has passed
  const std::string dbc = writeScratchFile("transport.dbc", TRANSPORT_DBC);
  const RunResult result = runVcu({"dbc", "decode", dbc, writeScratchFile("timeout.log", log)});
  REQUIRE(result.exitCode == EXIT_OK);
  const std::vector<std::string> lines = splitLines(result.out);
  REQUIRE(lines.size() == 4);
  const json timedOut = json::parse(lines[2]);  // before the frame that came after the deadline
  CHECK(timedOut["t"].get<double>() == doctest::Approx(1.8));
  CHECK(timedOut["tp_end"]["outcome"] == "TimedOut");
  CHECK(timedOut["tp_end"]["reason"] == "T1 ran out");
  CHECK(json::parse(lines[3])["id"] == 0x18FEF100);
}

TEST_CASE("decode writes reassembled signals and DTC rows in CSV") {
  const std::string dbc = writeScratchFile("transport.dbc", TRANSPORT_DBC);
  const std::string log = writeScratchFile("transport.log", transportLog());
  const RunResult result = runVcu({"dbc", "decode", "--format", "csv", dbc, log});
  REQUIRE(result.exitCode == EXIT_OK);
  CHECK(contains(result.out, "1.250000,can0,419357440,true,EngineConfig,IdleSpeed,8000,1000\n"
                             "1.250000,can0,419357440,true,EngineConfig,OverrideSpeed,16000,2000\n"
                             "1.250000,can0,419357440,true,EngineConfig,OverrideTime,25,2.5\n"));
  CHECK(contains(result.out, "2.100000,can0,419351073,true,DM1,lamp.malfunction,0,0\n"
                             "2.100000,can0,419351073,true,DM1,lamp.redStop,0,0\n"
                             "2.100000,can0,419351073,true,DM1,lamp.amberWarning,1,1\n"
                             "2.100000,can0,419351073,true,DM1,lamp.protect,0,0\n"
                             "2.100000,can0,419351073,true,DM1,dtc1.spn,100,100\n"
                             "2.100000,can0,419351073,true,DM1,dtc1.fmi,1,1\n"
                             "2.100000,can0,419351073,true,DM1,dtc1.oc,3,3\n"
                             "2.100000,can0,419351073,true,DM1,dtc1.cm,0,0\n"));
  CHECK(contains(result.out, "2.100000,can0,419351073,true,DM1,dtc3.spn,520192,520192\n"));
  CHECK(contains(result.out,
                 "4.010000,can0,419359520,true,tp_end,\"Aborted: by the responder, reason 1 AlreadyInSession, "
                 "0 of 3 packets\",,\n"));
}
