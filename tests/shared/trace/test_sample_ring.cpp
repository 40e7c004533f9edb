// The sample ring and its per-column decimation (the live plot and the trace timeline).
#include <doctest/doctest.h>

#include <vector>

#include "openvcu/trace/sample_ring.hpp"

using namespace openvcu::trace;

namespace {
constexpr std::size_t FOUR_SAMPLES = 4;
constexpr std::size_t TWO_COLUMNS = 2;
}  // namespace

TEST_CASE("the sample ring drops the oldest sample and decimation gives one min/max per pixel column") {
  SampleRing sut(FOUR_SAMPLES);
  for (int i = 0; i < 6; ++i) sut.push(i, i * 10);
  REQUIRE(sut.size() == FOUR_SAMPLES);
  CHECK(sut.time(0) == 2);
  CHECK(sut.value(3) == 50);
  std::vector<float> out(TWO_COLUMNS * 3);
  const std::size_t columns = decimate(sut, 2, 6, TWO_COLUMNS, out);  // [2,4) and [4,6)
  REQUIRE(columns == TWO_COLUMNS);
  CHECK(out[0] == 0);
  CHECK(out[1] == 20);
  CHECK(out[2] == 30);
  CHECK(out[3] == 1);
  CHECK(out[4] == 40);
  CHECK(out[5] == 50);
  std::vector<float> tooSmall(1);
  CHECK(decimate(sut, 2, 6, TWO_COLUMNS, tooSmall) == 0);
}

TEST_CASE("decimation skips columns without samples and ignores samples outside the window") {
  SampleRing sut(FOUR_SAMPLES);
  sut.push(0, 7);    // before the window
  sut.push(1, 1);    // column 0 of [1, 5)
  sut.push(4.5, 9);  // column 3
  sut.push(5, 100);  // at the end: outside
  std::vector<float> out(4 * 3);
  const std::size_t filled = decimate(sut, 1, 5, 4, out);
  REQUIRE(filled == 2);
  CHECK(out[0] == 0);
  CHECK(out[1] == 1);
  CHECK(out[3] == 3);
  CHECK(out[5] == 9);
  CHECK(decimate(sut, 5, 1, 4, out) == 0);  // an empty window
}

TEST_CASE("a ring of capacity 0 keeps nothing and has no range") {
  SampleRing sut;
  sut.push(1, 1);
  CHECK(sut.size() == 0);
  CHECK_FALSE(valueRange(sut).has_value());
  CHECK_FALSE(sampleAtOrBefore(sut, 1).has_value());
}

TEST_CASE("the value range spans every sample and the cursor finds the sample at or before a time") {
  SampleRing sut(FOUR_SAMPLES);
  sut.push(1, 5);
  sut.push(2, -3);
  sut.push(3, 8);
  const auto range = valueRange(sut);
  REQUIRE(range.has_value());
  CHECK(range->low == -3);
  CHECK(range->high == 8);
  CHECK(sampleAtOrBefore(sut, 2.5) == 1u);
  CHECK(sampleAtOrBefore(sut, 3) == 2u);
  CHECK(sampleAtOrBefore(sut, 0) == 0u);  // before every sample: the oldest
}
