// /proc readings for `vcu top` and the HMI's service health.
#include <doctest/doctest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <vector>

#include "openvcu/service/process_stats.hpp"

using namespace openvcu;

TEST_CASE("processCpuTicks grows while this process computes, processRssMb sees what it touches") {
  const std::int64_t before = service::processCpuTicks(::getpid());
  REQUIRE(before >= 0);
  const double rssBefore = service::processRssMb(::getpid());
  REQUIRE(rssBefore > 0);
  // 64 MB written so that it is resident; then compute until a clock tick (10 ms) more is
  // counted, giving up after 5 s of wall time (a loaded machine may lend little CPU)
  std::vector<char> block(64'000'000);
  for (std::size_t page = 0; page < block.size(); page += 4096) block[page] = 1;
  volatile std::uint64_t sink = 0;
  const auto giveUp = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (service::processCpuTicks(::getpid()) == before && std::chrono::steady_clock::now() < giveUp) {
    for (std::size_t i = 0; i < 1'000'000; ++i) sink = sink + i * 7919;
  }
  CHECK(service::processCpuTicks(::getpid()) > before);
  CHECK(service::processRssMb(::getpid()) >= rssBefore + 50);
  CHECK(service::clockTicksPerSecond() > 0);
}

TEST_CASE("a process that is gone reads as -1") {
  const pid_t child = ::fork();
  REQUIRE(child >= 0);
  if (child == 0) ::_exit(0);
  int status = 0;
  REQUIRE(::waitpid(child, &status, 0) == child);
  CHECK(service::processCpuTicks(child) == -1);
  CHECK(service::processRssMb(child) == -1);
}
