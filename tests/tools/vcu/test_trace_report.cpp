// `vcu trace report` in-process: a folder as `vcu record` writes it (vehicle.log and an
// events.lcmlog written through LCM's own file:// provider, no network) gives one HTML
// file with the FSM states and faults on the time axis; bad signal names and a missing
// log are reported (the pipeline itself is trace::makeReport, tests/shared/trace).

#include <doctest/doctest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "openvcu/ipc/event_bus.hpp"
#include "vcu_test_support.hpp"

using namespace openvcu::cli::test;
namespace ipc = openvcu::ipc;

namespace {

constexpr const char* REPORT_DBC = R"(VERSION ""
NS_ :
BS_:
BU_: VCU OBC
BO_ 2566869221 OBC: 8 OBC
 SG_ Voltage : 0|16@1+ (0.1,0) [0|1000] "V" VCU
BA_DEF_ BO_ "GenMsgCycleTime" INT 0 65535;
BA_DEF_DEF_ "GenMsgCycleTime" 0;
BA_ "GenMsgCycleTime" BO_ 2566869221 100;
)";

constexpr std::int64_t START_NS = 1'700'000'000'000'000'000;

std::string readText(const std::filesystem::path& path) {
  std::ifstream file(path);
  std::stringstream text;
  text << file.rdbuf();
  return text.str();
}

}  // namespace

TEST_CASE("vcu trace report on a vcu record folder puts the FSM states and faults on the time axis") {
  const std::filesystem::path folder = scratchFolder() / "report_record";
  std::filesystem::remove_all(folder);
  std::filesystem::create_directories(folder);
  const std::string dbc = writeScratchFile("report_obc.dbc", REPORT_DBC);
  {
    std::ofstream log(folder / "vehicle.log");
    for (int i = 0; i < 50; ++i) {  // OBC (0x18FF50E5) every 100 ms, Voltage 400.0 V then 410.0 V
      const int raw = i < 25 ? 4000 : 4100;
      char line[96];
      std::snprintf(line, sizeof line, "(%d.%06d) vehicle 18FF50E5#%02X%02X000000000000\n", 1'700'000'000 + i / 10,
                    (i % 10) * 100'000, raw & 0xFF, raw >> 8);
      log << line;
    }
  }
  {
    auto busResult = ipc::EventBus::open("file://" + (folder / "events.lcmlog").string() + "?mode=w", "hhea");
    REQUIRE_MESSAGE(busResult.ok(), (busResult.ok() ? "" : busResult.error().toString()));
    CHECK(busResult->publish(ipc::FsmTransition{START_NS + 1'000'000'000, "Off", "KeepAliveState", "StartStop == 1"}));
    CHECK(busResult->publish(ipc::FaultEvent{START_NS + 2'000'000'000, "BMS_IsolationFault", "0xF3",
                                             ipc::FaultSeverity::Critical, true, "isolation low"}));
  }
  const std::string html = (scratchFolder() / "report_record.html").string();
  // the signal by its table key (NODE.MESSAGE.SIGNAL, as `vcu signal list` shows it)
  const RunResult result =
      runVcu({"trace", "report", "--dbc", dbc, folder.string(), "-o", html, "--signals", "OBC.OBC.Voltage"});
  INFO(result.err);
  CHECK(result.exitCode == EXIT_OK);
  CHECK(contains(result.out, "50 frames"));
  const std::string text = readText(html);
  CHECK(contains(text, "KeepAliveState"));      // the FSM lane
  CHECK(contains(text, "BMS_IsolationFault"));  // the fault lane
  CHECK(contains(text, "OBC.Voltage"));         // the signal chart
  CHECK(contains(text, "data-chart=\"event-lanes\""));
  CHECK(contains(text, "data-chart=\"signals-1\""));
}

TEST_CASE("vcu trace report names an unknown signal and a missing log") {
  const std::string dbc = writeScratchFile("report_obc.dbc", REPORT_DBC);
  const std::string log = writeScratchFile("report_one.log", "(1700000000.000000) can0 18FF50E5#A00F000000000000\n");
  const std::string html = (scratchFolder() / "report_one.html").string();
  const RunResult unknown = runVcu({"trace", "report", "--dbc", dbc, log, "-o", html, "--signals", "OBC.Current"});
  CHECK(unknown.exitCode == EXIT_INPUT_ERROR);
  CHECK(contains(unknown.err, "OBC.Current: no such signal"));
  const RunResult wrongNode = runVcu({"trace", "report", "--dbc", dbc, log, "-o", html, "--signals", "VCU.OBC.Voltage"});
  CHECK(wrongNode.exitCode == EXIT_INPUT_ERROR);  // OBC is sent by OBC, not VCU
  CHECK(contains(readText(html), "</html>"));  // written anyway, with what could be read

  const RunResult missing = runVcu({"trace", "report", "/nonexistent/drive.log", "-o", html});
  CHECK(missing.exitCode == EXIT_INPUT_ERROR);
  CHECK(contains(missing.err, "/nonexistent/drive.log"));

  // one of two logs missing: named, exit 1, and the report of the other one is written
  std::filesystem::remove(html);
  const RunResult oneMissing = runVcu({"trace", "report", "--dbc", dbc, log, "/nonexistent/drive.log", "-o", html});
  CHECK(oneMissing.exitCode == EXIT_INPUT_ERROR);
  CHECK(contains(oneMissing.err, "/nonexistent/drive.log"));
  CHECK(contains(oneMissing.out, "1 frames"));
  CHECK(contains(readText(html), "</html>"));
}
