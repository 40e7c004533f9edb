// Service logging: the line format, the level threshold, journal style, and the rate limit.

#include <doctest/doctest.h>
#include <unistd.h>

#include <cstdio>
#include <string>

#include "openvcu/service/logger.hpp"

namespace ipc = openvcu::ipc;
namespace service = openvcu::service;

namespace {

constexpr std::int64_t SECOND_NS = 1'000'000'000;

/// A FILE* writing into memory (open_memstream); text() after the logger wrote.
class MemoryStream {
 public:
  MemoryStream() : m_file(::open_memstream(&m_buffer, &m_size)) { REQUIRE(m_file != nullptr); }
  MemoryStream(const MemoryStream&) = delete;
  MemoryStream& operator=(const MemoryStream&) = delete;
  ~MemoryStream() {
    std::fclose(m_file);
    std::free(m_buffer);
  }
  std::FILE* file() { return m_file; }
  std::string text() {
    std::fflush(m_file);
    return std::string(m_buffer, m_size);
  }

 private:
  char* m_buffer{nullptr};
  std::size_t m_size{0};
  std::FILE* m_file;
};

}  // namespace

TEST_CASE("the rate limiter passes a burst, then drops until time refills it") {
  constexpr std::uint32_t BURST = 3;
  service::RateLimiter sut(1.0, BURST);  // one line per second after the burst

  CHECK(sut.allow(0));
  CHECK(sut.allow(0));
  CHECK(sut.allow(0));
  CHECK_FALSE(sut.allow(0));
  CHECK_FALSE(sut.allow(SECOND_NS / 2));
  CHECK(sut.allow(SECOND_NS + SECOND_NS / 10));
  CHECK_FALSE(sut.allow(SECOND_NS + SECOND_NS / 5));
}

TEST_CASE("the rate limiter never saves up more than its burst") {
  constexpr std::uint32_t BURST = 2;
  service::RateLimiter sut(100.0, BURST);
  CHECK(sut.allow(0));

  const std::int64_t muchLater = 3600 * SECOND_NS;
  CHECK(sut.allow(muchLater));
  CHECK(sut.allow(muchLater));
  CHECK_FALSE(sut.allow(muchLater));
}

TEST_CASE("a log line carries the UTC time, the level, the program and pid, and the text") {
  MemoryStream stream;
  service::Logger sut("vcu-demo", {}, stream.file());

  sut.info("ready (instance itest)");

  const std::string line = stream.text();
  const std::string expectedTail = " info vcu-demo[" + std::to_string(::getpid()) + "]: ready (instance itest)\n";
  REQUIRE(line.size() > expectedTail.size());
  CHECK(line.substr(line.size() - expectedTail.size()) == expectedTail);
  CHECK(line[4] == '-');
  CHECK(line[23] == 'Z');  // 2026-11-21T06:00:00.123Z
}

TEST_CASE("lines below the threshold are not logged") {
  MemoryStream stream;
  service::Logger sut("vcu-demo", {.threshold = ipc::LogLevel::Warning}, stream.file());

  sut.info("not shown");
  sut.debug("not shown either");
  sut.error("shown");

  CHECK(stream.text().find("not shown") == std::string::npos);
  CHECK(stream.text().find("error vcu-demo") != std::string::npos);
  CHECK_FALSE(sut.enabled(ipc::LogLevel::Info));
  CHECK(sut.enabled(ipc::LogLevel::Critical));
}

TEST_CASE("journal format writes the syslog priority and the text only") {
  MemoryStream stream;
  service::Logger sut("vcu-demo", {.journalFormat = true}, stream.file());

  sut.warning("bus vehicle: bus-off");
  sut.info("recovered");

  CHECK(stream.text() == "<4>bus vehicle: bus-off\n<6>recovered\n");
}

TEST_CASE("newlines in a message cannot forge extra log lines") {
  MemoryStream stream;
  service::Logger sut("vcu-demo", {.journalFormat = true}, stream.file());

  sut.info("first\nfake line");

  CHECK(stream.text() == "<6>first fake line\n");
}

TEST_CASE("lines over the rate limit are dropped, counted, and reported by the next line that passes") {
  MemoryStream stream;
  constexpr std::uint32_t BURST = 2;
  service::Logger sut("vcu-demo", {.ratePerSecond = 0.0, .burst = BURST, .journalFormat = true}, stream.file());

  for (int i = 0; i < 5; ++i) sut.info("storm " + std::to_string(i));

  CHECK(stream.text() == "<6>storm 0\n<6>storm 1\n");
  CHECK(sut.suppressed() == 3);
}

TEST_CASE("UTC times print with milliseconds") {
  CHECK(service::formatUtc(0) == "1970-01-01T00:00:00.000Z");
  CHECK(service::formatUtc(1'700'000'000'123'456'789) == "2023-11-14T22:13:20.123Z");
}
