// Direct tests of shared/core's text helpers (issue 20: they were tested only through their users).

#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "openvcu/core/clock.hpp"
#include "openvcu/core/text.hpp"

namespace text = openvcu::text;
namespace clock_ = openvcu::clock;

TEST_CASE("the edit distance counts insertions, deletions and substitutions") {
  CHECK(text::editDistance("", "") == 0);
  CHECK(text::editDistance("kitten", "sitting") == 3);
  CHECK(text::editDistance("abc", "") == 3);
  CHECK(text::editDistance("SOC", "soc") == 3);  // case-sensitive
}

TEST_CASE("did-you-mean proposes the closest candidate only when it is a plausible typo") {
  const std::vector<std::string> candidates = {"HS_HiUBusCnctnSts", "HS_FastUpdSOC", "Start"};

  CHECK(text::didYouMean("HS_HiUBusCnctSts", candidates) == std::optional<std::string>("HS_HiUBusCnctnSts"));
  CHECK(text::didYouMean("Strat", candidates) == std::optional<std::string>("Start"));
  CHECK_FALSE(text::didYouMean("CompletelyDifferent", candidates).has_value());
  CHECK_FALSE(text::didYouMean("x", std::vector<std::string>{}).has_value());
}

TEST_CASE("UTF-8 is validated and Windows-1252 text is converted to it") {
  CHECK(text::isValidUtf8("plain ascii"));
  CHECK(text::isValidUtf8("\xC3\xA9t\xC3\xA9"));  // "été"
  CHECK_FALSE(text::isValidUtf8("\xC3"));          // cut after the lead byte
  CHECK_FALSE(text::isValidUtf8("\xE9t\xE9"));     // Latin-1 "été"
  CHECK(text::cp1252ToUtf8("\xE9t\xE9") == "\xC3\xA9t\xC3\xA9");
  CHECK(text::cp1252ToUtf8("\x80") == "\xE2\x82\xAC");  // the euro sign
  CHECK(text::cp1252ToUtf8("ascii") == "ascii");
}

TEST_CASE("a glob matches with * and ? over the whole text") {
  CHECK(text::globMatch("VIC.*SOC*", "VIC.HVESSD2_PGN61585.HS_FastUpdSOC"));
  CHECK(text::globMatch("internal.operator.?tart", "internal.operator.Start"));
  CHECK(text::globMatch("*", ""));
  CHECK_FALSE(text::globMatch("VIC.*", "BMS.Status.SOC"));
  CHECK_FALSE(text::globMatch("Start", "Start2"));
}

TEST_CASE("a number reads as its shortest round-trip text") {
  CHECK(text::number(0.1) == "0.1");
  CHECK(text::number(3'600'000) == "3600000");
  CHECK(text::number(-12345.5) == "-12345.5");
  CHECK(text::number(1.8e19) == "1.8e+19");
  CHECK(text::number(0) == "0");
  CHECK(text::number(std::numeric_limits<double>::infinity()) == "inf");
  CHECK(std::stod(text::number(2.0 / 3.0)) == 2.0 / 3.0);
}

TEST_CASE("the monotonic clock never goes back and the realtime clock is past 2020") {
  const std::int64_t first = clock_::monotonicNs();
  const std::int64_t second = clock_::monotonicNs();
  constexpr std::int64_t YEAR_2020_NS = 1'577'836'800LL * 1'000'000'000;

  CHECK(second >= first);
  CHECK(clock_::realtimeNs() > YEAR_2020_NS);
}

TEST_CASE("a code point is appended as UTF-8 of one to four bytes") {
  std::string out;
  text::appendUtf8(out, 'A');
  text::appendUtf8(out, 0xE9);     // é
  text::appendUtf8(out, 0x20AC);   // €
  text::appendUtf8(out, 0x1F600);  // an emoji, outside the BMP
  CHECK(out == "A\xC3\xA9\xE2\x82\xAC\xF0\x9F\x98\x80");
  CHECK(text::isValidUtf8(out));
}
