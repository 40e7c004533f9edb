// vcu-gpio's dead-man switch with a fake clock: when the writer of its output commands
// (vcu-fsm, watched through its heartbeat slot with signals::WriterWatch and the timeout of
// schedule.json "writers") stops beating, every output goes to its safe level at once; when
// it beats again, the outputs follow their commands after their delays, counted from its return.

#include "gpio_test_support.hpp"

using namespace gpiotest;

namespace {

constexpr std::int64_t T0 = 1000 * SECOND;
constexpr std::int64_t TIMEOUT = 3 * SECOND;  // HHEA: {"service": "fsm", "timeoutMs": 3000}
const std::string RELAY = "internal.relay.Cl15";
const std::string RELAY_STATUS = "internal.gpio.Cl15";
const std::string FSM_HEARTBEAT = "internal.service.fsm.heartbeat";

struct WatchingFixture : Fixture {
  std::uint64_t beats{};
  WatchingFixture() { writers.push_back(schedule::WatchedWriter{"fsm", key(FSM_HEARTBEAT), TIMEOUT}); }
  void beat(std::int64_t at) {
    ++beats;
    table->writeBus(key(FSM_HEARTBEAT), static_cast<double>(beats), at, FSM, signals::Quality::Valid);
  }
  /// Started at T0 with a fresh FSM heartbeat and Cl15 switched on by its command.
  std::size_t startWithRelayOn() {
    beat(T0);
    start(T0);
    const std::size_t relay = line("Cl15");
    command(RELAY, 1, T0);
    sut->updateOutputs(T0 + 2 * SECOND);
    REQUIRE(sut->level(relay));
    return relay;
  }
};

}  // namespace

TEST_CASE("a lost command writer drives every output to its safe level at once, without its off-delay") {
  WatchingFixture f;
  const std::size_t relay = f.startWithRelayOn();
  f.beat(T0 + 2'500 * MS);
  f.sut->updateOutputs(T0 + 5'500 * MS);
  CHECK(f.sut->level(relay));
  CHECK(f.writerChanges.empty());
  // the output thread sleeps until the writer would count as lost, not on a periodic tick
  CHECK(f.sut->nextOutputDeadlineNs() == T0 + 5'500 * MS + 1);

  f.sut->updateOutputs(T0 + 5'500 * MS + 1);
  CHECK_FALSE(f.sut->level(relay));  // Cl15's 2 s off-delay does not delay it
  CHECK_FALSE(*f.chip->get(relay));
  CHECK(f.bus(RELAY_STATUS) == 0);
  CHECK(f.writerChanges == std::vector<std::string>{"lost fsm"});
  CHECK(f.logged("writer fsm lost: no heartbeat for 3 s; every output to its safe level"));
  CHECK(f.logged("Cl15: output off (safe level: writer fsm lost)"));
  CHECK(f.sut->writersLost() == 1);
}

TEST_CASE(
    "while the writer is lost its commands are not followed, and once back the outputs follow them after their delay") {
  WatchingFixture f;
  const std::size_t relay = f.startWithRelayOn();
  f.sut->updateOutputs(T0 + TIMEOUT + 1);
  REQUIRE_FALSE(f.sut->level(relay));

  f.command(RELAY, 1, T0 + 4 * SECOND);  // a write from another writer, the writer still silent
  f.sut->updateOutputs(T0 + 8 * SECOND);
  CHECK_FALSE(f.sut->level(relay));
  CHECK(f.sut->nextOutputDeadlineNs() == gpio::NO_DEADLINE);  // woken by the heartbeat slot

  const std::int64_t back = T0 + 9 * SECOND;
  f.beat(back);
  f.sut->updateOutputs(back);
  CHECK(f.writerChanges == std::vector<std::string>{"lost fsm", "back fsm"});
  CHECK(f.logged("writer fsm back: outputs follow their commands"));
  CHECK_FALSE(f.sut->level(relay));
  CHECK(f.sut->nextOutputDeadlineNs() == back + 2 * SECOND);  // Cl15's on-delay from the return
  f.sut->updateOutputs(back + 2 * SECOND - 1);
  CHECK_FALSE(f.sut->level(relay));
  f.sut->updateOutputs(back + 2 * SECOND);
  CHECK(f.sut->level(relay));
}

TEST_CASE("an output already at its safe level is not switched when the writer is lost") {
  WatchingFixture f;
  f.beat(T0);
  f.start(T0);
  const std::size_t relay = f.line("Cl15");
  f.command(RELAY, 0, T0);
  f.sut->updateOutputs(T0 + TIMEOUT + 1);
  CHECK(f.writerChanges == std::vector<std::string>{"lost fsm"});
  CHECK_FALSE(f.sut->level(relay));
  CHECK(f.sut->counters().outputSwitches.load() == 0);
}

TEST_CASE("a writer silent when vcu-gpio starts holds the outputs until it beats, and is lost after the timeout") {
  WatchingFixture f;
  f.beat(T0 - 60 * SECOND);  // a heartbeat of a writer that hung a minute ago
  f.command(RELAY, 1, T0 - 60 * SECOND);
  f.start(T0);
  const std::size_t relay = f.line("Cl15");
  f.sut->updateOutputs(T0 + SECOND);
  CHECK_FALSE(f.sut->level(relay));  // the old command is not followed
  CHECK(f.writerChanges.empty());    // nor a fault before its full timeout from the start
  f.sut->updateOutputs(T0 + TIMEOUT + 1);
  CHECK(f.writerChanges == std::vector<std::string>{"lost fsm"});
  CHECK_FALSE(f.sut->level(relay));
}

TEST_CASE("a writer that beats after vcu-gpio started releases the outputs, with their delays from that beat") {
  WatchingFixture f;
  f.beat(T0 - 60 * SECOND);
  f.command(RELAY, 1, T0 - 60 * SECOND);
  f.start(T0);
  const std::size_t relay = f.line("Cl15");
  f.beat(T0 + 800 * MS);
  f.sut->updateOutputs(T0 + 800 * MS);
  CHECK(f.writerChanges.empty());
  CHECK_FALSE(f.sut->level(relay));
  f.sut->updateOutputs(T0 + 2'800 * MS);
  CHECK(f.sut->level(relay));
}

TEST_CASE("without watched writers the outputs follow their commands as before") {
  Fixture f;
  f.start(T0);
  f.command(RELAY, 1, T0);
  f.sut->updateOutputs(T0 + 60 * SECOND);
  CHECK(f.sut->level(f.line("Cl15")));
  CHECK(f.sut->nextOutputDeadlineNs() == gpio::NO_DEADLINE);
}
