// The board watchdog feeder against a regular file standing in for /dev/watchdog (the OS
// edge): what it writes per feed, the magic close, no magic character on a crash-like close.

#include <doctest/doctest.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <iterator>
#include <string>

#include "board_watchdog.hpp"

using openvcu::watchdog::BoardWatchdog;

namespace {

/// A fresh empty file in TMPDIR (or /tmp), removed at the end of the case.
struct FakeDevice {
  std::string path;
  FakeDevice() {
    const char* folder = std::getenv("TMPDIR");
    std::string pattern = std::string(folder != nullptr ? folder : "/tmp") + "/openvcu-watchdog-XXXXXX";
    const int fd = ::mkstemp(pattern.data());
    REQUIRE(fd >= 0);
    ::close(fd);
    path = pattern;
  }
  ~FakeDevice() { ::unlink(path.c_str()); }
  [[nodiscard]] std::string written() const {
    std::ifstream file(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>()};
  }
};

}  // namespace

TEST_CASE("each feed writes one keep-alive byte and never the magic character") {
  FakeDevice device;
  auto sut = BoardWatchdog::open(device.path);
  REQUIRE(sut.ok());
  CHECK(sut->feed());
  CHECK(sut->feed());
  CHECK(sut->feed());
  CHECK(sut->feeds() == 3);
  CHECK(device.written() == "111");
  CHECK_FALSE(sut->timeoutSeconds().has_value());  // a plain file has no WDIOC_GETTIMEOUT
}

TEST_CASE("an orderly stop writes the magic character V last and closes") {
  FakeDevice device;
  auto sut = BoardWatchdog::open(device.path);
  REQUIRE(sut.ok());
  REQUIRE(sut->feed());
  CHECK(sut->disarm());
  CHECK(device.written() == "1V");
  CHECK_FALSE(sut->feed());    // closed
  CHECK_FALSE(sut->disarm());  // once
  CHECK(device.written() == "1V");
}

TEST_CASE("a feeder that ends without disarm leaves no magic character: the device keeps running") {
  FakeDevice device;
  {
    auto sut = BoardWatchdog::open(device.path);
    REQUIRE(sut.ok());
    REQUIRE(sut->feed());
  }
  CHECK(device.written() == "1");
}

TEST_CASE("a device that cannot be opened is an error naming it") {
  const auto sut = BoardWatchdog::open("/nonexistent/watchdog0");
  REQUIRE_FALSE(sut.ok());
  CHECK(sut.error().message == "/nonexistent/watchdog0: No such file or directory");
}
