// libFuzzer target: the FSM condition language alone (docs/fsm.md, "Conditions"). The
// input is one condition (JSON) placed in a two-state machine, A -> B when it holds:
//   {"initialState": "A", "states": [{"name": "A", "transitions": [{"condition": INPUT,
//    "nextState": "B"}]}, {"name": "B"}]}
// A condition that compiles runs in fsm::Engine on memory (MemoryAccess) with a set clock:
// every signal it reads gets values from a fixed list (valid and stale) over 3 s of steps.
// Invariants: no crash, hang or leak; the engine stays in a known state.
#include "fuzz_support.hpp"

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "openvcu/fsm/engine.hpp"
#include "openvcu/fsm/machine.hpp"

using namespace openvcu;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const fuzz::Hhea& hhea = fuzz::hhea();
  const std::string text = R"({"initialState": "A", "states": [{"name": "A", "transitions": [{"condition": )" +
                           std::string(fuzz::asText(data, size)) + R"(, "nextState": "B"}]}, {"name": "B"}]})";
  std::vector<Error> diagnostics;
  auto machineResult = fsm::parseMachine(text, "condition.json", hhea.vehicle, hhea.catalog, &diagnostics);
  if (!machineResult) return 0;
  const fsm::Machine& machine = *machineResult;
  fuzz::require(machine.states.size() == 2 && machine.states[0].transitions.size() == 1);
  const std::uint32_t root = machine.states[0].transitions[0].condition;
  if (root != fsm::NONE) fuzz::require(!fsm::describeCondition(machine, hhea.catalog, root).empty());

  auto slots = fsm::StatusSlots::find(hhea.catalog);
  fuzz::require(slots.ok());
  std::vector<signals::SignalIndex> inputs;
  for (const fsm::SignalRef& ref : machine.signals) inputs.push_back(ref.index);
  fsm::MemoryAccess memory(hhea.catalog.size());
  fsm::Engine sut(machine, hhea.catalog, memory, std::move(*slots));
  constexpr std::int64_t MS = 1'000'000;
  constexpr std::int64_t REALTIME = 1'795'000'000'000'000'000;
  std::int64_t now = 10'000 * MS;
  sut.start(now, REALTIME + now, fsm::StartMode::Fresh);
  constexpr std::array<double, 6> VALUES = {0, 1, 2, 14, 50, -1};
  for (std::size_t round = 0; round < 12; ++round) {
    now += 250 * MS;
    for (std::size_t i = 0; i < inputs.size(); ++i) {
      const double value = VALUES[(round + i) % VALUES.size()];
      const auto quality = round % 5 == 4 ? signals::Quality::Stale : signals::Quality::Valid;
      if (round % 3 != 2) memory.setBus(inputs[i], value, now, quality);
    }
    sut.step(now, REALTIME + now);
    fuzz::require(sut.state() < machine.states.size());
  }
  return 0;
}
