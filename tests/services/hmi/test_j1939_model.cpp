// The Debug tab's J1939 page (issue 24): vcu-can-tx's view of each J1939 network as rows,
// the latest view per bus, a bus not heard for 3 s Stale. J1939Networks on a set clock;
// J1939Model fed by the stack connection's J1939 subscription on memq://.
#include <doctest/doctest.h>

#include <QCoreApplication>
#include <memory>

#include "common/stack_connection.hpp"
#include "debug/j1939_model.hpp"
#include "debug/j1939_networks.hpp"
#include "hmi_test_support.hpp"
#include "openvcu/core/clock.hpp"
#include "openvcu/ipc/event_bus.hpp"

using namespace openvcu;
using namespace openvcu::hmi;

namespace {

constexpr std::int64_t SECOND_NS = 1'000'000'000;
constexpr std::uint64_t VCU_NAME = 0xB002800000000001;
constexpr std::uint64_t OTHER_NAME = 0x8000000000012345;
constexpr std::uint8_t VIC_ADDRESS = 0xF3;  // HHEA's DBC: VIC's NmStationAddress (243)
/// DM1 byte 0 with the amber warning lamp on (bits 3-4 = 01), the others off.
constexpr std::uint8_t AMBER_ON = 0x04;

ipc::J1939Network claimedView(const std::string& bus) {
  ipc::J1939Network view;
  view.service = "vcu-can-tx";
  view.bus = bus;
  view.claimState = ipc::ClaimState::Claimed;
  view.address = 0x21;
  view.name = VCU_NAME;
  view.nodes = {{VIC_ADDRESS, OTHER_NAME}, {0x80, OTHER_NAME + 1}};
  view.dtcs = {{"pack_overtemp", 110, 0, 2, false}, {"relay_weld", 520200, 7, 1, true}};
  view.lamps = AMBER_ON;
  return view;
}

std::vector<J1939Row::Kind> kindsOf(const std::vector<J1939Row>& rows) {
  std::vector<J1939Row::Kind> kinds;
  for (const J1939Row& row : rows) kinds.push_back(row.kind);
  return kinds;
}

std::unique_ptr<StackConnection> openStack() {
  test::ensureApplication("test_hmi_models");
  auto opened = StackConnection::open(test::memqSettings("hmi-j1939"));
  REQUIRE_MESSAGE(opened, opened.error().toString());
  return std::move(*opened);
}

}  // namespace

TEST_CASE("a configured J1939 bus is listed as not heard until vcu-can-tx reports it") {
  const J1939Networks sut({"vehicle"}, {}, J1939_STALE_AFTER_NS);
  CHECK(sut.overall(0) == ValueStatus::NotConnected);
  const auto rows = sut.rows(0);
  REQUIRE(rows.size() == 1);
  CHECK(rows[0].kind == J1939Row::Kind::Claim);
  CHECK(rows[0].bus == "vehicle");
  CHECK(rows[0].busStatus == ValueStatus::NotConnected);
  CHECK(rows[0].label == "not heard from vcu-can-tx yet");
}

TEST_CASE("a view becomes claim, nodes with their DBC names, DTCs active first, and lamps") {
  DbcNodeNames names;
  names[VIC_ADDRESS] = "VIC";
  J1939Networks sut({"vehicle"}, names, J1939_STALE_AFTER_NS);
  sut.onNetwork(claimedView("vehicle"), 10 * SECOND_NS);
  const auto rows = sut.rows(10 * SECOND_NS);
  using Kind = J1939Row::Kind;
  REQUIRE(kindsOf(rows) ==
          std::vector<Kind>{Kind::Claim, Kind::Note, Kind::Node, Kind::Node, Kind::Note, Kind::Dtc, Kind::Dtc, Kind::Lamps});
  CHECK(rows[0].label == "claimed");
  CHECK(rows[0].address == "0x21 (33)");
  CHECK(rows[0].name == "0xB002800000000001");
  CHECK(rows[0].busStatus == ValueStatus::Ready);
  CHECK_FALSE(rows[0].alert);
  CHECK(rows[1].label == "other nodes (2): address, NAME, DBC node");
  CHECK(rows[2].address == "0xF3 (243)");
  CHECK(rows[2].name == "0x8000000000012345");
  CHECK(rows[2].label == "VIC");
  CHECK(rows[3].label.empty());  // 0x80: no DBC node has that address
  CHECK(rows[5].name == "relay_weld");  // the active one first
  CHECK(rows[5].spn == 520200);
  CHECK(rows[5].fmi == 7);
  CHECK(rows[5].occurrences == 1);
  CHECK(rows[5].active);
  CHECK(rows[5].alert);
  CHECK(rows[6].name == "pack_overtemp");
  CHECK(rows[6].label == "previously active");
  CHECK_FALSE(rows[6].alert);
  CHECK(rows[7].label == "DM1 lamps: protect Off, amber warning On, red stop Off, malfunction Off");
  CHECK(rows[7].alert);
}

TEST_CASE("the latest view of a bus replaces the previous one and an unexpected bus joins") {
  J1939Networks sut({"vehicle"}, {}, J1939_STALE_AFTER_NS);
  sut.onNetwork(claimedView("vehicle"), SECOND_NS);
  ipc::J1939Network lost;
  lost.bus = "vehicle";
  lost.claimState = ipc::ClaimState::CannotClaim;
  lost.address = 0xFE;
  lost.name = VCU_NAME;
  sut.onNetwork(lost, 2 * SECOND_NS);
  ipc::J1939Network off;
  off.bus = "battery";
  sut.onNetwork(off, 2 * SECOND_NS);
  const auto rows = sut.rows(2 * SECOND_NS);
  using Kind = J1939Row::Kind;
  REQUIRE(kindsOf(rows) == std::vector<Kind>{Kind::Claim, Kind::Note, Kind::Note, Kind::Lamps,    // vehicle
                                             Kind::Claim, Kind::Note, Kind::Note, Kind::Lamps});  // battery
  CHECK(rows[0].label == "cannot claim");
  CHECK(rows[0].alert);
  CHECK(rows[1].label == "other nodes: none claimed an address");
  CHECK(rows[2].label == "DTCs: none");
  CHECK(rows[4].bus == "battery");
  CHECK(rows[4].label == "off (no address claim configured)");
  CHECK(rows[4].address.empty());
  CHECK(sut.overall(2 * SECOND_NS) == ValueStatus::Ready);
}

TEST_CASE("a bus not heard for more than 3 s is Stale with its last view kept") {
  J1939Networks sut({"vehicle", "battery"}, {}, J1939_STALE_AFTER_NS);
  sut.onNetwork(claimedView("vehicle"), 0);
  CHECK(sut.overall(0) == ValueStatus::Stale);  // battery not heard yet
  sut.onNetwork(claimedView("battery"), SECOND_NS);
  CHECK(sut.overall(SECOND_NS) == ValueStatus::Ready);
  CHECK(sut.statusOf(0, 3 * SECOND_NS) == ValueStatus::Ready);
  CHECK(sut.statusOf(0, 3 * SECOND_NS + 1) == ValueStatus::Stale);
  CHECK(sut.overall(3 * SECOND_NS + 1) == ValueStatus::Stale);
  const auto rows = sut.rows(3 * SECOND_NS + 1);
  CHECK(rows.front().busStatus == ValueStatus::Stale);
  CHECK(rows.front().address == "0x21 (33)");
  sut.onNetwork(claimedView("vehicle"), 4 * SECOND_NS);
  CHECK(sut.statusOf(0, 4 * SECOND_NS) == ValueStatus::Ready);
}

TEST_CASE("the J1939 model shows the views from the bus, updates rows in place and marks a silent bus Stale") {
  auto stack = openStack();
  J1939Model sut;
  REQUIRE(sut.rowCount() == 1);  // HHEA: the vehicle bus has a "j1939" object
  CHECK(sut.data(sut.index(0), J1939Model::BusRole).toString() == "vehicle");
  CHECK(sut.data(sut.index(0), J1939Model::BusStatusRole).toInt() == ModelStatus::NotConnected);
  CHECK(sut.status() == ModelStatus::NotConnected);

  // through the stack connection's subscription
  stack->events()->publish(claimedView("vehicle"));
  stack->pumpEvents();
  QCoreApplication::processEvents();
  const std::int64_t received = clock::monotonicNs();
  sut.refresh(received);
  REQUIRE(sut.rowCount() == 8);
  CHECK(sut.status() == ModelStatus::Ready);
  CHECK(sut.data(sut.index(0), J1939Model::KindRole).toInt() == J1939Model::Claim);
  CHECK(sut.data(sut.index(0), J1939Model::AddressRole).toString() == "0x21 (33)");
  CHECK(sut.data(sut.index(0), J1939Model::NameRole).toString() == "0xB002800000000001");
  CHECK(sut.data(sut.index(2), J1939Model::LabelRole).toString() == "VIC");
  CHECK(sut.data(sut.index(5), J1939Model::KindRole).toInt() == J1939Model::Dtc);
  CHECK(sut.data(sut.index(5), J1939Model::SpnRole).toUInt() == 520200);
  CHECK(sut.data(sut.index(5), J1939Model::OccurrencesRole).toInt() == 1);
  CHECK(sut.roleNames().value(J1939Model::NameRole) == "nodeName");

  // a node leaves: one row removed, the others stay
  int removed = 0;
  int reset = 0;
  QObject::connect(&sut, &QAbstractItemModel::rowsRemoved, [&] { ++removed; });
  QObject::connect(&sut, &QAbstractItemModel::modelReset, [&] { ++reset; });
  ipc::J1939Network fewer = claimedView("vehicle");
  fewer.nodes.pop_back();
  sut.applyNetwork(fewer, received);
  sut.refresh(received);
  CHECK(sut.rowCount() == 7);
  CHECK(removed == 1);
  CHECK(reset == 0);
  CHECK(sut.data(sut.index(1), J1939Model::LabelRole).toString() == "other nodes (1): address, NAME, DBC node");

  // silent for more than 3 s
  sut.refresh(received + J1939_STALE_AFTER_NS + 1);
  CHECK(sut.status() == ModelStatus::Stale);
  CHECK(sut.data(sut.index(0), J1939Model::BusStatusRole).toInt() == ModelStatus::Stale);
  CHECK(sut.rowCount() == 7);
}
