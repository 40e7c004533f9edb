// bridge::MessageBinding (issue 20): a DBC message's signals decoded into their table slots
// and encoded from them, with the semantics can-rx and can-tx had before the bridge.

#include <doctest/doctest.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "openvcu/bridge/message_binding.hpp"
#include "openvcu/dbc/parser.hpp"

using namespace openvcu;

namespace {

constexpr std::int64_t NOW = 5'000'000'000;
constexpr std::uint16_t BMS_ADDRESS = 0xF3;
constexpr std::size_t STATUS = 0;  ///< BMS_Status: plain signals
constexpr std::size_t MUXED = 1;   ///< BMS_Mux: a multiplexor, two pages, an unsupported float
constexpr std::uint32_t SOC = 0, CURRENT = 1, SPARE = 2, NO_SLOT_SIGNAL = 3, TAIL = 4;
constexpr std::uint32_t SELECTOR = 0, PAGE_A = 1, PAGE_B = 2, BAD_FLOAT = 3, PLAIN = 4;

constexpr std::string_view DBC = R"(VERSION ""
BU_: VCU BMS
BO_ 2566849011 BMS_Status: 8 BMS
 SG_ Soc : 0|8@1+ (0.5,0) [0|100] "%" VCU
 SG_ Current : 8|16@1- (0.1,0) [-1000|1000] "A" VCU
 SG_ Spare : 24|8@1+ (1,0) [0|0] "" VCU
 SG_ NoSlot : 32|8@1+ (1,0) [0|255] "" VCU
 SG_ Tail : 48|16@1+ (1,0) [0|65535] "" VCU
BO_ 512 BMS_Mux: 8 BMS
 SG_ Sel M : 0|8@1+ (1,0) [0|0] "" VCU
 SG_ PageA m1 : 8|8@1+ (1,0) [0|0] "" VCU
 SG_ PageB m2 : 8|8@1+ (1,0) [0|0] "" VCU
 SG_ BadFloat : 16|16@1+ (1,0) [0|0] "" VCU
 SG_ Plain : 32|8@1+ (1,0) [0|0] "" VCU
SIG_VALTYPE_ 512 BadFloat : 1;
)";

/// The DBC above, a catalog of every signal but BMS_Status.NoSlot, a private table.
struct Fixture {
  dbc::Database database;
  signals::Catalog catalog;
  std::optional<signals::SignalTable> table;
  std::string instance = "bridgeunit-" + std::to_string(::getpid());

  Fixture() {
    dbc::ParseOutput parsed = dbc::parse(DBC, "bridge.dbc");
    REQUIRE_FALSE(parsed.hasErrors());
    database = std::move(parsed.database);
    REQUIRE(database.messages.size() == 2);
    std::vector<signals::SignalInfo> infos;
    for (const dbc::Message& message : database.messages) {
      for (const dbc::Signal& signal : message.signals) {
        if (signal.name == "NoSlot") continue;
        signals::SignalInfo info;
        info.key = message.transmitter + "." + message.name + "." + signal.name;
        infos.push_back(std::move(info));
      }
    }
    auto catalogResult = signals::Catalog::create(std::move(infos));
    REQUIRE(catalogResult);
    catalog = std::move(*catalogResult);
    (void)signals::SignalTable::remove(instance);
    auto tableResult = signals::SignalTable::open(catalog, instance);
    REQUIRE_MESSAGE(tableResult, (tableResult ? "" : tableResult.error().toString()));
    table.emplace(std::move(*tableResult));
  }
  ~Fixture() { (void)signals::SignalTable::remove(instance); }

  signals::SignalIndex index(std::string_view key) const {
    const auto maybeIndex = catalog.indexOf(key);
    REQUIRE_MESSAGE(maybeIndex, key);
    return *maybeIndex;
  }
  signals::BusValue bus(std::string_view key) const {
    const auto value = table->readBus(index(key));
    REQUIRE(value);
    return *value;
  }
};

using Payload = std::array<std::uint8_t, 8>;

}  // namespace

TEST_CASE("binding looks every signal's key up in the catalog once") {
  Fixture f;
  const bridge::DatabaseBinding bindings(f.database, f.catalog);
  REQUIRE(bindings.size() == 2);
  const bridge::MessageBinding& sut = bindings[STATUS];
  CHECK(sut.messageIndex() == STATUS);
  CHECK(sut.signalCount() == 5);
  CHECK(sut.slot(SOC) == f.index("BMS.BMS_Status.Soc"));
  CHECK(sut.slot(TAIL) == f.index("BMS.BMS_Status.Tail"));
  CHECK_FALSE(sut.slot(NO_SLOT_SIGNAL));
  CHECK_FALSE(sut.slot(99));
  CHECK(sut.limits(SOC).any());
  CHECK_FALSE(sut.limits(SPARE).any());
  CHECK(sut.signalIndex("Current") == CURRENT);
  CHECK_FALSE(sut.signalIndex("current"));
}

TEST_CASE("decode into the table lands each signal in its slot on the bus plane with source and time") {
  Fixture f;
  const bridge::DatabaseBinding bindings(f.database, f.catalog);
  // Soc 0xAF = 175 -> 87.5 %, Current 0xFF38 = -200 -> -20.0 A, Spare 7, NoSlot 9, Tail 0x1234.
  const Payload payload{0xAF, 0x38, 0xFF, 0x07, 0x09, 0x00, 0x34, 0x12};

  const bridge::DecodeResult result =
      bindings[STATUS].decodeInto(*f.table, payload, NOW, BMS_ADDRESS, bridge::RangeCheck::Mark);

  const signals::BusValue soc = f.bus("BMS.BMS_Status.Soc");
  CHECK(soc.value == doctest::Approx(87.5));
  CHECK(soc.timestampNs == NOW);
  CHECK(soc.source == BMS_ADDRESS);
  CHECK(soc.quality == signals::Quality::Valid);
  CHECK(soc.updates == 1);
  CHECK(f.bus("BMS.BMS_Status.Current").value == doctest::Approx(-20.0));
  CHECK(f.bus("BMS.BMS_Status.Spare").value == 7.0);
  CHECK(f.bus("BMS.BMS_Status.Tail").value == 0x1234);
  CHECK(result.decoded == 5);
  CHECK(result.written == 4);
  CHECK(result.outOfRange == 0);
  CHECK(result.missing == 0);
}

TEST_CASE("a signal with no slot is decoded but written nowhere") {
  Fixture f;
  const bridge::DatabaseBinding bindings(f.database, f.catalog);
  const Payload payload{0, 0, 0, 0, 0x09, 0, 0, 0};

  const bridge::DecodeResult result =
      bindings[STATUS].decodeInto(*f.table, payload, NOW, BMS_ADDRESS, bridge::RangeCheck::Mark);

  CHECK(result.decoded - result.written == 1);
  // only the 4 bound slots of BMS_Status were written; BMS_Mux's slots stay untouched
  for (const std::string_view key : {"BMS.BMS_Mux.Sel", "BMS.BMS_Mux.PageA", "BMS.BMS_Mux.Plain"}) {
    CHECK(f.bus(key).quality == signals::Quality::NeverReceived);
  }
}

TEST_CASE("a value outside the DBC range is written with quality OutOfRange and counted, [0|0] is no range") {
  Fixture f;
  const bridge::DatabaseBinding bindings(f.database, f.catalog);
  // Soc 0xFF -> 127.5 % (> 100), Spare 0xFF (no range).
  const Payload payload{0xFF, 0, 0, 0xFF, 0, 0, 0, 0};

  const bridge::DecodeResult result =
      bindings[STATUS].decodeInto(*f.table, payload, NOW, BMS_ADDRESS, bridge::RangeCheck::Mark);

  const signals::BusValue soc = f.bus("BMS.BMS_Status.Soc");
  CHECK(soc.value == doctest::Approx(127.5));  // the value is kept, only its quality says it
  CHECK(soc.quality == signals::Quality::OutOfRange);
  CHECK(f.bus("BMS.BMS_Status.Spare").quality == signals::Quality::Valid);
  CHECK(result.outOfRange == 1);
}

TEST_CASE("RangeCheck::None writes every value Valid (what this node sent itself)") {
  Fixture f;
  const bridge::DatabaseBinding bindings(f.database, f.catalog);
  const Payload payload{0xFF, 0, 0, 0, 0, 0, 0, 0};

  const bridge::DecodeResult result =
      bindings[STATUS].decodeInto(*f.table, payload, NOW, BMS_ADDRESS, bridge::RangeCheck::None);

  CHECK(f.bus("BMS.BMS_Status.Soc").quality == signals::Quality::Valid);
  CHECK(result.outOfRange == 0);
}

TEST_CASE("a payload shorter than the message writes the signals inside it and counts the rest missing") {
  Fixture f;
  const bridge::DatabaseBinding bindings(f.database, f.catalog);
  const std::array<std::uint8_t, 4> shortPayload{0x10, 0, 0, 0};

  const bridge::DecodeResult result =
      bindings[STATUS].decodeInto(*f.table, shortPayload, NOW, BMS_ADDRESS, bridge::RangeCheck::Mark);

  CHECK(f.bus("BMS.BMS_Status.Soc").value == doctest::Approx(8.0));
  CHECK(f.bus("BMS.BMS_Status.Tail").quality == signals::Quality::NeverReceived);
  CHECK(result.missing == 2);  // NoSlot and Tail
}

TEST_CASE("markBusQuality marks every bound slot of the message") {
  Fixture f;
  const bridge::DatabaseBinding bindings(f.database, f.catalog);
  const Payload payload{0x10, 0, 0, 0, 0, 0, 0, 0};
  (void)bindings[STATUS].decodeInto(*f.table, payload, NOW, BMS_ADDRESS, bridge::RangeCheck::Mark);

  bindings[STATUS].markBusQuality(*f.table, signals::Quality::Stale);

  const signals::BusValue soc = f.bus("BMS.BMS_Status.Soc");
  CHECK(soc.quality == signals::Quality::Stale);
  CHECK(soc.value == doctest::Approx(8.0));
  CHECK(f.bus("BMS.BMS_Status.Tail").quality == signals::Quality::Stale);
}

TEST_CASE("encode from the table round-trips through decode into the table and override wins over command") {
  Fixture f;
  const bridge::DatabaseBinding bindings(f.database, f.catalog);
  const bridge::MessageBinding& sut = bindings[STATUS];
  constexpr signals::WriterId WRITER = 240;
  REQUIRE(f.table->writeCommand(f.index("BMS.BMS_Status.Soc"), 42.5, NOW, WRITER));
  REQUIRE(f.table->writeCommand(f.index("BMS.BMS_Status.Current"), -12.3, NOW, WRITER));
  REQUIRE(f.table->writeCommand(f.index("BMS.BMS_Status.Tail"), 100, NOW, WRITER));
  REQUIRE(f.table->setOverride(f.index("BMS.BMS_Status.Tail"), 4660, NOW, WRITER));
  Payload payload{};
  const auto initial = sut.codec().initialPayload();
  std::copy(initial.begin(), initial.end(), payload.begin());
  payload[3] = 0x5A;  // Spare has no command: its bits stay

  const bridge::EncodeResult encoded = sut.encodeFrom(*f.table, payload);
  (void)sut.decodeInto(*f.table, payload, NOW, BMS_ADDRESS, bridge::RangeCheck::None);

  CHECK(encoded.encoded == 3);
  CHECK(encoded.errors == 0);
  CHECK(f.bus("BMS.BMS_Status.Soc").value == doctest::Approx(42.5));
  CHECK(f.bus("BMS.BMS_Status.Current").value == doctest::Approx(-12.3));
  CHECK(f.bus("BMS.BMS_Status.Tail").value == 4660);
  CHECK(payload[3] == 0x5A);
}

TEST_CASE("encode from values gives the value function each signal slot and counts refused values") {
  Fixture f;
  const bridge::DatabaseBinding bindings(f.database, f.catalog);
  const bridge::MessageBinding& sut = bindings[STATUS];
  std::vector<std::optional<signals::SignalIndex>> seen(sut.signalCount());
  Payload payload{};

  const bridge::EncodeResult result =
      sut.encodeFrom(payload, [&](std::uint32_t signal, std::optional<signals::SignalIndex> slot) {
        seen[signal] = slot;
        return signal == SOC ? std::optional<double>(500.0) : std::optional<double>(1.0);  // 500 %: out of range
      });

  CHECK(seen[SOC] == f.index("BMS.BMS_Status.Soc"));
  CHECK_FALSE(seen[NO_SLOT_SIGNAL]);
  CHECK(result.errors == 1);
  CHECK(result.encoded == 4);
  CHECK(payload[0] == 0);  // the refused value's bits are kept
  CHECK(payload[4] == 1);  // a signal without a slot is still encoded from the value
}

TEST_CASE("a multiplexed message decodes only the active page and never encodes a page signal") {
  Fixture f;
  const bridge::DatabaseBinding bindings(f.database, f.catalog);
  const bridge::MessageBinding& sut = bindings[MUXED];
  REQUIRE(sut.codec().skippedSignals() == std::vector<std::uint32_t>{BAD_FLOAT});
  const Payload page1{0x01, 0x33, 0x44, 0x55, 0x66, 0, 0, 0};

  const bridge::DecodeResult result = sut.decodeInto(*f.table, page1, NOW, BMS_ADDRESS, bridge::RangeCheck::Mark);

  CHECK(result.decoded == 3);  // Sel, PageA, Plain: PageB is not active, BadFloat not decodable
  CHECK(f.bus("BMS.BMS_Mux.Sel").value == 1.0);
  CHECK(f.bus("BMS.BMS_Mux.PageA").value == 0x33);
  CHECK(f.bus("BMS.BMS_Mux.PageB").quality == signals::Quality::NeverReceived);
  CHECK(f.bus("BMS.BMS_Mux.BadFloat").quality == signals::Quality::NeverReceived);
  CHECK(f.bus("BMS.BMS_Mux.Plain").value == 0x66);

  Payload out{};
  std::vector<std::uint32_t> asked;
  const bridge::EncodeResult encoded = sut.encodeFrom(out, [&](std::uint32_t signal, std::optional<signals::SignalIndex>) {
    asked.push_back(signal);
    return std::optional<double>(2.0);
  });
  CHECK(asked == std::vector<std::uint32_t>{SELECTOR, BAD_FLOAT, PLAIN});
  CHECK(encoded.encoded == 2);
  CHECK(encoded.errors == 1);  // BadFloat: NotEncodable, its bits kept
  CHECK(out == Payload{0x02, 0, 0, 0, 0x02, 0, 0, 0});
}

TEST_CASE("values by signal without a table: find, value, decodeValues and encodeClamped") {
  Fixture f;
  const bridge::DatabaseBinding bindings(f.database);
  const auto maybeSoc = bindings.find("BMS_Status", "Soc");
  REQUIRE(maybeSoc);
  CHECK(*maybeSoc == bridge::SignalRef{STATUS, SOC});
  CHECK_FALSE(bindings.find("BMS_Status", "Nope"));
  CHECK_FALSE(bindings.find("Nope", "Soc"));
  const bridge::MessageBinding& sut = bindings[maybeSoc->message];
  CHECK_FALSE(sut.slot(SOC));  // bound without a catalog

  Payload payload{};
  CHECK(sut.encodeClamped(SOC, 250.0, payload) == dbc::EncodeStatus::Ok);  // clamped to 100 %
  CHECK(sut.value(SOC, payload) == doctest::Approx(100.0));
  CHECK(sut.encodeClamped(SOC, std::numeric_limits<double>::quiet_NaN(), payload) == dbc::EncodeStatus::NotEncodable);
  CHECK(sut.value(SOC, payload) == doctest::Approx(100.0));
  CHECK(sut.encodeClamped(SPARE, 300.0, payload) == dbc::EncodeStatus::OutOfRange);  // no range: not clamped
  CHECK_FALSE(sut.value(TAIL, std::span<const std::uint8_t>(payload.data(), 4)));

  std::vector<double> values(sut.signalCount(), std::numeric_limits<double>::quiet_NaN());
  const std::array<std::uint8_t, 4> shortPayload{0xC8, 0x0A, 0x00, 0x03};
  const dbc::DecodeSummary summary = sut.decodeValues(shortPayload, values);
  CHECK(summary.decoded == 3);
  CHECK(values[SOC] == doctest::Approx(100.0));
  CHECK(values[CURRENT] == doctest::Approx(1.0));
  CHECK(values[SPARE] == 3.0);
  CHECK(std::isnan(values[TAIL]));
}
