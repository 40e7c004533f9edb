// cantx::ErrorHistogram: log-linear buckets, so p50 and p99 are percentiles at any size
// (issue 27: a p99 above the old 2 ms range read as the maximum).

#include <doctest/doctest.h>

#include <cstdint>

#include "error_histogram.hpp"

using namespace openvcu;

namespace {

constexpr std::int64_t US = 1'000;
constexpr std::int64_t MS = 1'000'000;
constexpr std::int64_t SECOND = 1'000'000'000;

}  // namespace

TEST_CASE("ErrorHistogram: percentiles in microseconds, exact maximum") {
  cantx::ErrorHistogram sut;
  for (int i = 0; i < 98; ++i) sut.record(10 * US);
  sut.record(-150 * US);  // the sign does not matter
  sut.record(5 * MS);     // in the log buckets
  const auto summary = sut.summary();
  CHECK(summary.count == 100);
  CHECK(summary.p50Us == 10);
  CHECK(summary.p99Us == 150);
  CHECK(summary.maxUs == 5000);
}

TEST_CASE("issue 27: 1000 errors of 5 ms and 10 of 1 us give a p99 of about 5 ms, not the maximum") {
  cantx::ErrorHistogram sut;
  constexpr std::int64_t LARGEST = 9 * MS;
  for (int i = 0; i < 10; ++i) sut.record(1 * US);
  for (int i = 0; i < 1000; ++i) sut.record(5 * MS);
  sut.record(LARGEST);
  const auto summary = sut.summary();
  CHECK(summary.maxUs == 9000);
  CHECK(summary.p99Us >= 5000 - 5000 / 64);
  CHECK(summary.p99Us <= 5000 + 5000 / 64);
  CHECK(summary.p50Us == summary.p99Us);
}

TEST_CASE("issue 27: a maximum of 20 ms beside a p99 of 3 ms reports both") {
  cantx::ErrorHistogram sut;
  for (int i = 0; i < 980; ++i) sut.record(20 * US);
  for (int i = 0; i < 19; ++i) sut.record(3 * MS);
  sut.record(20 * MS);
  const auto summary = sut.summary();
  CHECK(summary.count == 1000);
  CHECK(summary.p50Us == 20);
  CHECK(summary.p99Us >= 3000 - 3000 / 64);
  CHECK(summary.p99Us <= 3000 + 3000 / 64);
  CHECK(summary.maxUs == 20000);
}

TEST_CASE("ErrorHistogram: above 2,048 us a percentile is within 1/64 of the value, never above the maximum") {
  for (const std::int64_t micros : {2'048LL, 2'049LL, 3'333LL, 4'095LL, 4'096LL, 65'000LL, 1'000'000LL, 9'999'999LL,
                                    16'777'215LL}) {
    cantx::ErrorHistogram sut;
    sut.record(micros * US);
    sut.record(micros * US + 999);  // the same microsecond
    const auto summary = sut.summary();
    CAPTURE(micros);
    CHECK(summary.p99Us <= micros);  // the maximum bounds it
    CHECK(summary.p99Us >= micros - micros / 32);
    CHECK(summary.maxUs == micros);
  }
  for (const std::int64_t micros : {2'100LL, 5'000LL, 300'000LL, 7'000'000LL}) {
    const std::size_t bucket = cantx::ErrorHistogram::bucketOf(micros);
    const std::int64_t value = cantx::ErrorHistogram::valueOf(bucket);
    CAPTURE(micros);
    CHECK(value - micros <= micros / 64 + 1);
    CHECK(micros - value <= micros / 64 + 1);
  }
}

TEST_CASE("ErrorHistogram: every microsecond below 2,048 has its own bucket, buckets rise with the value") {
  for (std::int64_t micros = 0; micros < cantx::ErrorHistogram::LINEAR_US; ++micros) {
    REQUIRE(cantx::ErrorHistogram::valueOf(cantx::ErrorHistogram::bucketOf(micros)) == micros);
  }
  std::size_t previous = 0;
  for (std::int64_t micros = 1; micros < cantx::ErrorHistogram::RANGE_US; micros += micros / 7 + 1) {
    const std::size_t bucket = cantx::ErrorHistogram::bucketOf(micros);
    REQUIRE(bucket >= previous);
    REQUIRE(bucket < cantx::ErrorHistogram::BUCKETS - 1);
    previous = bucket;
  }
  CHECK(cantx::ErrorHistogram::bucketOf(cantx::ErrorHistogram::RANGE_US) == cantx::ErrorHistogram::BUCKETS - 1);
}

TEST_CASE("ErrorHistogram: a p99 beyond the 16.8 s range reads as RANGE_US (at least that), the maximum exact") {
  cantx::ErrorHistogram sut;
  for (int i = 0; i < 10; ++i) sut.record(20 * SECOND);
  const auto summary = sut.summary();
  CHECK(summary.p99Us == cantx::ErrorHistogram::RANGE_US);
  CHECK(summary.maxUs == 20'000'000);
}

TEST_CASE("ErrorHistogram: empty, every figure 0") {
  const cantx::ErrorHistogram sut;
  const auto summary = sut.summary();
  CHECK(summary.count == 0);
  CHECK(summary.p50Us == 0);
  CHECK(summary.p99Us == 0);
  CHECK(summary.maxUs == 0);
}
