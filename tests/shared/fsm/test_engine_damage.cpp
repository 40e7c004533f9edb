// Issue 18: the signal table lost its values under a running vcu-fsm (truncated or
// overwritten; docs/design/signal-table.md, "Damage"). Engine::restoreTable() writes back
// what the FSM keeps in the table, and for DAMAGE_GRACE_NS inputs that read as never
// written keep their previous samples, so the wipe is not taken for a sensor dropout (the
// HHEA stack used to leave Driving for Standby: StartStop read its initial value Stop).

#include <doctest/doctest.h>
#include <unistd.h>

#include <atomic>
#include <optional>
#include <string>

#include "fsm_test_support.hpp"
#include "openvcu/core/clock.hpp"
#include "openvcu/fsm/engine.hpp"

using namespace openvcu;

namespace {

constexpr std::int64_t MS = 1'000'000;
constexpr std::int64_t T0 = 10'000 * MS;
constexpr std::int64_t REALTIME = 1'795'000'000'000'000'000;
constexpr signals::WriterId CAN_TX = 2;  // vcu-can-tx's writer id (its safe values)
constexpr signals::WriterId OTHER = 99;
constexpr double START = 1;  // internal.operator.StartStop "Start"
constexpr double CONNECTED = 1;
constexpr double BATTERY_FAULT = 14;
constexpr double LOW_SOC = 10;

/// Standby -> Driving on Start; Driving runs a `for` timer on a low SOC and leaves for
/// "Dropout" when the battery's connection status is not 1 or the operator says Stop.
const std::string DRIVING = std::string(R"({"initialState": "Standby", "states": [
  {"name": "Standby", "entry": [{"sendGroup": "keepAlive", "on": false}],
   "transitions": [{"condition": {"key": "internal.operator.StartStop", "eq": "Start"},
                    "actions": [{"signal": ")") +
                            fsmtest::BMS_CONTROL + R"(", "value": 1}],
                    "nextState": "Driving"}]},
  {"name": "Driving", "entry": [{"sendGroup": "keepAlive", "on": true},
                                {"signal": ")" +
                            fsmtest::CONTACTOR_A + R"(", "value": 1}],
   "transitions": [{"condition": {"key": ")" +
                            fsmtest::SOC + R"(", "lt": 20, "for": "1s"}, "nextState": "Standby"},
                   {"condition": {"any": [{"key": ")" +
                            fsmtest::CONNECTION + R"(", "ne": 1},
                                          {"key": "internal.operator.StartStop", "eq": "Stop"}]},
                    "nextState": "Dropout"}]},
  {"name": "Dropout", "transitions": [{"after": "10s", "nextState": "Standby"}]}]})";

struct Bench {
  fsmtest::Hhea hhea;
  fsm::MemoryAccess memory{hhea.catalog.size()};
  std::optional<fsm::Engine> engine;
  std::int64_t now{T0};

  void start(const std::string& text) {
    auto slots = fsm::StatusSlots::find(hhea.catalog);
    REQUIRE(slots);
    engine.emplace(hhea.good(text), hhea.catalog, memory, std::move(*slots));
    engine->start(now, REALTIME + now, fsm::StartMode::Fresh);
  }
  void bus(const char* key, double value) { memory.setBus(hhea.key(key), value, now); }
  void command(const char* key, double value, signals::WriterId writer) {
    memory.setCommand(hhea.key(key), value, now, writer);
  }
  void at(std::int64_t t) {
    now = t;
    engine->step(now, REALTIME + now);
  }
  /// What a truncation leaves: every plane of every slot never written.
  void wipe() { memory = fsm::MemoryAccess(hhea.catalog.size()); }
  /// Standby -> Driving with the battery connected and the operator's Start (written by
  /// vcu-fsm's command handler, so with the FSM's writer id).
  void drive() {
    start(DRIVING);
    bus(fsmtest::CONNECTION, CONNECTED);
    command(fsmtest::START_STOP, START, fsm::FSM_WRITER);
    at(now + MS);
    REQUIRE(state() == "Driving");
  }
  [[nodiscard]] std::string state() const { return engine->stateName(); }
  [[nodiscard]] std::optional<double> commanded(const char* key) const {
    const signals::CommandValue& value = memory.slot(hhea.key(key)).command;
    if (value.updates == 0) return std::nullopt;
    return value.value;
  }
  [[nodiscard]] const signals::BusValue& status(const char* key) const { return memory.slot(hhea.key(key)).bus; }
};

}  // namespace

TEST_CASE("restoreTable writes back the state, entry time, machine hash, for timers and the FSM's own commands") {
  Bench bench;
  bench.drive();
  const std::int64_t enteredNs = bench.now;
  bench.bus(fsmtest::SOC, LOW_SOC);
  bench.at(bench.now + 100 * MS);  // the `for` timer starts
  const std::int64_t timerNs = bench.now;
  REQUIRE(bench.status("internal.fsm.timer.0").value == doctest::Approx(static_cast<double>(timerNs) / 1e9));
  bench.command(fsmtest::CONTACTOR_A, 0, CAN_TX);  // can-tx's safe value replaced the FSM's command
  bench.at(bench.now + 100 * MS);
  REQUIRE(bench.state() == "Driving");

  bench.wipe();
  REQUIRE(bench.status("internal.fsm.state").updates == 0);
  const std::size_t restored = bench.engine->restoreTable(bench.now, REALTIME + bench.now);

  CHECK(restored == 3);                                    // keepAlive, BMS_Control, the operator's StartStop
  CHECK(bench.status("internal.fsm.state").value == 1.0);  // Driving
  CHECK(bench.status("internal.fsm.stateEntered").value == doctest::Approx(static_cast<double>(enteredNs) / 1e9));
  CHECK(bench.status("internal.fsm.stateSince").value ==
        doctest::Approx(static_cast<double>(REALTIME + enteredNs) / 1e9));
  CHECK(bench.status("internal.fsm.machine").value == static_cast<double>(bench.engine->machine().hash));
  CHECK(bench.status("internal.fsm.timer.0").value == doctest::Approx(static_cast<double>(timerNs) / 1e9));
  CHECK(bench.status("internal.fsm.timer.1").updates == 1);  // an idle timer reads 0 again, not never written
  CHECK(bench.status("internal.fsm.timer.1").value == 0.0);
  CHECK(bench.commanded(fsmtest::KEEP_ALIVE) == 1.0);
  CHECK(bench.commanded(fsmtest::BMS_CONTROL) == 1.0);
  CHECK(bench.commanded(fsmtest::START_STOP) == START);
  CHECK_FALSE(bench.commanded(fsmtest::CONTACTOR_A).has_value());  // can-tx's own to write again

  // A restarted vcu-fsm would resume Driving from the restored table.
  fsm::MemoryAccess& table = bench.memory;
  auto slots = fsm::StatusSlots::find(bench.hhea.catalog);
  REQUIRE(slots);
  fsm::Engine restarted(bench.hhea.good(DRIVING), bench.hhea.catalog, table, std::move(*slots));
  restarted.start(bench.now, REALTIME + bench.now, fsm::StartMode::Resume);
  CHECK(restarted.stateName() == "Driving");
}

TEST_CASE("after restoreTable an input not received since the wipe keeps its last value for the grace window only") {
  Bench bench;
  bench.drive();
  bench.command(fsmtest::START_STOP, START, OTHER);  // not the FSM's: not written back
  bench.at(bench.now + MS);
  bench.wipe();
  (void)bench.engine->restoreTable(bench.now, REALTIME + bench.now);
  const std::int64_t wipedNs = bench.now;
  CHECK(bench.engine->inDamageGrace(wipedNs));
  CHECK(bench.engine->nextDeadlineNs() == wipedNs + fsm::DAMAGE_GRACE_NS);

  bench.at(wipedNs + 10 * MS);
  CHECK(bench.state() == "Driving");  // StartStop (initial Stop) and the connection status would leave it
  bench.at(wipedNs + fsm::DAMAGE_GRACE_NS - MS);
  CHECK(bench.state() == "Driving");

  bench.at(wipedNs + fsm::DAMAGE_GRACE_NS);  // still never written: now it is a dropout
  CHECK(bench.state() == "Dropout");
  CHECK_FALSE(bench.engine->inDamageGrace(bench.now));
}

TEST_CASE("during the grace window an input written again is taken at once") {
  Bench bench;
  bench.drive();
  bench.wipe();
  (void)bench.engine->restoreTable(bench.now, REALTIME + bench.now);
  bench.at(bench.now + 10 * MS);
  REQUIRE(bench.state() == "Driving");

  bench.bus(fsmtest::CONNECTION, BATTERY_FAULT);  // can-rx decodes the next frame
  bench.at(bench.now + 10 * MS);
  CHECK(bench.state() == "Dropout");
}

TEST_CASE("update counters that fell back start the grace window even before restoreTable is called") {
  // The table can be wiped between the app's damage check and the engine's reads.
  Bench bench;
  bench.drive();
  bench.wipe();
  bench.at(bench.now + MS);
  CHECK(bench.state() == "Driving");
  CHECK(bench.engine->inDamageGrace(bench.now));
}

TEST_CASE("without damage an input that is never received is no grace case") {
  Bench bench;
  bench.start(DRIVING);
  bench.command(fsmtest::START_STOP, START, fsm::FSM_WRITER);
  bench.at(bench.now + MS);  // the battery never spoke: the connection status compares false
  CHECK(bench.state() == "Driving");
  CHECK_FALSE(bench.engine->inDamageGrace(bench.now));
  CHECK(bench.engine->nextDeadlineNs() == fsm::NO_DEADLINE);
}

namespace {

/// "t-fsm-damage-<pid>-<n>": a table of its own, removed at the end.
class ScopedTable {
 public:
  explicit ScopedTable(const signals::Catalog& catalog) {
    static std::atomic<int> counter{0};
    m_instance = "t-fsm-damage-" + std::to_string(::getpid()) + "-" + std::to_string(counter.fetch_add(1));
    (void)signals::SignalTable::remove(m_instance);
    auto openResult = signals::SignalTable::open(catalog, m_instance);
    REQUIRE_MESSAGE(openResult, (openResult ? "" : openResult.error().toString()));
    m_table.emplace(std::move(*openResult));
  }
  ScopedTable(const ScopedTable&) = delete;
  ScopedTable& operator=(const ScopedTable&) = delete;
  ~ScopedTable() {
    m_table.reset();
    (void)signals::SignalTable::remove(m_instance);
  }
  signals::SignalTable& table() { return *m_table; }
  [[nodiscard]] std::string path() const { return signals::SignalTable::segmentPath(m_instance); }

 private:
  std::string m_instance;
  std::optional<signals::SignalTable> m_table;
};

}  // namespace

TEST_CASE("a truncated signal table gets the FSM's state and commands back from restoreTable") {
  const fsmtest::Hhea hhea;
  ScopedTable scoped(hhea.catalog);
  signals::SignalTable& table = scoped.table();
  fsm::TableAccess access(table, fsm::FSM_WRITER);
  auto slots = fsm::StatusSlots::find(hhea.catalog);
  REQUIRE(slots);
  fsm::Engine sut(hhea.good(DRIVING), hhea.catalog, access, std::move(*slots));
  std::int64_t now = openvcu::clock::monotonicNs();
  sut.start(now, REALTIME + now, fsm::StartMode::Fresh);
  table.writeBus(hhea.key(fsmtest::CONNECTION), CONNECTED, now, 0xF3, signals::Quality::Valid);
  table.writeCommand(hhea.key(fsmtest::START_STOP), START, now, fsm::FSM_WRITER);
  sut.step(now, REALTIME + now);
  REQUIRE(sut.stateName() == "Driving");
  const std::uint64_t damageBefore = table.damageCount();

  REQUIRE(::truncate(scoped.path().c_str(), 0) == 0);               // what `truncate -s 0 /dev/shm/openvcu-...` does
  const auto lost = table.readBus(hhea.key("internal.fsm.state"));  // was SIGBUS
  REQUIRE(lost);
  CHECK(lost->updates == 0);
  CHECK(table.damageCount() != damageBefore);
  now = openvcu::clock::monotonicNs();
  sut.step(now, REALTIME + now);  // before restoreTable: the wipe alone does not leave Driving
  CHECK(sut.stateName() == "Driving");
  CHECK(sut.restoreTable(now, REALTIME + now) == 4);  // keepAlive, BMS_Control, contactor A, StartStop

  const auto state = table.readBus(hhea.key("internal.fsm.state"));
  REQUIRE(state);
  CHECK(state->value == 1.0);
  const auto keepAlive = table.readCommand(hhea.key(fsmtest::KEEP_ALIVE));
  REQUIRE(keepAlive);
  CHECK(keepAlive->value == 1.0);
  CHECK(keepAlive->writer == fsm::FSM_WRITER);
  const auto startStop = table.readCommand(hhea.key(fsmtest::START_STOP));
  REQUIRE(startStop);
  CHECK(startStop->value == START);
  const auto contactor = table.readCommand(hhea.key(fsmtest::CONTACTOR_A));
  REQUIRE(contactor);
  CHECK(contactor->value == 1.0);
  CHECK(table.checkAndRepair().has_value());
}
