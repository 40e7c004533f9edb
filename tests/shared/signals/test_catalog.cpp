#include <doctest/doctest.h>

#include <string>
#include <vector>

#include "openvcu/signals/catalog.hpp"
#include "signals_test_support.hpp"

using namespace openvcu::signals;
using openvcu::signals::testing::makeCatalog;

namespace {

const std::string SOC_KEY = "VIC.HVESSD2_PGN61585.HS_FastUpdSOC";
const std::string VOLTAGE_KEY = "VIC.HVESSD1_PGN61584.HS_Voltage";
const std::string START_KEY = "internal.operator.start";

SignalInfo info(std::string key, SignalKind kind = SignalKind::Bus) {
  SignalInfo result;
  result.key = std::move(key);
  result.kind = kind;
  return result;
}

}  // namespace

TEST_CASE("catalog keeps the configuration order and finds every key") {
  const Catalog sut = makeCatalog({SOC_KEY, VOLTAGE_KEY, START_KEY});

  REQUIRE(sut.size() == 3);
  CHECK(sut[0].key == SOC_KEY);
  CHECK(sut[1].key == VOLTAGE_KEY);
  CHECK(sut[2].key == START_KEY);
  CHECK(sut.indexOf(VOLTAGE_KEY) == 1u);
  const auto findResult = sut.find(START_KEY);
  REQUIRE(findResult.ok());
  CHECK(*findResult == 2u);
  CHECK_FALSE(sut.indexOf("VIC.nothing").has_value());
}

TEST_CASE("catalog keeps the metadata of each signal") {
  const SignalInfo soc{.key = SOC_KEY,
                       .unit = "%",
                       .minimum = 0,
                       .maximum = 100,
                       .comment = "state of charge",
                       .message = "HVESSD2_PGN61585",
                       .bus = "vehicle",
                       .kind = SignalKind::Bus,
                       .valueTexts = {{0, "Empty"}, {100, "Full"}}};
  auto catalogResult = Catalog::create({soc, info(START_KEY, SignalKind::Internal)});
  REQUIRE(catalogResult.ok());

  const Catalog& sut = *catalogResult;

  CHECK(sut[0].unit == "%");
  CHECK(sut[0].maximum == 100);
  CHECK(sut[0].bus == "vehicle");
  CHECK(sut[0].valueTexts.size() == 2);
  CHECK(sut[1].kind == SignalKind::Internal);
  CHECK(signalKindName(sut[1].kind) == "Internal");
}

TEST_CASE("catalog refuses a duplicate key and names both signals") {
  const auto catalogResult = Catalog::create({info(SOC_KEY), info(START_KEY), info(SOC_KEY)});

  REQUIRE_FALSE(catalogResult.ok());
  CHECK(catalogResult.error().message == "duplicate signal key '" + SOC_KEY + "' (signals 0 and 2)");
}

TEST_CASE("catalog refuses an empty key") {
  const auto catalogResult = Catalog::create({info(SOC_KEY), info("")});

  REQUIRE_FALSE(catalogResult.ok());
  CHECK(catalogResult.error().message == "signal 1 has an empty key");
}

TEST_CASE("find suggests the closest key for a typo") {
  const Catalog sut = makeCatalog({SOC_KEY, VOLTAGE_KEY, START_KEY});

  const auto findResult = sut.find("VIC.HVESSD2_PGN61585.HS_FastUpdSoc");

  REQUIRE_FALSE(findResult.ok());
  CHECK(findResult.error().message ==
        "unknown signal 'VIC.HVESSD2_PGN61585.HS_FastUpdSoc' (did you mean '" + SOC_KEY + "'?)");
}

TEST_CASE("find suggests the full key for a signal name given without its message") {
  const Catalog sut = makeCatalog({SOC_KEY, VOLTAGE_KEY, START_KEY});

  CHECK(sut.suggest("HS_FastUpdSOC") == SOC_KEY);
  CHECK(sut.suggest("start") == START_KEY);
}

TEST_CASE("find gives no suggestion when nothing is close or the short name is ambiguous") {
  const Catalog sut = makeCatalog({"A.M1.Voltage", "B.M2.Voltage", START_KEY});

  const auto findResult = sut.find("completely.different.thing");

  REQUIRE_FALSE(findResult.ok());
  CHECK(findResult.error().message == "unknown signal 'completely.different.thing'");
  CHECK_FALSE(sut.suggest("Voltage").has_value());
}

TEST_CASE("layout hash is deterministic and pinned") {
  const Catalog first = makeCatalog({SOC_KEY, START_KEY});
  const Catalog second = makeCatalog({SOC_KEY, START_KEY});
  const Catalog empty;

  CHECK(first.layoutHash() == second.layoutHash());
  // Pinned so that a change of the hash function (which would make two builds of the same
  // format version disagree) cannot go unnoticed.
  CHECK(empty.layoutHash() == computeLayoutHash({}));
  CHECK(computeLayoutHash({}) == 0x280bc297682f8620ULL);  // format version 2
}

TEST_CASE("layout hash changes when a key, a kind, the order or the count changes") {
  const Catalog sut = makeCatalog({SOC_KEY, VOLTAGE_KEY});

  CHECK(sut.layoutHash() != makeCatalog({SOC_KEY, VOLTAGE_KEY + "x"}).layoutHash());
  CHECK(sut.layoutHash() != makeCatalog({SOC_KEY, VOLTAGE_KEY}, SignalKind::Internal).layoutHash());
  CHECK(sut.layoutHash() != makeCatalog({VOLTAGE_KEY, SOC_KEY}).layoutHash());
  CHECK(sut.layoutHash() != makeCatalog({SOC_KEY}).layoutHash());
  CHECK(makeCatalog({"ab", "c"}).layoutHash() != makeCatalog({"a", "bc"}).layoutHash());
}

TEST_CASE("layout hash ignores metadata that does not shape the table") {
  const SignalInfo withMetadata{.key = SOC_KEY,
                                .unit = "%",
                                .minimum = 0,
                                .maximum = 100,
                                .comment = "state of charge",
                                .message = "HVESSD2_PGN61585",
                                .bus = "vehicle",
                                .kind = SignalKind::Bus,
                                .valueTexts = {}};
  auto catalogResult = Catalog::create({withMetadata});
  REQUIRE(catalogResult.ok());

  CHECK(catalogResult->layoutHash() == makeCatalog({SOC_KEY}).layoutHash());
}

TEST_CASE("a copied catalog finds keys on its own") {
  Catalog copy;
  {
    const Catalog original = makeCatalog({SOC_KEY, START_KEY});
    copy = original;
  }

  CHECK(copy.indexOf(START_KEY) == 1u);
  CHECK(copy.layoutHash() == makeCatalog({SOC_KEY, START_KEY}).layoutHash());
}
