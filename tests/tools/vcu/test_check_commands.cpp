// Issue 19: `vcu check` over every file of a vehicle, `vcu fsm check` on stderr and blaming
// the schedule for its own syntax error, and `vcu` finding the running stack's
// configuration through its command sockets. Broken vehicles are copies of config/hhea
// made by the test, each with one file damaged.

#include <doctest/doctest.h>
#include <fcntl.h>
#include <signal.h>
#include <stdlib.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "stack_access.hpp"
#include "vcu_test_support.hpp"

using namespace openvcu::cli::test;
namespace fs = std::filesystem;

namespace {

const fs::path HHEA_FOLDER = fs::path(OPENVCU_SOURCE_DIR) / "config/hhea";

/// A copy of config/hhea in the scratch folder under `name`, with `file` replaced by
/// `content` when given; returns the copy's vehicle.json.
std::string hheaCopy(const std::string& name, const std::string& file = {}, const std::string& content = {}) {
  const fs::path folder = scratchFolder() / name;
  fs::remove_all(folder);
  fs::create_directories(folder);
  for (const auto& entry : fs::directory_iterator(HHEA_FOLDER)) {
    if (entry.is_regular_file()) fs::copy_file(entry.path(), folder / entry.path().filename());
  }
  if (!file.empty()) writeScratchFile(name + "/" + file, content);
  return (folder / "vehicle.json").string();
}

/// Sets an environment variable for one scope.
class ScopedEnvironment {
 public:
  ScopedEnvironment(const char* name, const std::string& value) : m_name(name) {
    if (const char* old = ::getenv(name)) m_old = old;
    ::setenv(name, value.c_str(), 1);
  }
  ~ScopedEnvironment() {
    if (m_old) {
      ::setenv(m_name, m_old->c_str(), 1);
    } else {
      ::unsetenv(m_name);
    }
  }
  ScopedEnvironment(const ScopedEnvironment&) = delete;
  ScopedEnvironment& operator=(const ScopedEnvironment&) = delete;

 private:
  const char* m_name;
  std::optional<std::string> m_old;
};

/// A stand-in service: a child process listening on <root>/<instance>/<program>.sock whose
/// command line carries `arguments` (it is /bin/sh running a script that waits).
class FakeService {
 public:
  FakeService(const fs::path& root, const std::string& instance, const std::vector<std::string>& arguments,
              const fs::path& workingFolder = fs::current_path()) {
    const fs::path folder = root / instance;
    fs::create_directories(folder);
    fs::permissions(folder, fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec);
    const std::string script = writeScratchFile("fake_service.sh", "sleep 60\n");
    const std::string socketPath = (folder / "vcu-fake.sock").string();
    m_pid = ::fork();
    REQUIRE(m_pid >= 0);
    if (m_pid == 0) {
      // a group of its own, so the destructor ends the script's `sleep` too; output away
      // from the test's (ctest waits for every holder of its pipe)
      ::setpgid(0, 0);
      const int null = ::open("/dev/null", O_RDWR);
      ::dup2(null, STDOUT_FILENO);
      ::dup2(null, STDERR_FILENO);
      const int fd = ::socket(AF_UNIX, SOCK_SEQPACKET, 0);
      sockaddr_un address{};
      address.sun_family = AF_UNIX;
      std::strncpy(address.sun_path, socketPath.c_str(), sizeof(address.sun_path) - 1);
      ::unlink(socketPath.c_str());
      if (fd < 0 || ::bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address)) != 0 || ::listen(fd, 8) != 0) {
        ::_exit(3);
      }
      if (::chdir(workingFolder.c_str()) != 0) ::_exit(4);
      std::vector<const char*> argv{"/bin/sh", script.c_str()};
      for (const std::string& argument : arguments) argv.push_back(argument.c_str());
      argv.push_back(nullptr);
      ::execv("/bin/sh", const_cast<char* const*>(argv.data()));
      ::_exit(5);
    }
    // ready once the socket accepts a connection and the child has exec'd the script (the
    // socket listens before execv: a look at /proc/PID/cmdline in between sees the test's)
    const std::string cmdline = "/proc/" + std::to_string(m_pid) + "/cmdline";
    for (int attempt = 0; attempt < 500; ++attempt) {
      const int probe = ::socket(AF_UNIX, SOCK_SEQPACKET, 0);
      sockaddr_un address{};
      address.sun_family = AF_UNIX;
      std::strncpy(address.sun_path, socketPath.c_str(), sizeof(address.sun_path) - 1);
      const bool up = ::connect(probe, reinterpret_cast<sockaddr*>(&address), sizeof(address)) == 0;
      ::close(probe);
      std::ifstream cmdlineFile(cmdline, std::ios::binary);
      const std::string text((std::istreambuf_iterator<char>(cmdlineFile)), std::istreambuf_iterator<char>());
      if (up && text.find(script) != std::string::npos) return;
      ::usleep(10'000);
    }
    FAIL("the stand-in service did not listen");
  }
  ~FakeService() {
    ::kill(-m_pid, SIGKILL);
    ::waitpid(m_pid, nullptr, 0);
  }
  FakeService(const FakeService&) = delete;
  FakeService& operator=(const FakeService&) = delete;

 private:
  pid_t m_pid{};
};

}  // namespace

TEST_CASE("vcu check passes the shipped HHEA vehicle and lists every file it checked") {
  const RunResult result = runVcu({"check", "--config", (HHEA_FOLDER / "vehicle.json").string()});
  CHECK_MESSAGE(result.exitCode == EXIT_OK, result.err);
  for (const char* file : {"vehicle.json: 0 errors", "hhea.dbc: 0 errors", "gpio.json: 0 errors", "fsm.json: 0 errors",
                           "schedule.json: 0 errors", "simulation.json: 0 errors", "dashboard.json: 0 errors",
                           "telemetry.json: 0 errors", "safety.json: 0 errors"}) {
    CHECK_MESSAGE(contains(result.out, file), file);
  }
  // the whole-vehicle checks' two warnings (#22): received messages nothing reads, and the
  // DC-DC command the VCU sends with the charger's source address 0xE5 (as the original did)
  CHECK(contains(result.out, "vehicle 'hhea': 12 files, 0 errors, 2 warnings\n"));
  CHECK(contains(result.err, "vehicle.json: /buses/0/messages: warning: bus 'vehicle': "));
  CHECK(contains(result.err, "hhea.dbc:166: warning: bus 'vehicle': J1939 source address 0xE5 (229)"));
  CHECK_FALSE(contains(result.err, "error:"));
  // every file through its loader: no note that a service checks the rest when it starts (#20)
  CHECK_FALSE(contains(result.err, "note:"));
}

TEST_CASE("vcu check takes the vehicle file or its folder as a positional argument, as --config") {
  const std::string vehicle = (HHEA_FOLDER / "vehicle.json").string();
  const RunResult byOption = runVcu({"check", "--config", vehicle});
  const RunResult byFile = runVcu({"check", vehicle});
  const RunResult byFolder = runVcu({"check", HHEA_FOLDER.string()});

  CHECK_MESSAGE(byFile.exitCode == byOption.exitCode, byFile.err);
  CHECK_MESSAGE(byFolder.exitCode == byOption.exitCode, byFolder.err);
  CHECK(byFile.exitCode == EXIT_OK);
  CHECK(byFolder.exitCode == EXIT_OK);
  CHECK(contains(byFile.out, "vehicle 'hhea': "));
  CHECK(byFile.out == byOption.out);  // the same files, the same counts
  CHECK(contains(byFolder.out, "vehicle 'hhea': "));
  CHECK(contains(byFolder.out, (HHEA_FOLDER / "vehicle.json").string() + ": 0 errors"));
}

TEST_CASE("vcu check refuses a positional path and a different --config, and a folder without vehicle.json") {
  const std::string vehicle = (HHEA_FOLDER / "vehicle.json").string();
  const std::string other = hheaCopy("check_other");
  const RunResult different = runVcu({"check", vehicle, "--config", other});
  CHECK(different.exitCode == EXIT_USAGE);
  CHECK(contains(different.err, "two configurations given: '" + vehicle + "' and --config '" + other + "'"));

  // the same vehicle named twice, once by its folder: no conflict
  const RunResult same = runVcu({"check", HHEA_FOLDER.string(), "--config", vehicle});
  CHECK_MESSAGE(same.exitCode == EXIT_OK, same.err);

  const fs::path empty = scratchFolder() / "check_empty_folder";
  fs::create_directories(empty);
  const RunResult noVehicle = runVcu({"check", empty.string()});
  CHECK(noVehicle.exitCode == EXIT_INPUT_ERROR);
  CHECK(contains(noVehicle.err, (empty / "vehicle.json").string()));
  CHECK(contains(noVehicle.err, "a folder given as the configuration must hold vehicle.json"));
}

TEST_CASE("the commands that read the stack's configuration take its folder for --config, as vcu check does") {
  const std::string vehicle = (HHEA_FOLDER / "vehicle.json").string();
  const RunResult byFile = runVcu({"signal", "list", "--config", vehicle});
  const RunResult byFolder = runVcu({"signal", "list", "--config", HHEA_FOLDER.string()});
  REQUIRE_MESSAGE(byFile.exitCode == EXIT_OK, byFile.err);
  CHECK_MESSAGE(byFolder.exitCode == EXIT_OK, byFolder.err);
  CHECK(byFolder.out == byFile.out);

  const fs::path empty = scratchFolder() / "stack_empty_folder";
  fs::create_directories(empty);
  const RunResult noVehicle = runVcu({"signal", "list", "--config", empty.string()});
  CHECK(noVehicle.exitCode == EXIT_INPUT_ERROR);
  CHECK(contains(noVehicle.err, (empty / "vehicle.json").string() +
                                    ": error: a folder given as the configuration must hold vehicle.json"));
}

TEST_CASE("vcu check reports a broken simulation, dashboard and schedule together with their locations (#19)") {
  const std::string vehicle = hheaCopy("check_broken", "simulation.json", "{\"vehicle\": {\"x\": 1,}}");
  writeScratchFile("check_broken/dashboard.json", "[1, 2]");
  writeScratchFile("check_broken/schedule.json", "{\"messages\": {\n  \"a\": 1\n  \"b\": 2}}");
  const RunResult result = runVcu({"check", "--config", vehicle});
  CHECK(result.exitCode == EXIT_INPUT_ERROR);
  CHECK(contains(result.err, "check_broken/simulation.json:1:"));
  CHECK(contains(result.err, "check_broken/dashboard.json: error: the top level must be a JSON object"));
  CHECK(contains(result.err, "check_broken/schedule.json:3:"));
  // the schedule's syntax error is not turned into unknown send groups of fsm.json
  CHECK_FALSE(contains(result.err, "fsm.json: /"));
  CHECK(contains(result.out, "schedule.json: 1 error"));
  CHECK(contains(result.out, "fsm.json: 0 errors"));
  CHECK(contains(result.out, "12 files, 3 errors"));
  CHECK(result.out.find("error:") == std::string::npos);  // diagnostics on stderr only
}

TEST_CASE("vcu check refuses a fractional cycle in the schedule with its JSON path (#19)") {
  const std::string vehicle = hheaCopy("check_cycle");
  const fs::path schedulePath = fs::path(vehicle).parent_path() / "schedule.json";
  std::string text;
  {
    std::ifstream in(schedulePath);
    text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  const std::string message = "\"S1_ES_PGN61427\": {";
  const auto at = text.find(message);
  REQUIRE(at != std::string::npos);
  text.insert(at + message.size(), "\"cycleMs\": 0.5, ");
  writeScratchFile("check_cycle/schedule.json", text);
  const RunResult result = runVcu({"check", "--config", vehicle});
  CHECK(result.exitCode == EXIT_INPUT_ERROR);
  CHECK(contains(result.err, "check_cycle/schedule.json: /messages/S1_ES_PGN61427/cycleMs: error: "));
  CHECK(contains(result.err, "0.5"));
  CHECK(contains(result.out, "schedule.json: 1 error"));
}

/// The text of `path`.
std::string readFile(const fs::path& path) {
  std::ifstream in(path);
  REQUIRE(in.good());
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

/// A copy of config/hhea under `name` whose receive.json holds `receive`; returns the copy's
/// vehicle.json.
std::string hheaCopyWithReceive(const std::string& name, const std::string& receive) {
  return hheaCopy(name, "receive.json", receive);
}

/// A copy of config/hhea under `name` whose `file` has the first `from` replaced by `to`;
/// returns the copy's vehicle.json.
std::string hheaCopyEdited(const std::string& name, const std::string& file, const std::string& from,
                           const std::string& to) {
  const std::string vehicle = hheaCopy(name);
  std::string text = readFile(fs::path(vehicle).parent_path() / file);
  const auto at = text.find(from);
  REQUIRE(at != std::string::npos);
  text.replace(at, from.size(), to);
  writeScratchFile(name + "/" + file, text);
  return vehicle;
}

TEST_CASE("vcu check refuses cycleMs 0, another node's message and an unknown wake signal, at their paths") {
  SUBCASE("cycleMs 0 in the schedule") {
    const std::string vehicle =
        hheaCopyEdited("check_cycle0", "schedule.json", "\"PDU_Rx_1\": {", "\"PDU_Rx_1\": {\"cycleMs\": 0, ");
    const RunResult result = runVcu({"check", "--config", vehicle});
    CHECK(result.exitCode == EXIT_INPUT_ERROR);
    CHECK_MESSAGE(contains(result.err,
                           "check_cycle0/schedule.json: /messages/PDU_Rx_1/cycleMs: error: the cycle "
                           "must be a whole number of ms from 1 to 3600000, not 0"),
                  result.err);
    CHECK(contains(result.out, "schedule.json: 1 error"));
  }
  SUBCASE("the schedule sends the VIC's battery status") {
    const std::string vehicle = hheaCopyEdited("check_impersonate", "schedule.json", "\"messages\": {",
                                               "\"messages\": {\"HVESSS1_PGN61590\": {}, ");
    const RunResult result = runVcu({"check", "--config", vehicle});
    CHECK(result.exitCode == EXIT_INPUT_ERROR);
    CHECK_MESSAGE(contains(result.err,
                           "check_impersonate/schedule.json: /messages/HVESSS1_PGN61590: error: message "
                           "'HVESSS1_PGN61590' is sent by VIC (its DBC transmitter)"),
                  result.err);
    CHECK(contains(result.out, "schedule.json: 1 error"));
  }
  SUBCASE("a wake signal the catalog does not have") {
    const std::string vehicle =
        hheaCopyEdited("check_wake", "simulation.json", "internal.gpio.Cl15", "internal.gpio.Cl16");
    const RunResult result = runVcu({"check", "--config", vehicle});
    CHECK(result.exitCode == EXIT_INPUT_ERROR);
    CHECK_MESSAGE(contains(result.err,
                           "check_wake/simulation.json: /wakeSignal: error: unknown signal "
                           "'internal.gpio.Cl16'; did you mean 'internal.gpio.Cl15'?"),
                  result.err);
  }
}

TEST_CASE("vcu check refuses a simulation file its loader refuses, with the file and the JSON path (#19, #20)") {
  const std::string vehicle =
      hheaCopy("check_simulation", "simulation.json", R"({"model": "hhea", "battery": {"initialSoc": 150}})");

  const RunResult result = runVcu({"check", "--config", vehicle});

  CHECK(result.exitCode == EXIT_INPUT_ERROR);
  CHECK_MESSAGE(contains(result.err, "check_simulation/simulation.json: /battery/initialSoc: error: "), result.err);
  CHECK(contains(result.out, "simulation.json: 1 error"));
  CHECK(contains(result.out, "12 files, 1 error"));
}

TEST_CASE(
    "vcu check refuses a receive file naming a message the DBC lacks, with the file and the JSON path (#19, #20)") {
  const std::string vehicle =
      hheaCopyWithReceive("check_receive", R"({"messages": {"HVESSS1_PGN6159": {"timeoutMs": 300}}})");

  const RunResult result = runVcu({"check", "--config", vehicle});

  CHECK(result.exitCode == EXIT_INPUT_ERROR);
  CHECK_MESSAGE(contains(result.err, "check_receive/receive.json: /messages/HVESSS1_PGN6159: error: "), result.err);
  CHECK(contains(result.err, "HVESSS1_PGN61590"));  // the suggestion
  CHECK(contains(result.out, "receive.json: 1 error"));
  CHECK(contains(result.out, "12 files, 1 error"));
}

TEST_CASE("vcu check passes a receive file its loader accepts and counts it") {
  const std::string vehicle = hheaCopyWithReceive("check_receive_ok", R"({"timeoutFactor": 5, "dm1": true})");

  const RunResult result = runVcu({"check", "--config", vehicle});

  CHECK_MESSAGE(result.exitCode == EXIT_OK, result.err);
  CHECK(contains(result.out, "receive.json: 0 errors, 0 warnings"));
  CHECK(contains(result.out, "vehicle 'hhea': 12 files, 0 errors, 2 warnings\n"));  // the whole-vehicle ones (#22)
}

TEST_CASE("vcu check counts a whole-vehicle error for its file and fails: two nodes with one address (#22)") {
  const std::string vehicle = hheaCopy("check_address");
  std::string dbc;
  {
    std::ifstream in(HHEA_FOLDER / "hhea.dbc");
    dbc.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  const std::string charger = "BA_ \"NmStationAddress\" BU_ OBC 229;";
  REQUIRE(dbc.find(charger) != std::string::npos);
  dbc.replace(dbc.find(charger), charger.size(), "BA_ \"NmStationAddress\" BU_ OBC 243;");  // the VIC's
  writeScratchFile("check_address/hhea.dbc", dbc);

  const RunResult result = runVcu({"check", "--config", vehicle});

  CHECK(result.exitCode == EXIT_INPUT_ERROR);
  CHECK_MESSAGE(
      contains(result.err, "hhea.dbc: error: bus 'vehicle': J1939 source address 0xF3 (243) is used by 2 nodes"),
      result.err);
  CHECK(contains(result.err, "OBC (NmStationAddress)"));
  CHECK(contains(result.out, "hhea.dbc: 1 error, 1 warning"));
  CHECK(contains(result.out, "vehicle 'hhea': 12 files, 1 error, 2 warnings\n"));
}

TEST_CASE("vcu check refuses a schedule naming a message the DBC lacks, with the file and the JSON path (#19, #20)") {
  const std::string vehicle = hheaCopy("check_schedule");
  const fs::path schedulePath = fs::path(vehicle).parent_path() / "schedule.json";
  std::string text = readFile(schedulePath);
  const std::string messages = "\"messages\": {";
  const auto at = text.find(messages);
  REQUIRE(at != std::string::npos);
  text.insert(at + messages.size(), "\"HVESSC1_PGN691\": {\"cycleMs\": 100}, ");
  writeScratchFile("check_schedule/schedule.json", text);

  const RunResult result = runVcu({"check", "--config", vehicle});

  CHECK(result.exitCode == EXIT_INPUT_ERROR);
  CHECK_MESSAGE(contains(result.err, "check_schedule/schedule.json: /messages/HVESSC1_PGN691"), result.err);
  CHECK(contains(result.out, "schedule.json: 1 error"));
  CHECK(contains(result.out, "fsm.json: 0 errors"));  // its send groups still come from the schedule
  CHECK(contains(result.out, "12 files, 1 error"));
}

TEST_CASE(
    "vcu check refuses a dashboard naming a signal the catalog lacks, with the file and the JSON path (#19, #20)") {
  const std::string vehicle =
      hheaCopy("check_dashboard", "dashboard.json",
               R"({"items": [{"key": "internal.relay.Cl15"}, {"key": "internal.relay.Cl16"}]})");

  const RunResult result = runVcu({"check", "--config", vehicle});

  CHECK(result.exitCode == EXIT_INPUT_ERROR);
  CHECK_MESSAGE(
      contains(result.err, "check_dashboard/dashboard.json: /items/1/key: error: unknown signal 'internal.relay.Cl16'"),
      result.err);
  CHECK(contains(result.out, "dashboard.json: 1 error"));
  CHECK(contains(result.out, "12 files, 1 error"));
}

TEST_CASE("vcu check refuses a telemetry.json naming a signal the catalog lacks, and one its loader refuses (#25)") {
  const std::string unknown =
      hheaCopy("check_telemetry", "telemetry.json",
               R"({"broker": "mqtt://127.0.0.1", "vehicleId": "v1", "signals": [{"name": "BMS.Nope"}]})");
  const RunResult unknownResult = runVcu({"check", "--config", unknown});
  CHECK(unknownResult.exitCode == EXIT_INPUT_ERROR);
  CHECK_MESSAGE(
      contains(unknownResult.err, "check_telemetry/telemetry.json: error: /signals: unknown signal 'BMS.Nope'"),
      unknownResult.err);
  CHECK(contains(unknownResult.out, "telemetry.json: 1 error"));

  const std::string refused =
      hheaCopy("check_telemetry_bad", "telemetry.json", R"({"broker": "http://x", "vehicleId": "v1"})");
  const RunResult refusedResult = runVcu({"check", "--config", refused});
  CHECK(refusedResult.exitCode == EXIT_INPUT_ERROR);
  CHECK_MESSAGE(contains(refusedResult.err, "check_telemetry_bad/telemetry.json: /broker: error: "), refusedResult.err);
  CHECK(contains(refusedResult.out, "12 files, 1 error"));
}

TEST_CASE("vcu check still checks the other files when vehicle.json itself has an error") {
  const std::string vehicle = hheaCopy("check_vehicle_error");
  std::string text;
  {
    std::ifstream in(vehicle);
    text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  text.replace(text.find("\"Vehicle_Control_Unit\""), 22, "\"Vehicle_Control_Unix\"");
  writeScratchFile("check_vehicle_error/vehicle.json", text);
  writeScratchFile("check_vehicle_error/simulation.json", "{");
  const RunResult result = runVcu({"check", "--config", vehicle});
  CHECK(result.exitCode == EXIT_INPUT_ERROR);
  CHECK(contains(result.err, "vehicle.json: /node: error: node 'Vehicle_Control_Unix'"));
  CHECK(contains(result.err, "check_vehicle_error/simulation.json:1:"));
}

TEST_CASE("vcu check without any configuration or running stack is a usage error") {
  ScopedEnvironment root("OPENVCU_RUN_DIR", (scratchFolder() / "no_stacks").string());
  ::unsetenv("OPENVCU_CONFIG");
  const RunResult result = runVcu({"check"});
  CHECK(result.exitCode == EXIT_USAGE);
  CHECK(contains(result.err, "no configuration: give --config FILE or set OPENVCU_CONFIG (no running stack found in"));
}

TEST_CASE("vcu fsm check writes diagnostics to stderr and blames a broken schedule, not fsm.json (#19)") {
  const std::string vehicle = hheaCopy("fsm_schedule_broken", "schedule.json", "{ \"broken");
  const std::string fsm = (fs::path(vehicle).parent_path() / "fsm.json").string();
  const RunResult result = runVcu({"fsm", "check", fsm, "--config", vehicle});
  CHECK(result.exitCode == EXIT_INPUT_ERROR);
  CHECK(contains(result.err, "fsm_schedule_broken/schedule.json:1:"));
  CHECK_FALSE(contains(result.err, "unknown send group"));
  CHECK(contains(result.err, "fsm.json: note: 2 send-group actions not checked"));
  CHECK_FALSE(contains(result.out, "error:"));
  CHECK(contains(result.out, "fsm.json: 1 error, 0 warnings"));
}

TEST_CASE("vcu finds the configuration of the one running stack through its command socket (#19)") {
  const fs::path root = scratchFolder() / "run_one";
  fs::remove_all(root);
  ScopedEnvironment rootVariable("OPENVCU_RUN_DIR", root.string());
  ::unsetenv("OPENVCU_CONFIG");
  const std::string vehicle = (HHEA_FOLDER / "vehicle.json").string();
  // a relative --config resolves against the service's working folder
  const FakeService service(root, "hhea2", {"--config", "vehicle.json"}, HHEA_FOLDER);

  std::vector<std::string> problems;
  const auto stacks = openvcu::cli::findRunningStacks(&problems);
  REQUIRE_MESSAGE(stacks.size() == 1, (problems.empty() ? std::string() : problems.front()));
  CHECK(stacks[0].instance == "hhea2");
  CHECK(stacks[0].configPath == vehicle);
  CHECK(contains(stacks[0].foundBy, "vcu-fake (pid "));

  const RunResult check = runVcu({"check"});
  CHECK_MESSAGE(check.exitCode == EXIT_OK, check.err);
  CHECK(contains(check.out, vehicle + ": 0 errors"));
}

TEST_CASE("vcu refuses to guess between two running stacks and ignores a socket nobody serves") {
  const fs::path root = scratchFolder() / "run_two";
  fs::remove_all(root);
  ScopedEnvironment rootVariable("OPENVCU_RUN_DIR", root.string());
  ::unsetenv("OPENVCU_CONFIG");
  const std::string vehicle = (HHEA_FOLDER / "vehicle.json").string();
  {
    const FakeService crashed(root, "crashed", {"--config=" + vehicle});
  }  // killed: its socket file stays, nobody answers
  REQUIRE(fs::exists(root / "crashed" / "vcu-fake.sock"));
  CHECK(openvcu::cli::findRunningStacks(nullptr).empty());

  const FakeService first(root, "first", {"--config", vehicle});
  const FakeService second(root, "second", {"-c", vehicle});
  const RunResult result = runVcu({"check"});
  CHECK(result.exitCode == EXIT_USAGE);
  CHECK(contains(result.err, "2 stacks are running (first: " + vehicle + ", second: " + vehicle + ")"));
}
