// cantx::ScheduleCommands on the HHEA configuration: each schedule command is checked,
// saved to the overlay file and only then posted to the transmit thread (a recorder here);
// a refused command changes nothing (issue 20).

#include <doctest/doctest.h>

#include "vehicle_fixture.hpp"
#include <unistd.h>

#include <filesystem>
#include <limits>
#include <string>
#include <variant>
#include <vector>

#include "openvcu/config/catalog.hpp"
#include "schedule_commands.hpp"

using namespace openvcu;

namespace {

constexpr std::int64_t MS = 1'000'000;
constexpr std::int64_t START = 5'000 * MS;
const std::string HHEA = std::string(OPENVCU_SOURCE_DIR) + "/config/hhea/vehicle.json";
const std::string CMD_SYS_1 = "CMD_SYS_1";  // 10 ms, no group
const std::string TORQUE = "Vehicle_Control_Unit.HC1_Demands.Torque_Request";
const std::string HC1_COUNTER = "Vehicle_Control_Unit.HC1_Demands.SEQ_Command1";  // computed: counter
const std::string ADDABLE = "HVESSD2_PGN61585";  // in the DBC, not in the schedule

struct NoPort final : cantx::TxPort {
  can::SendStatus send(std::size_t, const can::Frame&) noexcept override { return can::SendStatus::Sent; }
};
struct NoClock final : cantx::Clock {
  std::int64_t monotonicNs() noexcept override { return START; }
  std::int64_t realtimeNs() noexcept override { return 0; }
};

/// The transmit thread and the heartbeat, recorded.
struct Recorder final : cantx::ScheduleChangeSink {
  std::vector<cantx::TxCommand> posted;
  std::vector<std::pair<std::size_t, const cantx::MessageStats*>> joined;
  bool full{false};
  bool post(cantx::TxCommand&& command) noexcept override {
    if (full) return false;
    posted.push_back(std::move(command));
    return true;
  }
  void added(std::size_t scheduled, const cantx::MessageStats& stats) override {
    joined.emplace_back(scheduled, &stats);
  }
};

struct Fixture : openvcu::testing::VehicleTable {
  cantx::Schedule schedule;
  cantx::Overlay overlay;
  NoPort port;
  NoClock clock;
  Recorder sink;
  std::unique_ptr<cantx::Scheduler> scheduler;
  std::optional<cantx::ScheduleCommands> sut;
  std::filesystem::path directory = std::filesystem::temp_directory_path() / instance;

  Fixture() : VehicleTable(HHEA, "txcmd-" + std::to_string(::getpid())) {
    auto scheduleResult = cantx::loadSchedule(vehicle, catalog);
    REQUIRE_MESSAGE(scheduleResult, (scheduleResult ? "" : scheduleResult.error().toString()));
    schedule = std::move(*scheduleResult);
    std::filesystem::create_directories(directory);
    schedule.overlay = (directory / "overlay.json").string();
    auto created = cantx::Scheduler::create(vehicle, schedule, catalog, *table, port, clock, START);
    REQUIRE_MESSAGE(created, (created ? "" : created.error().toString()));
    scheduler = std::move(*created);
    sut.emplace(vehicle, catalog, schedule, overlay, *scheduler, sink);
  }
  ~Fixture() {
    std::error_code ignored;
    std::filesystem::remove_all(directory, ignored);
  }

  static ipc::CommandRequest request(ipc::CommandKind kind, const std::string& key, double value) {
    ipc::CommandRequest command;
    command.kind = kind;
    command.key = key;
    command.value = value;
    return command;
  }
  std::size_t scheduledIndex(const std::string& message) {
    auto found = cantx::findScheduled(schedule, vehicle, message);
    REQUIRE(found);
    return *found;
  }
  cantx::Overlay saved() {
    auto loaded = cantx::loadOverlay(schedule.overlay);
    REQUIRE_MESSAGE(loaded, (loaded ? "" : loaded.error().toString()));
    return *loaded;
  }
};

}  // namespace

TEST_CASE("a cycle change is saved to the overlay, posted to the transmit thread and kept in the schedule") {
  Fixture f;
  const std::size_t sys1 = f.scheduledIndex(CMD_SYS_1);

  const auto refusal = f.sut->apply(Fixture::request(ipc::CommandKind::ScheduleCycle, CMD_SYS_1, 20));

  REQUIRE_FALSE(refusal);
  REQUIRE(f.sink.posted.size() == 1);
  const auto* posted = std::get_if<cantx::SetCycle>(&f.sink.posted[0]);
  REQUIRE(posted != nullptr);
  CHECK(posted->scheduled == sys1);
  CHECK(posted->cycleNs == 20 * MS);
  CHECK(f.schedule.messages[sys1].cycleNs == 20 * MS);
  const cantx::Overlay saved = f.saved();
  REQUIRE(saved.messages.size() == 1);
  CHECK(saved.messages[0].message == CMD_SYS_1);
  CHECK(saved.messages[0].cycleMs == 20.0);
}

TEST_CASE("a cycle that is not a whole number of ms or not finite is refused and nothing changes") {
  Fixture f;
  const std::size_t sys1 = f.scheduledIndex(CMD_SYS_1);

  const auto fraction = f.sut->apply(Fixture::request(ipc::CommandKind::ScheduleCycle, CMD_SYS_1, 0.5));
  const auto infinite =
      f.sut->apply(Fixture::request(ipc::CommandKind::ScheduleCycle, CMD_SYS_1, std::numeric_limits<double>::infinity()));

  REQUIRE(fraction);
  CHECK(fraction->find("whole number") != std::string::npos);
  REQUIRE(infinite);
  CHECK(*infinite == "the value must be a finite number");
  CHECK(f.sink.posted.empty());
  CHECK(f.schedule.messages[sys1].cycleNs == 10 * MS);
  CHECK_FALSE(std::filesystem::exists(f.schedule.overlay));
}

TEST_CASE("a cycle that overloads the bus is refused") {
  Fixture f;
  // every scheduled message at 1 ms would far exceed half the bus; one alone does not,
  // so shorten them one by one until the limit answers
  std::optional<std::string> refusal;
  for (std::size_t s = 0; s < f.schedule.messages.size() && !refusal; ++s) {
    if (f.schedule.messages[s].cycleNs <= 0 || f.schedule.messages[s].safetyDeltaNs) continue;
    const std::string name = f.vehicle.database.messages[f.schedule.messages[s].message].name;
    refusal = f.sut->apply(Fixture::request(ipc::CommandKind::ScheduleCycle, name, 1));
  }
  REQUIRE(refusal);
  CHECK(refusal->find("%") != std::string::npos);
}

TEST_CASE("enable takes 1 or 0 only, and disabling is posted and saved") {
  Fixture f;
  const std::size_t sys1 = f.scheduledIndex(CMD_SYS_1);

  const auto wrong = f.sut->apply(Fixture::request(ipc::CommandKind::ScheduleEnable, CMD_SYS_1, 2));
  const auto disabled = f.sut->apply(Fixture::request(ipc::CommandKind::ScheduleEnable, CMD_SYS_1, 0));

  REQUIRE(wrong);
  CHECK(*wrong == "the value is 1 (enable) or 0 (disable)");
  REQUIRE_FALSE(disabled);
  REQUIRE(f.sink.posted.size() == 1);
  const auto* posted = std::get_if<cantx::SetEnabled>(&f.sink.posted[0]);
  REQUIRE(posted != nullptr);
  CHECK(posted->scheduled == sys1);
  CHECK_FALSE(posted->enabled);
  CHECK_FALSE(f.schedule.messages[sys1].enabled);
  CHECK(f.saved().messages.at(0).enabled == false);
}

TEST_CASE("a default is refused on a computed field and outside the signal's range, else posted") {
  Fixture f;

  const auto computed = f.sut->apply(Fixture::request(ipc::CommandKind::ScheduleDefault, HC1_COUNTER, 3));
  const auto outside = f.sut->apply(Fixture::request(ipc::CommandKind::ScheduleDefault, TORQUE, 1e12));
  const auto accepted = f.sut->apply(Fixture::request(ipc::CommandKind::ScheduleDefault, TORQUE, 12));

  REQUIRE(computed);
  CHECK(*computed == "'" + HC1_COUNTER + "' is computed (counter) for every frame");
  REQUIRE(outside);
  CHECK(outside->find("is outside the range") != std::string::npos);
  REQUIRE_FALSE(accepted);
  REQUIRE(f.sink.posted.size() == 1);
  const auto* posted = std::get_if<cantx::SetDefault>(&f.sink.posted[0]);
  REQUIRE(posted != nullptr);
  CHECK(posted->value == 12.0);
  CHECK(f.schedule.messages[posted->scheduled].defaults[posted->signal] == 12.0);
  const cantx::Overlay saved = f.saved();
  REQUIRE(saved.defaults.size() == 1);
  CHECK(saved.defaults[0] == std::pair<std::string, double>{TORQUE, 12.0});
}

TEST_CASE("a full transmit inbox refuses the command and puts the previous overlay back") {
  Fixture f;
  REQUIRE_FALSE(f.sut->apply(Fixture::request(ipc::CommandKind::ScheduleCycle, CMD_SYS_1, 20)));
  f.sink.full = true;
  const std::size_t sys1 = f.scheduledIndex(CMD_SYS_1);

  const auto refusal = f.sut->apply(Fixture::request(ipc::CommandKind::ScheduleCycle, CMD_SYS_1, 50));

  REQUIRE(refusal);
  CHECK(*refusal == "the transmit thread's inbox is full; try again");
  CHECK(f.schedule.messages[sys1].cycleNs == 20 * MS);
  CHECK(f.saved().messages.at(0).cycleMs == 20.0);
  CHECK(f.overlay.messages.at(0).cycleMs == 20.0);
}

TEST_CASE("a DBC message added at run time is posted with its prepared entry and joins the schedule") {
  Fixture f;
  const std::size_t before = f.schedule.messages.size();

  const auto refusal = f.sut->apply(Fixture::request(ipc::CommandKind::ScheduleAdd, ADDABLE, 40));

  REQUIRE_FALSE(refusal);
  REQUIRE(f.sink.posted.size() == 1);
  auto* posted = std::get_if<cantx::AddMessage>(&f.sink.posted[0]);
  REQUIRE(posted != nullptr);
  REQUIRE(posted->message);
  REQUIRE(f.schedule.messages.size() == before + 1);
  CHECK(f.schedule.messages.back().cycleNs == 40 * MS);
  REQUIRE(f.sink.joined.size() == 1);
  CHECK(f.sink.joined[0].first == before);
  CHECK(f.sink.joined[0].second == &cantx::Scheduler::statsOf(*posted->message));
  const cantx::Overlay saved = f.saved();
  REQUIRE(saved.messages.size() == 1);
  CHECK(saved.messages[0].added);
  CHECK(saved.messages[0].cycleMs == 40.0);
  // a second add of the same message: already scheduled
  CHECK(f.sut->apply(Fixture::request(ipc::CommandKind::ScheduleAdd, ADDABLE, 40)));
}

TEST_CASE("an override is kept in the overlay file and dropped again") {
  Fixture f;

  REQUIRE_FALSE(f.sut->recordOverride(TORQUE, 7.0));
  CHECK(f.saved().overrides == std::vector<std::pair<std::string, double>>{{TORQUE, 7.0}});
  REQUIRE_FALSE(f.sut->recordOverride(TORQUE, std::nullopt));
  CHECK(f.saved().overrides.empty());
}
