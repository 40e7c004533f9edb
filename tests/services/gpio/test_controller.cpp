// vcu-gpio's controller on the simulated chip with a fake clock: delays, debounce, safe
// state, resuming after a restart, commands, and the libgpiod back end without a chip.

#include <array>

#include "gpio_app.hpp"
#include "gpio_test_support.hpp"
#include "openvcu/core/clock.hpp"
#include "openvcu/service/command_handler.hpp"

using namespace gpiotest;

namespace {

constexpr std::int64_t T0 = 1000 * SECOND;
const std::string RELAY = "internal.relay.Cl15";
const std::string RELAY_STATUS = "internal.gpio.Cl15";
const std::string FAULT = "internal.fault.Contactor";
const std::string FAULT_STATUS = "internal.gpio.ContactorFault";
const std::string FAULT_SIM = "internal.gpio.sim.ContactorFault";

/// A chip whose set() fails while `failing` (the kernel refusing a write).
class FailingChip final : public gpio::Chip {
 public:
  bool failing{true};
  std::vector<bool> levels;
  Status request(std::span<const bool> start) override {
    levels.assign(start.begin(), start.end());
    return {};
  }
  Status set(std::size_t line, bool level) override {
    if (failing) return Error{"I/O error"};
    levels[line] = level;
    return {};
  }
  Result<bool> get(std::size_t line) override { return static_cast<bool>(levels[line]); }
  [[nodiscard]] std::vector<int> eventFds() const override { return {}; }
  std::size_t readEvents(int, std::span<gpio::LineEvent>) override { return 0; }
  void release() noexcept override {}
  [[nodiscard]] std::string_view kind() const noexcept override { return "failing"; }
};

}  // namespace

TEST_CASE("an output switches on its on-delay after the command and off its off-delay after the next") {
  Fixture f;
  f.start(T0);
  const std::size_t relay = f.line("Cl15");
  CHECK_FALSE(f.sut->level(relay));  // fresh table: the initial level
  CHECK(f.bus(RELAY_STATUS) == 0);

  f.command(RELAY, 1, T0 + SECOND);
  f.sut->updateOutputs(T0 + SECOND + 1);
  CHECK(f.sut->nextOutputDeadlineNs() == T0 + 3 * SECOND);
  f.sut->updateOutputs(T0 + 3 * SECOND - 1);
  CHECK_FALSE(f.sut->level(relay));
  f.sut->updateOutputs(T0 + 3 * SECOND);
  CHECK(f.sut->level(relay));
  CHECK(f.bus(RELAY_STATUS) == 1);
  CHECK(*f.chip->get(relay));
  CHECK(f.logged("Cl15: output on (commanded on, on-delay 2 s)"));
  CHECK(f.sut->nextOutputDeadlineNs() == gpio::NO_DEADLINE);

  f.command(RELAY, 0, T0 + 10 * SECOND);
  f.sut->updateOutputs(T0 + 11 * SECOND);
  CHECK(f.sut->level(relay));
  f.sut->updateOutputs(T0 + 12 * SECOND);
  CHECK_FALSE(f.sut->level(relay));
  CHECK(f.sut->counters().outputSwitches.load() == 2);
}

TEST_CASE("a command that flips back within the delay never reaches the line") {
  Fixture f;
  f.start(T0);
  const std::size_t relay = f.line("Cl15");
  f.command(RELAY, 1, T0);
  f.sut->updateOutputs(T0 + SECOND);
  f.command(RELAY, 0, T0 + SECOND + 500 * MS);
  f.sut->updateOutputs(T0 + 5 * SECOND);
  CHECK_FALSE(f.sut->level(relay));
  CHECK(f.sut->counters().outputSwitches.load() == 0);
  CHECK(f.sut->nextOutputDeadlineNs() == gpio::NO_DEADLINE);
}

TEST_CASE("an override wins over the command, and a command older than its delay switches at once") {
  Fixture f;
  f.start(T0);
  const std::size_t relay = f.line("Cl15");
  f.command(RELAY, 1, T0 - 10 * SECOND);  // commanded before this vcu-gpio started
  f.sut->updateOutputs(T0);
  CHECK(f.sut->level(relay));
  f.table->setOverride(f.key(RELAY), 0, T0 + SECOND, 5);
  f.sut->updateOutputs(T0 + 3 * SECOND);
  CHECK_FALSE(f.sut->level(relay));
  CHECK(f.logged("commanded off (override)"));
}

TEST_CASE("safe state drives every output to its safe level and a restart resumes the level driven last") {
  Fixture f;
  f.start(T0);
  const std::size_t relay = f.line("Cl15");
  f.command(RELAY, 1, T0);
  f.sut->updateOutputs(T0 + 2 * SECOND);
  REQUIRE(f.sut->level(relay));

  // a crash: a new controller on the same table starts with the relay on, no glitch
  f.start(T0 + 5 * SECOND);
  CHECK(f.sut->level(relay));
  CHECK(*f.chip->get(relay));
  CHECK(f.logged("resumed: the level driven before the restart"));

  f.sut->safeState(T0 + 6 * SECOND);
  CHECK_FALSE(f.sut->level(relay));
  CHECK(f.bus(RELAY_STATUS) == 0);
  CHECK(f.logged("Cl15: output off (safe state)"));
}

TEST_CASE("an input level counts once it stayed for the debounce time, and a bounce is dropped") {
  Fixture f;
  f.start(T0);
  const std::size_t input = f.line("ContactorFault");  // debounce 20 ms
  CHECK(f.bus(FAULT) == 0);  // pull-down: the unset simulated line reads 0
  CHECK(f.bus(FAULT_STATUS) == 0);

  f.sut->onEvent(gpio::LineEvent{input, true, T0 + SECOND});
  f.sut->onEvent(gpio::LineEvent{input, false, T0 + SECOND + 5 * MS});  // a bounce
  f.sut->updateInputs(T0 + SECOND + 30 * MS);
  CHECK_FALSE(f.sut->level(input));
  CHECK(f.sut->counters().inputBounces.load() == 1);

  f.sut->onEvent(gpio::LineEvent{input, true, T0 + 2 * SECOND});
  f.sut->updateInputs(T0 + 2 * SECOND + 19 * MS);
  CHECK_FALSE(f.sut->level(input));
  CHECK(f.sut->nextInputDeadlineNs() == T0 + 2 * SECOND + 20 * MS);
  f.sut->updateInputs(T0 + 2 * SECOND + 20 * MS);
  CHECK(f.sut->level(input));
  CHECK(f.bus(FAULT) == 1);
  CHECK(f.bus(FAULT_STATUS) == 1);
  CHECK(f.sut->counters().inputChanges.load() == 1);
  CHECK(f.sut->counters().inputEdges.load() == 3);
  CHECK(f.logged("ContactorFault: input on -> internal.fault.Contactor = 1 (stable for 20 ms)"));
}

TEST_CASE("the simulated chip turns a commanded line level into an edge event on its descriptor") {
  Fixture f;
  f.start(openvcu::clock::monotonicNs());
  const std::size_t input = f.line("ContactorFault");
  const std::vector<int> fds = f.chip->eventFds();
  REQUIRE(fds.size() == 1);
  std::array<gpio::LineEvent, 8> batch{};
  CHECK(f.chip->readEvents(fds[0], batch) == 0);

  f.command(FAULT_SIM, 1, openvcu::clock::monotonicNs());
  f.chip->tableChanged();
  REQUIRE(f.chip->readEvents(fds[0], batch) == 1);
  CHECK(batch[0].line == input);
  CHECK(batch[0].level);
  f.chip->tableChanged();  // no change: no event
  CHECK(f.chip->readEvents(fds[0], batch) == 0);
  f.sut->onEvent(batch[0]);
  f.sut->updateInputs(batch[0].monotonicNs + 20 * MS);
  CHECK(f.bus(FAULT) == 1);
}

TEST_CASE("an active-low simulated input reads the inverse of its electrical level") {
  Fixture f;
  f.vehicle.gpio.lines[f.line("ContactorFault")].activeLow = true;
  f.start(T0);
  CHECK(f.sut->level(f.line("ContactorFault")));  // electrical 0 (pull-down) = active
  CHECK(f.bus(FAULT) == 1);
}

TEST_CASE("a failed write is counted, logged and retried a second later, not in a loop") {
  Fixture f;
  auto failing = std::make_unique<FailingChip>();
  FailingChip* chip = failing.get();
  f.start(T0, std::move(failing));
  const std::size_t relay = f.line("Cl15");
  f.command(RELAY, 1, T0);
  f.sut->updateOutputs(T0 + 2 * SECOND);
  CHECK_FALSE(f.sut->level(relay));
  CHECK(f.sut->counters().setFailures.load() == 1);
  CHECK(f.logged("Cl15: output on failed: I/O error; retrying in 1 s"));
  CHECK(f.sut->nextOutputDeadlineNs() == T0 + 3 * SECOND);
  f.sut->updateOutputs(T0 + 2 * SECOND + 500 * MS);
  CHECK(f.sut->counters().setFailures.load() == 1);
  chip->failing = false;
  f.sut->updateOutputs(T0 + 3 * SECOND);
  CHECK(f.sut->level(relay));
  CHECK(chip->levels[relay]);
}

TEST_CASE("vcu-gpio answers for its keys: simulated levels and overrides yes, statuses and input signals no") {
  Fixture f;
  const auto decide = [&](const std::string& key, ipc::CommandKind kind) {
    ipc::CommandRequest request;
    request.key = key;
    request.kind = kind;
    request.value = 1;
    return service::checkCommand(request, f.catalog, gpio::gpioCommandPolicy(f.catalog, f.vehicle.gpio));
  };
  CHECK(decide(FAULT_SIM, ipc::CommandKind::SetSignal).decision == service::CommandDecision::Accepted);
  const auto plain = decide(FAULT, ipc::CommandKind::SetSignal);
  CHECK(plain.decision == service::CommandDecision::Refused);
  CHECK(plain.reason.find("read from input line ContactorFault") != std::string::npos);
  CHECK(decide(FAULT, ipc::CommandKind::SetOverride).decision == service::CommandDecision::Accepted);
  CHECK(decide(RELAY_STATUS, ipc::CommandKind::SetSignal).decision == service::CommandDecision::Refused);
  CHECK(decide(RELAY, ipc::CommandKind::SetSignal).decision == service::CommandDecision::Ignored);  // vcu-fsm's

  f.vehicle.gpio.backend = config::GpioBackend::Gpiod;
  const auto real = decide(FAULT_SIM, ipc::CommandKind::SetSignal);
  CHECK(real.decision == service::CommandDecision::Refused);
  CHECK(real.reason.find("the real line sets this input") != std::string::npos);
}

TEST_CASE("the libgpiod back end is built and names a missing chip plainly") {
  CHECK(gpio::haveGpiod());
  config::GpioMap map;
  map.backend = config::GpioBackend::Gpiod;
  map.chips.push_back(config::GpioChip{"main", "gpiochip-openvcu-none", ""});
  auto opened = gpio::openGpiodChip(map);
  REQUIRE_FALSE(opened);
  CHECK(opened.error().message == "gpio chip 'main' (gpiochip-openvcu-none): no such chip");
  map.chips[0] = config::GpioChip{"main", "", "no-such-label"};
  auto byLabel = gpio::openGpiodChip(map);
  REQUIRE_FALSE(byLabel);
  CHECK(byLabel.error().message.find("label 'no-such-label'") != std::string::npos);
}
