// libFuzzer target: an FSM file (fsm.json, docs/fsm.md) through fsm::parseMachine on the
// HHEA vehicle and catalog: the JSON checks, the condition compiler, the graph and cycle
// checks. A compiled machine is then described (every transition's condition as text).
// Invariants: no crash, hang or leak; a refused file names an error; a compiled machine's
// indices (initial state, targets, condition nodes, children) are in range.
#include "fuzz_support.hpp"

#include <vector>

#include "openvcu/fsm/machine.hpp"

using namespace openvcu;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const fuzz::Hhea& hhea = fuzz::hhea();
  std::vector<Error> diagnostics;
  auto machineResult = fsm::parseMachine(fuzz::asText(data, size), "fuzz.json", hhea.vehicle, hhea.catalog,
                                         &diagnostics);
  if (!machineResult) {
    fuzz::require(!diagnostics.empty());
    return 0;
  }
  const fsm::Machine& machine = *machineResult;
  fuzz::require(machine.initial < machine.states.size());
  for (const fsm::ConditionNode& node : machine.nodes) {
    if (node.kind == fsm::NodeKind::All || node.kind == fsm::NodeKind::Any || node.kind == fsm::NodeKind::Not) {
      fuzz::require(node.first + node.count <= machine.children.size());
    }
    if (node.kind == fsm::NodeKind::Compare && node.op == fsm::CompareOp::In) {
      fuzz::require(node.first + node.count <= machine.constants.size());
    }
  }
  for (const fsm::State& state : machine.states) {
    for (const fsm::Transition& transition : state.transitions) {
      fuzz::require(transition.target < machine.states.size());
      if (transition.condition != fsm::NONE) {
        fuzz::require(transition.condition < machine.nodes.size());
        fuzz::require(!fsm::describeCondition(machine, hhea.catalog, transition.condition).empty());
      }
    }
  }
  return 0;
}
