// The checks of a command before anything changes (checkCommand: no table, no bus).

#include <doctest/doctest.h>

#include <cmath>
#include <limits>

#include "openvcu/service/command_handler.hpp"
#include "service_test_support.hpp"

namespace ipc = openvcu::ipc;
namespace service = openvcu::service;
namespace signals = openvcu::signals;
using service::CommandDecision;

namespace {

ipc::CommandRequest request(std::string key, double value, ipc::CommandKind kind = ipc::CommandKind::SetSignal) {
  return ipc::CommandRequest{0, 1, "test", kind, std::move(key), value, ""};
}

}  // namespace

TEST_CASE("a command for a key the service does not own is ignored without a reason") {
  const auto catalog = service::testing::makeCatalog();
  const auto sut = service::CommandPolicy::byPrefix("internal.");

  const auto verdict = service::checkCommand(request("VCU.Command.Enable", 1), catalog, sut);

  CHECK(verdict.decision == CommandDecision::Ignored);
  CHECK(verdict.reason.empty());
}

TEST_CASE("a policy without an ownership rule owns nothing") {
  const auto catalog = service::testing::makeCatalog();
  const service::CommandPolicy sut;

  CHECK(service::checkCommand(request("internal.test.level", 1), catalog, sut).decision == CommandDecision::Ignored);
}

TEST_CASE("an owned key missing from the catalog is refused with a did-you-mean") {
  const auto catalog = service::testing::makeCatalog();
  const auto sut = service::CommandPolicy::byPrefix("internal.");

  const auto verdict = service::checkCommand(request("internal.operator.Strat", 1), catalog, sut);

  CHECK(verdict.decision == CommandDecision::Refused);
  CHECK(verdict.reason == "unknown signal 'internal.operator.Strat' (did you mean 'internal.operator.Start'?)");
  CHECK_FALSE(verdict.index.has_value());
}

TEST_CASE("a value outside the signal's range is refused, naming the range and the unit") {
  const auto catalog = service::testing::makeCatalog();
  const auto sut = service::CommandPolicy::byPrefix("internal.");

  const auto above = service::checkCommand(request("internal.test.level", 100.5), catalog, sut);
  const auto below = service::checkCommand(request("internal.test.level", -1), catalog, sut);

  CHECK(above.decision == CommandDecision::Refused);
  CHECK(above.reason == "value 100.5 is outside the range [0, 100] % of 'internal.test.level'");
  CHECK(below.decision == CommandDecision::Refused);
  REQUIRE(above.index);
  CHECK(catalog[*above.index].key == "internal.test.level");
}

TEST_CASE("the range boundaries themselves are accepted") {
  const auto catalog = service::testing::makeCatalog();
  const auto sut = service::CommandPolicy::byPrefix("internal.");

  CHECK(service::checkCommand(request("internal.test.level", 0), catalog, sut).decision == CommandDecision::Accepted);
  CHECK(service::checkCommand(request("internal.test.level", 100), catalog, sut).decision == CommandDecision::Accepted);
}

TEST_CASE("a signal whose min is not below its max has no range to check") {
  const auto catalog = service::testing::makeCatalog();
  const auto sut = service::CommandPolicy::byPrefix("internal.");

  CHECK(service::checkCommand(request("internal.test.free", -1e9), catalog, sut).decision == CommandDecision::Accepted);
}

TEST_CASE("NaN and infinite values are refused even without a range") {
  const auto catalog = service::testing::makeCatalog();
  const auto sut = service::CommandPolicy::byPrefix("internal.");

  const auto nan = service::checkCommand(request("internal.test.free", std::nan("")), catalog, sut);
  const auto infinite =
      service::checkCommand(request("internal.test.free", std::numeric_limits<double>::infinity()), catalog, sut);

  CHECK(nan.decision == CommandDecision::Refused);
  CHECK(nan.reason == "value nan is not a finite number");
  CHECK(infinite.decision == CommandDecision::Refused);
}

TEST_CASE("clearing an override carries no value, so its value is not checked") {
  const auto catalog = service::testing::makeCatalog();
  const auto sut = service::CommandPolicy::byPrefix("internal.");

  const auto verdict = service::checkCommand(
      request("internal.test.level", std::nan(""), ipc::CommandKind::ClearOverride), catalog, sut);

  CHECK(verdict.decision == CommandDecision::Accepted);
}

TEST_CASE("a kind the policy does not permit is refused") {
  const auto catalog = service::testing::makeCatalog();
  auto sut = service::CommandPolicy::byPrefix("internal.");
  sut.kinds = {ipc::CommandKind::SetSignal};

  const auto verdict =
      service::checkCommand(request("internal.test.level", 5, ipc::CommandKind::SetOverride), catalog, sut);

  CHECK(verdict.decision == CommandDecision::Refused);
  CHECK(verdict.reason == "SetOverride is not permitted for 'internal.test.level'");
}

TEST_CASE("an unknown kind number is refused") {
  const auto catalog = service::testing::makeCatalog();
  const auto sut = service::CommandPolicy::byPrefix("internal.");
  constexpr auto UNKNOWN_KIND = static_cast<ipc::CommandKind>(42);

  const auto verdict = service::checkCommand(request("internal.test.level", 5, UNKNOWN_KIND), catalog, sut);

  CHECK(verdict.decision == CommandDecision::Refused);
  CHECK(verdict.reason == "unknown command kind 42");
}

TEST_CASE("the service's veto has the last word, after the catalog and range checks") {
  const auto catalog = service::testing::makeCatalog();
  auto sut = service::CommandPolicy::byPrefix("internal.");
  sut.veto = [](const ipc::CommandRequest& command, const openvcu::signals::SignalInfo&) -> std::optional<std::string> {
    if (command.kind == ipc::CommandKind::SetOverride) return "overrides are forbidden in state Drive";
    return std::nullopt;
  };

  const auto vetoed =
      service::checkCommand(request("internal.test.level", 5, ipc::CommandKind::SetOverride), catalog, sut);
  const auto outOfRange =
      service::checkCommand(request("internal.test.level", 500, ipc::CommandKind::SetOverride), catalog, sut);
  const auto passed = service::checkCommand(request("internal.test.level", 5), catalog, sut);

  CHECK(vetoed.reason == "overrides are forbidden in state Drive");
  CHECK(outOfRange.reason.find("outside the range") != std::string::npos);
  CHECK(passed.decision == CommandDecision::Accepted);
}

TEST_CASE("command kinds have readable names") {
  CHECK(service::commandKindName(ipc::CommandKind::SetSignal) == "SetSignal");
  CHECK(service::commandKindName(ipc::CommandKind::ClearOverride) == "ClearOverride");
  CHECK(service::commandKindName(ipc::CommandKind::FsmReload) == "FsmReload");
  CHECK(service::commandKindName(ipc::CommandKind::SimFault) == "SimFault");
  CHECK(service::commandKindName(ipc::CommandKind::ScheduleAdd) == "ScheduleAdd");
  CHECK(service::commandKindName(static_cast<ipc::CommandKind>(12)) == "kind 12");
}

TEST_CASE("a switch (its value table names every value of its range) takes table values only") {
  const auto catalog = service::testing::makeCatalog();
  const auto sut = service::CommandPolicy::byPrefix("internal.");

  const auto half = service::checkCommand(request("internal.operator.Start", 0.5), catalog, sut);
  const auto start = service::checkCommand(request("internal.operator.Start", 1), catalog, sut);

  CHECK(half.decision == CommandDecision::Refused);
  CHECK(half.reason == "value 0.5 is not one of the values of 'internal.operator.Start' (0 Stop, 1 Start)");
  CHECK(start.decision == CommandDecision::Accepted);
}

TEST_CASE("a value table that names only special values of a continuous signal does not restrict it") {
  std::vector<openvcu::signals::SignalInfo> infos;
  infos.push_back(service::testing::signal("internal.test.pressure", 0, 255, "kPa"));
  infos.back().valueTexts = {{254, "Error"}, {255, "Not available"}};
  auto catalog = openvcu::signals::Catalog::create(std::move(infos));
  REQUIRE(catalog.ok());
  const auto sut = service::CommandPolicy::byPrefix("internal.");

  CHECK(service::checkCommand(request("internal.test.pressure", 101.5), *catalog, sut).decision ==
        CommandDecision::Accepted);
}

TEST_CASE("a policy by owner answers exactly for the keys the catalog gives its writer id (#20)") {
  constexpr signals::WriterId FSM = 3;
  constexpr signals::WriterId CAN_TX = 2;
  std::vector<signals::SignalInfo> infos(3);
  infos[0].key = "internal.operator.Start";
  infos[0].owner = FSM;
  infos[1].key = "VCU.Command.Enable";
  infos[1].owner = CAN_TX;
  infos[2].key = "internal.fsm.state";
  infos[2].owner = FSM;
  infos[2].reported = true;
  auto catalog = signals::Catalog::create(std::move(infos));
  REQUIRE(catalog.ok());
  const auto sut = service::CommandPolicy::byOwner(*catalog, FSM);

  CHECK(sut.owns("internal.operator.Start"));
  CHECK(sut.owns("internal.fsm.state"));
  CHECK_FALSE(sut.owns("VCU.Command.Enable"));
  CHECK_FALSE(sut.owns("internal.operator.Strat"));  // unknown: nobody's
  CHECK(service::statusRefusal((*catalog)[2]) ==
        std::optional<std::string>("'internal.fsm.state' is a status the stack reports; it cannot be commanded"));
  CHECK_FALSE(service::statusRefusal((*catalog)[0]).has_value());
}
