#include "openvcu/j1939/dm1.hpp"
#include "openvcu/j1939/transport.hpp"

#include <doctest/doctest.h>

#include <array>
#include <cstdint>
#include <initializer_list>
#include <vector>

using namespace openvcu::j1939;

namespace {
doctest::String toDoctest(std::string_view name) {
  return {name.data(), static_cast<doctest::String::size_type>(name.size())};
}
}  // namespace

template <>
struct doctest::StringMaker<LampStatus> {
  static doctest::String convert(LampStatus status) { return toDoctest(lampStatusName(status)); }
};
template <>
struct doctest::StringMaker<LampFlash> {
  static doctest::String convert(LampFlash flash) { return toDoctest(lampFlashName(flash)); }
};

namespace {

using Bytes = std::vector<std::uint8_t>;

// Well-known SPNs: 100 engine oil pressure, 110 coolant temperature, 190 engine speed,
// 3226 aftertreatment NOx; 520192 (0x7F000) is the first proprietary SPN and uses all 19 bits.
constexpr std::uint32_t SPN_OIL_PRESSURE = 100;
constexpr std::uint32_t SPN_COOLANT_TEMPERATURE = 110;
constexpr std::uint32_t SPN_ENGINE_SPEED = 190;
constexpr std::uint32_t SPN_NOX = 3226;
constexpr std::uint32_t SPN_PROPRIETARY = 520192;
constexpr std::uint8_t FMI_HIGH = 0;
constexpr std::uint8_t FMI_LOW = 1;
constexpr std::uint8_t FMI_ERRATIC = 2;
constexpr std::uint8_t FMI_BAD_DEVICE = 12;

// Single frame: amber warning lamp on, nothing flashes, SPN 100 FMI 1 OC 3.
constexpr std::array<std::uint8_t, 8> SINGLE_DTC_FRAME{0x04, 0xFF, 0x64, 0x00,
                                                       0x01, 0x03, 0xFF, 0xFF};
// Single frame: lamps off, the "no active DTC" record SPN 0 FMI 0.
constexpr std::array<std::uint8_t, 8> NO_DTC_FRAME{0x00, 0xFF, 0x00, 0x00, 0x00, 0x00, 0xFF, 0xFF};

Dm1 makeDm1(std::initializer_list<Dtc> dtcs) {
  Dm1 dm1;
  for (const Dtc& dtc : dtcs) dm1.dtcs[dm1.dtcCount++] = dtc;
  return dm1;
}

struct DiffRecorder {
  std::vector<Dtc> appeared;
  std::vector<Dtc> disappeared;

  void diff(const Dm1& before, const Dm1& after) {
    diffDtcs(
        before, after, [this](const Dtc& dtc) { appeared.push_back(dtc); },
        [this](const Dtc& dtc) { disappeared.push_back(dtc); });
  }
};

struct CollectingSink final : TpSink {
  std::vector<TpFrame> frames;
  Bytes data;
  std::uint32_t pgn{};
  int completions{};
  void send(const TpFrame& frame) noexcept override { frames.push_back(frame); }
  void completed(const TpMessage& message) noexcept override {
    ++completions;
    pgn = message.pgn;
    data.assign(message.data.begin(), message.data.end());
  }
  void event(const TpEvent&) noexcept override {}
};

}  // namespace

TEST_CASE("single-frame DM1 with one DTC decodes SPN, FMI, occurrence count and lamps") {
  const std::optional<Dm1> maybeSut = decodeDm1(SINGLE_DTC_FRAME);

  REQUIRE(maybeSut);
  CHECK(maybeSut->lamps.amberWarning == LampStatus::On);
  CHECK(maybeSut->lamps.protect == LampStatus::Off);
  CHECK(maybeSut->lamps.redStop == LampStatus::Off);
  CHECK(maybeSut->lamps.malfunction == LampStatus::Off);
  CHECK(maybeSut->lamps.amberWarningFlash == LampFlash::NotFlashing);
  REQUIRE(maybeSut->dtcCount == 1);
  CHECK(maybeSut->dtcs[0] == Dtc{SPN_OIL_PRESSURE, FMI_LOW, 3, false});
}

TEST_CASE("DM1 SPN takes its top three bits from the FMI byte") {
  constexpr std::array<std::uint8_t, 8> FRAME{0x00, 0xFF, 0x00, 0xF0, 0xEC, 0x7F, 0xFF, 0xFF};

  const std::optional<Dm1> maybeSut = decodeDm1(FRAME);

  REQUIRE(maybeSut);
  REQUIRE(maybeSut->dtcCount == 1);
  CHECK(maybeSut->dtcs[0].spn == SPN_PROPRIETARY);  // 0x7F000
  CHECK(maybeSut->dtcs[0].fmi == FMI_BAD_DEVICE);
  CHECK(maybeSut->dtcs[0].occurrenceCount == DTC_MAX_OCCURRENCE_COUNT);
}

TEST_CASE("DM1 with SPN 0 and FMI 0 has no active DTC") {
  const std::optional<Dm1> maybeSut = decodeDm1(NO_DTC_FRAME);

  REQUIRE(maybeSut);
  CHECK(maybeSut->dtcCount == 0);
  CHECK(maybeSut->activeDtcs().empty());
  CHECK(maybeSut->lamps.malfunction == LampStatus::Off);
}

TEST_CASE("DM1 no-DTC record with a non-zero occurrence count or CM is still no DTC") {
  constexpr std::array<std::uint8_t, 8> FRAME{0x00, 0xFF, 0x00, 0x00, 0x00, 0x85, 0xFF, 0xFF};

  const std::optional<Dm1> maybeSut = decodeDm1(FRAME);

  REQUIRE(maybeSut);
  CHECK(maybeSut->dtcCount == 0);
}

TEST_CASE("DM1 lamp bits map to the four lamps and their flash states") {
  // status: malfunction 01 On, red stop 10 Error, amber 11 not available, protect 00 Off
  // flash:  malfunction 00 slow, red stop 01 fast, amber 10 reserved, protect 11 none
  constexpr std::array<std::uint8_t, 8> FRAME{0x6C, 0x1B, 0x00, 0x00, 0x00, 0x00, 0xFF, 0xFF};

  const std::optional<Dm1> maybeSut = decodeDm1(FRAME);

  REQUIRE(maybeSut);
  const LampStates& lamps = maybeSut->lamps;
  CHECK(lamps.malfunction == LampStatus::On);
  CHECK(lamps.redStop == LampStatus::Error);
  CHECK(lamps.amberWarning == LampStatus::NotAvailable);
  CHECK(lamps.protect == LampStatus::Off);
  CHECK(lamps.malfunctionFlash == LampFlash::Slow);
  CHECK(lamps.redStopFlash == LampFlash::Fast);
  CHECK(lamps.amberWarningFlash == LampFlash::Reserved);
  CHECK(lamps.protectFlash == LampFlash::NotFlashing);
}

TEST_CASE("lamp status and flash values have names for logs") {
  CHECK(lampStatusName(LampStatus::Off) == "Off");
  CHECK(lampStatusName(LampStatus::On) == "On");
  CHECK(lampStatusName(LampStatus::Error) == "Error");
  CHECK(lampStatusName(LampStatus::NotAvailable) == "NotAvailable");
  CHECK(lampFlashName(LampFlash::Fast) == "Fast");
  CHECK(lampFlashName(LampFlash::NotFlashing) == "NotFlashing");
}

TEST_CASE("DTC with conversion method 1 keeps the raw SPN and flags it") {
  constexpr std::array<std::uint8_t, 8> FRAME{0x04, 0xFF, 0x64, 0x00, 0x01, 0x83, 0xFF, 0xFF};

  const std::optional<Dm1> maybeSut = decodeDm1(FRAME);

  REQUIRE(maybeSut);
  REQUIRE(maybeSut->dtcCount == 1);
  CHECK(maybeSut->dtcs[0] == Dtc{SPN_OIL_PRESSURE, FMI_LOW, 3, true});
}

TEST_CASE("DM1 skips FF FF FF FF padding records and bytes short of a record") {
  const Bytes padded{0x04, 0xFF, 0x64, 0x00, 0x01, 0x03, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF};

  const std::optional<Dm1> maybeSut = decodeDm1(padded);

  REQUIRE(maybeSut);
  REQUIRE(maybeSut->dtcCount == 1);
  CHECK(maybeSut->dtcs[0].spn == SPN_OIL_PRESSURE);
}

TEST_CASE("DM1 decode refuses fewer than 6 or more than 1785 bytes") {
  const Bytes lampsOnly{0x04, 0xFF};
  const Bytes fiveBytes{0x04, 0xFF, 0x64, 0x00, 0x01};
  const Bytes tooLong(DM1_MAX_LENGTH + 1, 0xFF);

  CHECK_FALSE(decodeDm1({}));
  CHECK_FALSE(decodeDm1(lampsOnly));
  CHECK_FALSE(decodeDm1(fiveBytes));
  CHECK_FALSE(decodeDm1(tooLong));
  CHECK(decodeDm1(std::span<const std::uint8_t>(SINGLE_DTC_FRAME).first(DM1_MIN_LENGTH)));
}

TEST_CASE("DM1 of 1785 bytes holds 445 DTCs and all of them are decoded") {
  Bytes data(DM1_MAX_LENGTH, 0xFF);
  data[0] = 0x04;
  for (std::size_t i = 0; i < DM1_MAX_DTCS; ++i) {
    const std::size_t offset = DM1_LAMP_BYTES + i * DM1_DTC_BYTES;
    data[offset] = static_cast<std::uint8_t>((i + 1) & 0xFF);
    data[offset + 1] = static_cast<std::uint8_t>((i + 1) >> 8);
    data[offset + 2] = FMI_ERRATIC;
    data[offset + 3] = 1;
  }

  const std::optional<Dm1> maybeSut = decodeDm1(data);

  REQUIRE(maybeSut);
  CHECK(DM1_MAX_DTCS == 445);
  REQUIRE(maybeSut->dtcCount == DM1_MAX_DTCS);
  CHECK(maybeSut->dtcs[0] == Dtc{1, FMI_ERRATIC, 1, false});
  CHECK(maybeSut->dtcs[DM1_MAX_DTCS - 1] == Dtc{445, FMI_ERRATIC, 1, false});
}

TEST_CASE("DM1 with four DTCs sent by BAM is reassembled and decoded") {
  constexpr std::uint32_t ENGINE_BAM_CM = 0x1CECFF00;  // from the engine, address 0
  constexpr std::uint32_t ENGINE_BAM_DT = 0x1CEBFF00;
  constexpr std::int64_t MS = 1'000'000;
  // 18 bytes: lamps (malfunction and amber on), 4 DTC records -> 3 packets
  const std::array<std::array<std::uint8_t, 8>, 4> frames{{
      {0x20, 0x12, 0x00, 0x03, 0xFF, 0xCA, 0xFE, 0x00},
      {0x01, 0x44, 0xFF, 0x64, 0x00, 0x01, 0x03, 0x6E},
      {0x02, 0x00, 0x00, 0x01, 0x00, 0xF0, 0xEC, 0x7F},
      {0x03, 0x9A, 0x0C, 0x02, 0x02, 0xFF, 0xFF, 0xFF},
  }};
  TpReceiver receiver({0x21, TP_NO_PACKET_LIMIT, 2, 0});
  CollectingSink sink;
  std::int64_t nowNs = 0;
  receiver.onFrame(ENGINE_BAM_CM, frames[0], nowNs, sink);
  for (std::size_t i = 1; i < frames.size(); ++i) {
    receiver.onFrame(ENGINE_BAM_DT, frames[i], nowNs += 50 * MS, sink);
  }
  REQUIRE(sink.completions == 1);
  REQUIRE(sink.pgn == PGN_DM1);

  const std::optional<Dm1> maybeSut = decodeDm1(sink.data);

  REQUIRE(maybeSut);
  CHECK(maybeSut->lamps.malfunction == LampStatus::On);
  CHECK(maybeSut->lamps.amberWarning == LampStatus::On);
  CHECK(maybeSut->lamps.redStop == LampStatus::Off);
  REQUIRE(maybeSut->dtcCount == 4);
  CHECK(maybeSut->dtcs[0] == Dtc{SPN_OIL_PRESSURE, FMI_LOW, 3, false});
  CHECK(maybeSut->dtcs[1] == Dtc{SPN_COOLANT_TEMPERATURE, FMI_HIGH, 1, false});
  CHECK(maybeSut->dtcs[2] == Dtc{SPN_PROPRIETARY, FMI_BAD_DEVICE, 127, false});
  CHECK(maybeSut->dtcs[3] == Dtc{SPN_NOX, FMI_ERRATIC, 2, false});
  CHECK(maybeSut->contains(SPN_NOX, FMI_ERRATIC));
  CHECK_FALSE(maybeSut->contains(SPN_NOX, FMI_HIGH));
}

TEST_CASE("DTC diff reports codes that appeared and disappeared by SPN and FMI") {
  const Dm1 before = makeDm1({{SPN_OIL_PRESSURE, FMI_LOW, 3, false},
                              {SPN_COOLANT_TEMPERATURE, FMI_HIGH, 1, false},
                              {SPN_NOX, FMI_ERRATIC, 2, false}});
  const Dm1 after = makeDm1({{SPN_COOLANT_TEMPERATURE, FMI_HIGH, 2, false},  // count changed
                             {SPN_NOX, FMI_ERRATIC, 2, false},
                             {SPN_ENGINE_SPEED, FMI_ERRATIC, 1, false}});
  DiffRecorder sut;

  sut.diff(before, after);

  REQUIRE(sut.appeared.size() == 1);
  CHECK(sut.appeared[0] == Dtc{SPN_ENGINE_SPEED, FMI_ERRATIC, 1, false});
  REQUIRE(sut.disappeared.size() == 1);
  CHECK(sut.disappeared[0] == Dtc{SPN_OIL_PRESSURE, FMI_LOW, 3, false});
}

TEST_CASE("DTC diff tells a new FMI of the same SPN apart") {
  const Dm1 before = makeDm1({{SPN_OIL_PRESSURE, FMI_LOW, 1, false}});
  const Dm1 after = makeDm1({{SPN_OIL_PRESSURE, FMI_HIGH, 1, false}});
  DiffRecorder sut;

  sut.diff(before, after);

  REQUIRE(sut.appeared.size() == 1);
  CHECK(sut.appeared[0].fmi == FMI_HIGH);
  REQUIRE(sut.disappeared.size() == 1);
  CHECK(sut.disappeared[0].fmi == FMI_LOW);
}

TEST_CASE("DTC diff of equal sets, or against no-DTC messages, reports what changed only") {
  const Dm1 none = *decodeDm1(NO_DTC_FRAME);
  const Dm1 one = *decodeDm1(SINGLE_DTC_FRAME);

  DiffRecorder same;
  same.diff(one, one);
  CHECK(same.appeared.empty());
  CHECK(same.disappeared.empty());

  DiffRecorder raised;
  raised.diff(none, one);
  CHECK(raised.appeared.size() == 1);
  CHECK(raised.disappeared.empty());

  DiffRecorder cleared;
  cleared.diff(one, none);
  CHECK(cleared.appeared.empty());
  CHECK(cleared.disappeared.size() == 1);
}

TEST_CASE("DTC diff reports a code repeated within one message once") {
  const Dm1 before = makeDm1({});
  const Dm1 after = makeDm1({{SPN_NOX, FMI_ERRATIC, 1, false}, {SPN_NOX, FMI_ERRATIC, 2, false}});
  DiffRecorder sut;

  sut.diff(before, after);

  CHECK(sut.appeared.size() == 1);
}
