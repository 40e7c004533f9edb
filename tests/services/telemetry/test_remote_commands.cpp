// vcu-telemetry's remote commands (issue 25, docs/design/telemetry.md "Remote commands").
// The handler (services/telemetry/src/remote_commands.*) on the HHEA catalog with a recording
// send function: what passes goes out once with the remote issuer and a bounded deadline, each
// refusal is answered without sending, a repeated cmdId is refused as a replay without a second
// send (also by a handler created again on the same folder).
// Then, inside tests/harness/run_isolated.sh (loopback only), a real mosquitto with test
// passwords and the ACL shipped in services/telemetry/examples/acl, the real vcu-fsm on a copy
// of the HHEA configuration (the authority) and the real vcu-telemetry with remote commands on
// for internal.operator.StartStop, commanded by an MQTT v5 client:
//   - forged commands (another vehicle's account, the vehicle's own account, a read-only watcher)
//     get PUBACK 0x87 "not authorized" from the broker and never reach the FSM (its table is
//     unchanged; an unknown user is not even let in);
//   - an accepted command reaches vcu-fsm (the state leaves Standby) and its answer is published;
//   - a repeated cmdId is refused as a replay and not sent again, also after 66 other commands
//     and after vcu-telemetry was SIGKILLed and restarted on its queue folder;
//   - a payload with a key given twice (at any level) is refused with the key and its path;
//   - an unlisted key, an unknown kind, a past deadline and a retained command are refused by
//     vcu-telemetry, an out-of-range value by vcu-fsm, each with an answer.
#include <doctest/doctest.h>
#include <signal.h>
#include <stdlib.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <future>
#include <mutex>
#include <optional>
#include <thread>
#include <utility>

#include "broker_fixture.hpp"
#include "openvcu/config/catalog.hpp"
#include "openvcu/config/vehicle.hpp"
#include "openvcu/core/clock.hpp"
#include "openvcu/signals/table.hpp"
#include "remote_commands.hpp"
#include "skip.hpp"

namespace {

using namespace openvcu;
using namespace std::chrono_literals;
using telemetry_test::Message;
using telemetry_test::MqttClient;
using telemetry_test::REASON_NOT_AUTHORIZED;
using telemetry_test::writeFile;
using Json = nlohmann::json;
namespace fs = std::filesystem;

constexpr const char* VEHICLE = "hhea-01";
constexpr const char* START_STOP = "internal.operator.StartStop";
constexpr const char* CRASH = "internal.operator.Crash";
constexpr std::int64_t NOW_UNIX_MS = 1'764'259'200'000;
constexpr std::int64_t NOW_MONO_NS = 5'000'000'000;
constexpr telemetry::ClockPair NOW{.monoNs = NOW_MONO_NS, .unixMs = NOW_UNIX_MS};

/// The HHEA vehicle as the service loads it.
struct Hhea {
  config::VehicleConfig vehicle;
  signals::Catalog catalog;
  static Hhea load() {
    auto vehicle = config::loadVehicleConfig(OPENVCU_SOURCE_DIR "/config/hhea/vehicle.json");
    REQUIRE_STATUS(vehicle);
    auto catalog = config::buildCatalog(*vehicle);
    REQUIRE_STATUS(catalog);
    return Hhea{std::move(*vehicle), std::move(*catalog)};
  }
};

std::string command(const std::string& kind, const std::string& key, const Json& value, std::int64_t deadlineUnixMs) {
  Json body = {{"kind", kind}, {"key", key}, {"deadlineUnixMs", deadlineUnixMs}};
  if (!value.is_null()) body["value"] = value;
  return body.dump();
}

/// A fresh folder under the temporary directory, removed at the end of the case.
struct TempFolder {
  std::string path;
  TempFolder() {
    std::string pattern = (fs::temp_directory_path() / "openvcu-commands-XXXXXX").string();
    REQUIRE(::mkdtemp(pattern.data()) != nullptr);
    path = pattern;
  }
  ~TempFolder() { fs::remove_all(path); }
  TempFolder(const TempFolder&) = delete;
  TempFolder& operator=(const TempFolder&) = delete;
};

/// The handler with a send function that records each request and answers as `answer` says.
struct Recorded {
  TempFolder folder;  ///< its memory of received cmdIds
  std::mutex mutex;
  std::vector<std::pair<ipc::CommandRequest, std::chrono::nanoseconds>> sent;
  std::unique_ptr<telemetry::RemoteCommands> sut;
  std::vector<std::string> warnings;
  std::shared_future<void> gate;  ///< when valid, each send waits for it (an owner that is slow to answer)

  /// `stateFolder`: the memory of received cmdIds there instead of in `folder`.
  Recorded(const Hhea& hhea, std::vector<std::string> keys, commands::CommandOutcome answer,
           std::shared_future<void> sendGate = {}, const std::string& stateFolder = {})
      : gate(std::move(sendGate)) {
    auto created = telemetry::RemoteCommands::create(
        {.vehicleId = VEHICLE,
         .keys = std::move(keys),
         .stateFolder = stateFolder.empty() ? folder.path : stateFolder,
         .catalog = &hhea.catalog,
         .database = &hhea.vehicle.database,
         .send =
             [this, answer](const ipc::CommandRequest& request, std::chrono::nanoseconds timeout) {
               {
                 const std::lock_guard lock(mutex);
                 sent.emplace_back(request, timeout);
               }
               if (gate.valid()) gate.wait();
               return answer;
             },
         .logInfo = {},
         .logWarning = [this](const std::string& text) { warnings.push_back(text); }});
    REQUIRE_STATUS(created);
    sut = std::move(*created);
  }
  /// The answers once nothing is with the worker (or after 5 s), parsed.
  std::vector<Json> answers() {
    std::vector<Json> out;
    const auto end = std::chrono::steady_clock::now() + 5s;
    for (;;) {
      for (const std::string& record : sut->takeRecords(100 + out.size(), NOW)) {
        const std::size_t newline = record.find('\n');
        REQUIRE(newline != std::string::npos);
        Json body = Json::parse(record.substr(newline + 1));
        CHECK(record.substr(0, newline) == "cmd/" + body["cmdId"].get<std::string>() + "/answer");
        out.push_back(std::move(body));
      }
      if (sut->inFlight() == 0 || std::chrono::steady_clock::now() > end) return out;
      std::this_thread::sleep_for(1ms);  // the worker hands the outcome back by itself
    }
  }
  std::size_t sentCount() {
    const std::lock_guard lock(mutex);
    return sent.size();
  }
};

commands::CommandOutcome acceptedBy(const std::string& responder) {
  commands::CommandOutcome outcome;
  outcome.kind = commands::CommandOutcome::Kind::Answered;
  outcome.ack.accepted = true;
  outcome.ack.responder = responder;
  return outcome;
}

/// A copy of config/hhea in work/vehicle with remote commands on for StartStop, its queue in
/// work/queue, logging in to 127.0.0.1:`port` as the vehicle; the path of its vehicle.json.
std::string writeVehicle(const fs::path& work, int port) {
  fs::create_directories(work / "vehicle");
  for (const auto& entry : fs::directory_iterator(fs::path(OPENVCU_SOURCE_DIR) / "config/hhea")) {
    if (entry.is_regular_file()) fs::copy_file(entry.path(), work / "vehicle" / entry.path().filename());
  }
  writeFile(work / "vehicle/vehicle-password", "vehicle-secret\n");
  writeFile(work / "vehicle/telemetry.json", Json{{"broker", "mqtt://127.0.0.1:" + std::to_string(port)},
                                                  {"vehicleId", VEHICLE},
                                                  {"username", VEHICLE},
                                                  {"passwordFile", "vehicle-password"},
                                                  {"queueFolder", (work / "queue").string()},
                                                  {"maxQueueMB", 1},
                                                  {"remoteCommands", {{"enabled", true}, {"keys", {START_STOP}}}}}
                                                 .dump(2));
  return (work / "vehicle/vehicle.json").string();
}

/// Connects `client` to the test broker on 127.0.0.1:`port`, retried for 5 s (mosquitto sends no
/// readiness), and subscribes it to everything of the vehicle.
void connectAndSubscribe(MqttClient& client, int port) {
  int connack = telemetry_test::NO_ANSWER;
  for (int attempt = 0; attempt < 50 && (connack = client.connect(port)) == telemetry_test::NO_ANSWER; ++attempt) {
    std::this_thread::sleep_for(100ms);
  }
  REQUIRE(connack == 0);
  REQUIRE(client.subscribe(std::string("openvcu/") + VEHICLE + "/#") == 1);
}

telemetry::InboundMessage onTopic(const std::string& cmdId, std::string payload, bool retained = false) {
  return {.topic = std::string("openvcu/") + VEHICLE + "/cmd/" + cmdId,
          .payload = std::move(payload),
          .retained = retained};
}

}  // namespace

TEST_CASE(
    "a remote command that passes the checks goes out once with the remote issuer and a deadline at most 2 s ahead") {
  const Hhea hhea = Hhea::load();
  Recorded recorded(hhea, {START_STOP}, acceptedBy("vcu-fsm"));

  recorded.sut->onMessage(onTopic("c-1", command("operator", START_STOP, "Start", NOW_UNIX_MS + 5000)), NOW);
  const auto first = recorded.answers();
  recorded.sut->onMessage(onTopic("c-1", command("operator", START_STOP, "Start", NOW_UNIX_MS + 5000)), NOW);
  const auto repeated = recorded.answers();

  REQUIRE(recorded.sentCount() == 1);
  const auto& [request, timeout] = recorded.sent[0];
  CHECK(request.kind == ipc::CommandKind::OperatorSwitch);
  CHECK(request.key == START_STOP);
  CHECK(request.value == 1);
  CHECK(request.issuer == "vcu-telemetry/mqtt");
  CHECK(request.deadlineNs == NOW_MONO_NS + telemetry::MAX_REQUEST_WAIT_MS * 1'000'000);
  CHECK(timeout == std::chrono::milliseconds(telemetry::MAX_REQUEST_WAIT_MS));
  REQUIRE(first.size() == 1);
  CHECK(first[0]["v"] == 1);
  CHECK(first[0]["seq"] == 100);
  CHECK(first[0]["t"] == NOW_UNIX_MS);
  CHECK(first[0]["cmdId"] == "c-1");
  CHECK(first[0]["accepted"] == true);
  CHECK(first[0]["responder"] == "vcu-fsm");
  REQUIRE(repeated.size() == 1);  // refused as a replay, not sent a second time
  CHECK(repeated[0]["accepted"] == false);
  CHECK(repeated[0]["responder"] == "vcu-telemetry");
  CHECK(repeated[0]["reason"].get<std::string>().starts_with("replayed: cmdId 'c-1' was received before"));
}

TEST_CASE("a remote command received before is refused as replayed after 66 other commands and never sent twice") {
  const Hhea hhea = Hhea::load();
  Recorded recorded(hhea, {START_STOP}, acceptedBy("vcu-fsm"));
  constexpr int OTHERS = 66;  // more than any count-bounded memory of recent cmdIds kept
  const std::string start = command("operator", START_STOP, "Start", NOW_UNIX_MS + 9000);

  recorded.sut->onMessage(onTopic("first", start), NOW);
  const auto first = recorded.answers();
  for (int i = 0; i < OTHERS; ++i) {
    recorded.sut->onMessage(
        onTopic("other-" + std::to_string(i), command("operator", START_STOP, "Stop", NOW_UNIX_MS + 9000)), NOW);
    (void)recorded.answers();
  }
  recorded.sut->onMessage(onTopic("first", start), NOW);
  const auto replayed = recorded.answers();

  CHECK(recorded.sentCount() == 1 + OTHERS);
  REQUIRE(first.size() == 1);
  CHECK(first[0]["accepted"] == true);
  REQUIRE(replayed.size() == 1);
  CHECK(replayed[0]["cmdId"] == "first");
  CHECK(replayed[0]["accepted"] == false);
  CHECK(replayed[0]["responder"] == "vcu-telemetry");
  CHECK_MESSAGE(replayed[0]["reason"].get<std::string>().starts_with("replayed"), replayed[0].dump());
}

TEST_CASE("a remote command received before is refused as replayed by a handler created again on the same folder") {
  const Hhea hhea = Hhea::load();
  TempFolder shared;
  const std::string start = command("operator", START_STOP, "Start", NOW_UNIX_MS + 9000);
  {
    Recorded before(hhea, {START_STOP}, acceptedBy("vcu-fsm"), {}, shared.path);
    before.sut->onMessage(onTopic("first", start), NOW);
    REQUIRE(before.answers().size() == 1);
    REQUIRE(before.sentCount() == 1);
  }
  Recorded recorded(hhea, {START_STOP}, acceptedBy("vcu-fsm"), {}, shared.path);
  constexpr telemetry::ClockPair LATER{.monoNs = NOW_MONO_NS + 1'000'000'000, .unixMs = NOW_UNIX_MS + 1000};

  recorded.sut->onMessage(onTopic("first", start), LATER);
  const auto answers = recorded.answers();

  CHECK(recorded.sentCount() == 0);
  REQUIRE(answers.size() == 1);
  CHECK(answers[0]["accepted"] == false);
  CHECK(answers[0]["reason"].get<std::string>().starts_with("replayed: cmdId 'first' was received before"));
}

TEST_CASE("a remote command with a key given twice at any level is refused with the key and its path") {
  const Hhea hhea = Hhea::load();
  Recorded recorded(hhea, {START_STOP}, acceptedBy("vcu-fsm"));
  const std::string deadline = std::to_string(NOW_UNIX_MS + 5000);
  const std::string past = std::to_string(NOW_UNIX_MS - 60'000);
  struct Case {
    const char* cmdId;
    std::string payload;
    const char* reason;
  };
  const std::vector<Case> cases{
      {"two-values",
       R"({"kind":"operator","key":"internal.operator.StartStop","value":"Stop","value":"Start","deadlineUnixMs":)" +
           deadline + "}",
       R"(/: key "value" given twice (first at 1:)"},
      {"two-deadlines",
       R"({"kind":"operator","key":"internal.operator.StartStop","value":"Start","deadlineUnixMs":)" + past +
           R"(,"deadlineUnixMs":)" + deadline + "}",
       R"(/: key "deadlineUnixMs" given twice)"},
      {"escaped-twin",
       R"({"kind":"operator","key":"internal.operator.StartStop","value":"Stop","value":"Start","deadlineUnixMs":)" +
           deadline + "}",
       R"(/: key "value" given twice)"},
      {"nested",
       R"({"kind":"operator","key":"internal.operator.StartStop","value":"Start","deadlineUnixMs":)" + deadline +
           R"(,"by":{"name":"a","name":"b"}})",
       R"(/by: key "name" given twice)"},
  };
  for (const Case& entry : cases) recorded.sut->onMessage(onTopic(entry.cmdId, entry.payload), NOW);

  const auto answers = recorded.answers();
  CHECK(recorded.sentCount() == 0);
  REQUIRE(answers.size() == cases.size());
  for (std::size_t i = 0; i < cases.size(); ++i) {
    CAPTURE(cases[i].cmdId);
    CHECK(answers[i]["cmdId"] == cases[i].cmdId);
    CHECK(answers[i]["accepted"] == false);
    CHECK(answers[i]["responder"] == "vcu-telemetry");
    CHECK_MESSAGE(answers[i]["reason"].get<std::string>().starts_with(cases[i].reason), answers[i].dump());
  }
}

TEST_CASE("a remote command due sooner than 2 s carries its own deadline") {
  const Hhea hhea = Hhea::load();
  Recorded recorded(hhea, {START_STOP}, acceptedBy("vcu-fsm"));
  constexpr std::int64_t SOON_MS = 300;

  recorded.sut->onMessage(onTopic("soon", command("operator", START_STOP, "Stop", NOW_UNIX_MS + SOON_MS)), NOW);
  (void)recorded.answers();

  REQUIRE(recorded.sentCount() == 1);
  CHECK(recorded.sent[0].first.deadlineNs == NOW_MONO_NS + SOON_MS * 1'000'000);
  CHECK(recorded.sent[0].first.value == 0);
}

TEST_CASE("remote commands refused by vcu-telemetry are answered with the reason and never sent") {
  const Hhea hhea = Hhea::load();
  Recorded recorded(hhea, {START_STOP, "internal.operator.FaultReset"}, acceptedBy("vcu-fsm"));
  struct Case {
    const char* cmdId;
    std::string payload;
    bool retained;
    const char* reason;
  };
  const std::vector<Case> cases{
      {"retained", command("operator", START_STOP, "Start", NOW_UNIX_MS + 5000), true, "retained"},
      {"past", command("operator", START_STOP, "Start", NOW_UNIX_MS - 1), false, "in the past"},
      {"far", command("operator", START_STOP, "Start", NOW_UNIX_MS + telemetry::MAX_DEADLINE_AHEAD_MS + 1), false,
       "at most 10000"},
      {"no-deadline", R"({"kind":"operator","key":"internal.operator.StartStop","value":"Start"})", false,
       "/deadlineUnixMs: missing"},
      {"unlisted", command("operator", CRASH, 1, NOW_UNIX_MS + 5000), false,
       "not among telemetry.json's remoteCommands keys"},
      {"unknown-kind", command("bogus", START_STOP, 1, NOW_UNIX_MS + 5000), false, "/kind: unknown kind 'bogus'"},
      {"bad-value", command("operator", START_STOP, "Sideways", NOW_UNIX_MS + 5000), false,
       "'Sideways' is not a value"},
      {"not-json", "Start!", false, "/: not JSON"},
  };
  for (const Case& entry : cases) recorded.sut->onMessage(onTopic(entry.cmdId, entry.payload, entry.retained), NOW);
  // a cmdId that cannot name an answer topic is logged, not answered
  recorded.sut->onMessage(onTopic("bad+id", command("operator", START_STOP, "Start", NOW_UNIX_MS + 5000)), NOW);

  const auto answers = recorded.answers();
  CHECK(recorded.sentCount() == 0);
  REQUIRE(answers.size() == cases.size());
  for (std::size_t i = 0; i < cases.size(); ++i) {
    CAPTURE(cases[i].cmdId);
    CHECK(answers[i]["cmdId"] == cases[i].cmdId);
    CHECK(answers[i]["accepted"] == false);
    CHECK(answers[i]["responder"] == "vcu-telemetry");
    CHECK_MESSAGE(answers[i]["reason"].get<std::string>().find(cases[i].reason) != std::string::npos,
                  answers[i].dump());
  }
  CHECK(recorded.warnings.size() == cases.size() + 1);  // each refusal and the bad cmdId logged
}

TEST_CASE("remote commands beyond the worker's queue are refused busy while the owner is slow") {
  const Hhea hhea = Hhea::load();
  std::promise<void> release;
  Recorded recorded(hhea, {START_STOP}, acceptedBy("vcu-fsm"), release.get_future().share());
  struct ReleaseAtExit {  // a failed REQUIRE must not leave the worker waiting (its destructor joins it)
    std::promise<void>& promise;
    bool released{false};
    void now() {
      if (!std::exchange(released, true)) promise.set_value();
    }
    ~ReleaseAtExit() { now(); }
  } releaser{release};
  const std::string start = command("operator", START_STOP, "Start", NOW_UNIX_MS + 5000);

  recorded.sut->onMessage(onTopic("first", start), NOW);
  const auto end = std::chrono::steady_clock::now() + 5s;
  while (recorded.sentCount() == 0 && std::chrono::steady_clock::now() < end) std::this_thread::sleep_for(1ms);
  REQUIRE(recorded.sentCount() == 1);  // the worker is busy with it
  for (std::size_t i = 0; i < telemetry::MAX_WAITING_COMMANDS; ++i) {
    recorded.sut->onMessage(onTopic("waiting-" + std::to_string(i), start), NOW);
  }
  recorded.sut->onMessage(onTopic("one-too-many", start), NOW);
  const auto refused = recorded.sut->takeRecords(1, NOW);
  releaser.now();
  const auto answered = recorded.answers();

  REQUIRE(refused.size() == 1);
  CHECK(refused[0].find("\"cmdId\":\"one-too-many\"") != std::string::npos);
  CHECK(refused[0].find("busy") != std::string::npos);
  CHECK(answered.size() == 1 + telemetry::MAX_WAITING_COMMANDS);
  CHECK(recorded.sentCount() == 1 + telemetry::MAX_WAITING_COMMANDS);
}

TEST_CASE("a remote command key that is neither a signal nor a DBC message stops the start") {
  const Hhea hhea = Hhea::load();
  auto created = telemetry::RemoteCommands::create(
      {.vehicleId = VEHICLE,
       .keys = {START_STOP, "internal.operator.Strat"},
       .stateFolder = fs::temp_directory_path().string(),
       .catalog = &hhea.catalog,
       .database = &hhea.vehicle.database,
       .send = [](const ipc::CommandRequest&, std::chrono::nanoseconds) { return commands::CommandOutcome{}; },
       .logInfo = {},
       .logWarning = {}});
  REQUIRE_FALSE(created);
  CHECK(created.error().message ==
        "/remoteCommands/keys/1: 'internal.operator.Strat' is neither a signal of this vehicle nor a DBC message");
}

TEST_CASE(
    "forged remote commands are refused by the broker and never reach vcu-fsm, checked ones reach it and are "
    "answered") {
  if (!harness::isolated()) OPENVCU_SKIP(harness::NOT_ISOLATED);
  if (!fs::exists("/usr/sbin/mosquitto") || !fs::exists("/usr/bin/mosquitto_passwd")) {
    OPENVCU_SKIP("skipped: needs mosquitto (Debian's mosquitto package; scripts/install-deps.sh)");
  }
  constexpr int PORT = 1883;
  const std::string bin = OPENVCU_BINARY_DIR "/bin";
  harness::Harness sut;
  const fs::path work = fs::temp_directory_path() / "telemetry-commands";  // the sandbox's own /tmp
  fs::remove_all(work);

  // the broker: test passwords made now, the ACL as shipped
  auto brokerSpec = telemetry_test::brokerSpec(sut, work / "broker",
                                               {{VEHICLE, "vehicle-secret"},
                                                {"hhea-02", "other-secret"},
                                                {"fleet-operator", "operator-secret"},
                                                {"fleet-watcher", "watcher-secret"}},
                                               fs::path(OPENVCU_SOURCE_DIR) / "services/telemetry/examples/acl", PORT);
  auto broker = sut.start(brokerSpec);
  REQUIRE_STATUS(broker);

  const std::string vehiclePath = writeVehicle(work, PORT);
  auto vehicle = config::loadVehicleConfig(vehiclePath);
  REQUIRE_STATUS(vehicle);
  auto catalog = config::buildCatalog(*vehicle);
  REQUIRE_STATUS(catalog);
  auto table = signals::SignalTable::open(*catalog, vehicle->instance);
  REQUIRE_STATUS(table);
  const signals::SignalIndex state = *catalog->indexOf("internal.fsm.state");
  const signals::SignalIndex startStop = *catalog->indexOf(START_STOP);
  const signals::SignalIndex crash = *catalog->indexOf(CRASH);

  auto fsm =
      sut.start({.name = "vcu-fsm", .argv = {bin + "/vcu-fsm", "--config", vehiclePath}, .notifyReadiness = true});
  REQUIRE_STATUS(fsm);
  auto bridge = sut.start(
      {.name = "vcu-telemetry", .argv = {bin + "/vcu-telemetry", "--config", vehiclePath}, .notifyReadiness = true});
  REQUIRE_STATUS(bridge);

  MqttClient fleetOperator("test-operator", "fleet-operator", "operator-secret");
  connectAndSubscribe(fleetOperator, PORT);
  // the birth of the connection that subscribed to cmd/+ (subscribed before the birth went out)
  const auto birth = fleetOperator.waitForTopic(std::string("openvcu/") + VEHICLE + "/birth", 10s);
  REQUIRE(birth);
  CHECK(birth->body["commands"]["enabled"] == true);
  const auto until = std::chrono::steady_clock::now() + 5s;  // vcu-fsm's initial state in the table
  while (table->readBus(state)->updates == 0 && std::chrono::steady_clock::now() < until) {
    (void)table->waitForChange(table->changeEpoch(), 100ms);
  }
  REQUIRE(table->readBus(state)->updates > 0);
  const double standby = table->readBus(state)->value;
  const std::string cmd = std::string("openvcu/") + VEHICLE + "/cmd/";
  const auto deadline = [] { return clock::realtimeNs() / 1'000'000 + 5000; };
  const auto answerOf = [&](const std::string& cmdId) {
    return fleetOperator.waitForTopic(cmd + cmdId + "/answer", 10s);
  };

  // forged: another vehicle's account, the vehicle's own account, a read-only watcher: the ACL refuses each
  const std::string start = command("operator", START_STOP, "Start", deadline());
  for (const auto& [user, password] : {std::pair{"hhea-02", "other-secret"}, std::pair{VEHICLE, "vehicle-secret"},
                                       std::pair{"fleet-watcher", "watcher-secret"}}) {
    CAPTURE(user);
    MqttClient forger(std::string("forger-") + user, user, password);
    REQUIRE(forger.connect(PORT) == 0);
    CHECK(forger.publish(cmd + "forged-" + user, start) == REASON_NOT_AUTHORIZED);
  }
  MqttClient stranger("stranger", "intruder", "guess");
  const int refusedConnect = stranger.connect(PORT);
  CHECK_MESSAGE((refusedConnect == 0x86 || refusedConnect == REASON_NOT_AUTHORIZED), "CONNACK " << refusedConnect);

  // accepted: through vcu-telemetry to vcu-fsm, the authority; published after the forged ones
  REQUIRE(fleetOperator.publish(cmd + "c1", start) == 0);
  const auto accepted = answerOf("c1");
  REQUIRE(accepted);
  CHECK(accepted->body["accepted"] == true);
  CHECK(accepted->body["responder"] == "vcu-fsm");
  CHECK(accepted->body.contains("seq"));
  CHECK_FALSE(accepted->retained);
  const auto commanded = table->readCommand(startStop);
  REQUIRE(commanded);
  CHECK(commanded->updates == 1);  // this command only: none of the forged ones reached the FSM
  CHECK(commanded->value == 1);
  for (const Message& message : fleetOperator.messages())
    CHECK_FALSE(message.topic.find("/cmd/forged-") != std::string::npos);
  const auto end = std::chrono::steady_clock::now() + 5s;
  while (table->readBus(state)->value == standby && std::chrono::steady_clock::now() < end) {
    (void)table->waitForChange(table->changeEpoch(), 100ms);
  }
  CHECK_MESSAGE(table->readBus(state)->value != standby, "vcu-fsm left Standby on the remote Start");

  // the same cmdId again: refused as a replay, nothing sent twice
  REQUIRE(fleetOperator.publish(cmd + "c1", start) == 0);
  REQUIRE(fleetOperator.waitFor(
      [&](const std::vector<Message>& messages) {
        return std::count_if(messages.begin(), messages.end(), [&](const Message& m) {
                 return m.topic == cmd + "c1/answer" && m.body["accepted"] == false &&
                        m.body["reason"].get<std::string>().starts_with("replayed");
               }) == 1;
      },
      10s));

  // refused with an answer: an unlisted key (by vcu-telemetry), an out-of-range value (by vcu-fsm), a retained command
  REQUIRE(fleetOperator.publish(cmd + "c2", command("operator", CRASH, "Crash test", deadline())) == 0);
  REQUIRE(fleetOperator.publish(cmd + "c3", command("operator", START_STOP, 7, deadline())) == 0);
  REQUIRE(fleetOperator.publish(cmd + "c4", command("operator", START_STOP, "Stop", deadline()), true) == 0);
  const auto unlisted = answerOf("c2");
  const auto outOfRange = answerOf("c3");
  const auto retained = answerOf("c4");
  REQUIRE(unlisted);
  CHECK(unlisted->body["accepted"] == false);
  CHECK(unlisted->body["responder"] == "vcu-telemetry");
  CHECK(unlisted->body["reason"].get<std::string>().find("not among") != std::string::npos);
  REQUIRE(outOfRange);
  CHECK(outOfRange->body["accepted"] == false);
  CHECK(outOfRange->body["responder"] == "vcu-fsm");
  MESSAGE("vcu-fsm's refusal: " << outOfRange->body["reason"]);
  REQUIRE(retained);
  CHECK(retained->body["accepted"] == false);
  CHECK(retained->body["reason"].get<std::string>().starts_with("retained"));
  CHECK(table->readCommand(startStop)->updates == 1);
  CHECK(table->readCommand(startStop)->value == 1);
  CHECK(table->readCommand(crash)->updates == 0);
  const std::string log = (*bridge)->output();
  for (const char* cmdId : {"c2", "c3", "c4"}) {
    CHECK_MESSAGE(log.find(std::string("remote command ") + cmdId) != std::string::npos, log);
  }
  CHECK_MESSAGE((*bridge)->running(), log);
  (void)fleetOperator.publish(cmd + "c4", "", true);  // the retained command removed from the broker
}

TEST_CASE(
    "a remote command published again within its deadline is refused after 66 other commands and after a restart "
    "of vcu-telemetry on its queue, and a duplicated key is refused, none of them reaching vcu-fsm") {
  if (!harness::isolated()) OPENVCU_SKIP(harness::NOT_ISOLATED);
  if (!fs::exists("/usr/sbin/mosquitto") || !fs::exists("/usr/bin/mosquitto_passwd")) {
    OPENVCU_SKIP("skipped: needs mosquitto (Debian's mosquitto package; scripts/install-deps.sh)");
  }
  constexpr int PORT = 1884;
  constexpr int OTHERS = 66;
  constexpr int BURST = 16;  // published before waiting for their answers (the sender keeps at most 64 waiting)
  constexpr std::int64_t AHEAD_MS = 9500;  // the deadline of a replayed command: just inside the 10 s allowed
  const std::string bin = OPENVCU_BINARY_DIR "/bin";
  harness::Harness sut;
  const fs::path work = fs::temp_directory_path() / "telemetry-replay";
  fs::remove_all(work);
  auto broker = sut.start(telemetry_test::brokerSpec(
      sut, work / "broker", {{VEHICLE, "vehicle-secret"}, {"fleet-operator", "operator-secret"}},
      fs::path(OPENVCU_SOURCE_DIR) / "services/telemetry/examples/acl", PORT));
  REQUIRE_STATUS(broker);
  const std::string vehiclePath = writeVehicle(work, PORT);
  auto vehicle = config::loadVehicleConfig(vehiclePath);
  REQUIRE_STATUS(vehicle);
  auto catalog = config::buildCatalog(*vehicle);
  REQUIRE_STATUS(catalog);
  auto table = signals::SignalTable::open(*catalog, vehicle->instance);
  REQUIRE_STATUS(table);
  const signals::SignalIndex startStop = *catalog->indexOf(START_STOP);
  const harness::ProcessSpec bridgeSpec{
      .name = "vcu-telemetry", .argv = {bin + "/vcu-telemetry", "--config", vehiclePath}, .notifyReadiness = true};
  auto fsm =
      sut.start({.name = "vcu-fsm", .argv = {bin + "/vcu-fsm", "--config", vehiclePath}, .notifyReadiness = true});
  REQUIRE_STATUS(fsm);
  auto bridge = sut.start(bridgeSpec);
  REQUIRE_STATUS(bridge);

  MqttClient fleetOperator("test-operator", "fleet-operator", "operator-secret");
  connectAndSubscribe(fleetOperator, PORT);
  const std::string root = std::string("openvcu/") + VEHICLE + "/";
  const auto birthsIn = [&](const std::vector<Message>& messages) {
    return std::count_if(messages.begin(), messages.end(), [&](const Message& m) { return m.topic == root + "birth"; });
  };
  REQUIRE(fleetOperator.waitFor([&](const std::vector<Message>& messages) { return birthsIn(messages) > 0; }, 10s));
  const auto answersOf = [&](const std::string& cmdId) {
    std::vector<Json> out;
    for (const Message& message : fleetOperator.messages()) {
      if (message.topic == root + "cmd/" + cmdId + "/answer") out.push_back(message.body);
    }
    return out;
  };
  /// Waits for an answer on cmdId that `matches`; the first such answer.
  const auto waitForAnswer = [&](const std::string& cmdId, auto matches) -> std::optional<Json> {
    std::optional<Json> found;
    fleetOperator.waitFor(
        [&](const std::vector<Message>& messages) {
          for (const Message& message : messages) {
            if (message.topic == root + "cmd/" + cmdId + "/answer" && matches(message.body)) {
              found = message.body;
              return true;
            }
          }
          return false;
        },
        10s);
    return found;
  };
  const auto any = [](const Json&) { return true; };
  const auto refusedHere = [](const Json& body) {
    return body["accepted"] == false && body["responder"] == "vcu-telemetry";
  };
  const auto aheadMs = [](std::int64_t ms) { return clock::realtimeNs() / 1'000'000 + ms; };

  // accepted once, then 66 other commands, then the same message again
  const std::string start = command("operator", START_STOP, "Start", aheadMs(AHEAD_MS));
  REQUIRE(fleetOperator.publish(root + "cmd/first", start) == 0);
  const auto firstAnswer = waitForAnswer("first", any);
  REQUIRE(firstAnswer);
  CHECK((*firstAnswer)["accepted"] == true);
  REQUIRE(table->readCommand(startStop)->updates == 1);
  for (int i = 0; i < OTHERS; i += BURST) {
    const int end = std::min(OTHERS, i + BURST);
    for (int j = i; j < end; ++j) {
      REQUIRE(fleetOperator.publish(root + "cmd/other-" + std::to_string(j),
                                    command("operator", CRASH, 1, aheadMs(AHEAD_MS))) == 0);
    }
    REQUIRE(waitForAnswer("other-" + std::to_string(end - 1), any));
  }
  REQUIRE(fleetOperator.publish(root + "cmd/first", start) == 0);
  const auto replayed = waitForAnswer("first", refusedHere);
  CHECK_MESSAGE((replayed && (*replayed)["reason"].get<std::string>().starts_with("replayed")),
                "answers on cmd/first: " << Json(answersOf("first")).dump());

  // accepted once, vcu-telemetry SIGKILLed and started again on the same queue folder, the same message again
  const std::string stop = command("operator", START_STOP, "Stop", aheadMs(AHEAD_MS));
  REQUIRE(fleetOperator.publish(root + "cmd/before-restart", stop) == 0);
  const auto beforeRestart = waitForAnswer("before-restart", any);
  REQUIRE(beforeRestart);
  CHECK((*beforeRestart)["responder"] == "vcu-fsm");
  const std::uint64_t updatesBeforeRestart = table->readCommand(startStop)->updates;
  const auto birthsBefore = birthsIn(fleetOperator.messages());
  REQUIRE((*bridge)->signal(SIGKILL));
  REQUIRE((*bridge)->waitForExit(5s));
  auto restarted = sut.start(bridgeSpec);
  REQUIRE_STATUS(restarted);
  REQUIRE(fleetOperator.waitFor([&](const std::vector<Message>& messages) { return birthsIn(messages) > birthsBefore; },
                                10s));
  REQUIRE(fleetOperator.publish(root + "cmd/before-restart", stop) == 0);
  const auto afterRestart = waitForAnswer("before-restart", refusedHere);
  CHECK_MESSAGE((afterRestart && (*afterRestart)["reason"].get<std::string>().starts_with("replayed")),
                "answers on cmd/before-restart: " << Json(answersOf("before-restart")).dump());

  // a duplicated key: nlohmann alone would keep the last ("Start")
  REQUIRE(
      fleetOperator.publish(
          root + "cmd/two-values",
          R"({"kind":"operator","key":"internal.operator.StartStop","value":"Stop","value":"Start","deadlineUnixMs":)" +
              std::to_string(aheadMs(AHEAD_MS)) + "}") == 0);
  const auto twoValues = waitForAnswer("two-values", any);
  REQUIRE(twoValues);
  CHECK_MESSAGE(((*twoValues)["accepted"] == false &&
                 (*twoValues)["reason"].get<std::string>().starts_with(R"(/: key "value" given twice)")),
                twoValues->dump());

  // none of the refused ones reached vcu-fsm
  CHECK(table->readCommand(startStop)->updates == updatesBeforeRestart);
  CHECK_MESSAGE((*restarted)->running(), (*restarted)->output());
}
