// The input-file rule (issue 19): regular files only, a size limit per kind, a pending
// SIGTERM ends a read. Every input is made by the test.

#include <doctest/doctest.h>
#include <sys/stat.h>

#include <chrono>
#include <fstream>
#include <string>

#include "openvcu/core/input_file.hpp"
#include "openvcu/core/text.hpp"
#include "pending_signal.hpp"
#include "temp_folder.hpp"

using namespace openvcu;

namespace {

constexpr input::FileKind SMALL_KIND{"test file", 16};

/// The error of a refused read, "" when the read succeeded.
std::string refusal(const Result<std::string>& readResult) {
  return readResult ? std::string{} : readResult.error().toString();
}

}  // namespace

TEST_CASE("a regular file within the limit is read whole") {
  const test::TempFolder folder;
  const std::string path = folder.write("ok.txt", "0123456789");

  const Result<std::string> sut = input::readWholeFile(path, SMALL_KIND);

  REQUIRE(sut.ok());
  CHECK(*sut == "0123456789");
}

TEST_CASE("a directory is refused as not a regular file, naming the path (#19)") {
  const test::TempFolder folder;
  const std::string path = folder.path("");

  const Result<std::string> sut = input::readWholeFile(path, input::DBC_FILE);

  CHECK(refusal(sut) == path + ": not a regular file (directory)");
}

TEST_CASE("/dev/zero is refused at once as a character device, nothing read (#19)") {
  const auto started = std::chrono::steady_clock::now();

  const Result<std::string> sut = input::readWholeFile("/dev/zero", input::DBC_FILE);

  CHECK(refusal(sut) == "/dev/zero: not a regular file (character device)");
  CHECK(std::chrono::steady_clock::now() - started < std::chrono::seconds(1));
}

TEST_CASE("a FIFO without a writer is refused without waiting for one (#19)") {
  const test::TempFolder folder;
  const std::string path = folder.path("fifo");
  REQUIRE(::mkfifo(path.c_str(), 0600) == 0);

  const Result<input::InputFile> sut = input::InputFile::open(path, input::CAN_LOG);

  REQUIRE_FALSE(sut.ok());
  CHECK(sut.error().toString() == path + ": not a regular file (FIFO)");
}

TEST_CASE("a missing file is refused with the OS reason") {
  const test::TempFolder folder;
  const std::string path = folder.path("missing.dbc");

  CHECK(refusal(input::readWholeFile(path, input::DBC_FILE)) == path + ": cannot open: No such file or directory");
}

TEST_CASE("a file over its kind's limit is refused with the size and the limit (#19)") {
  const test::TempFolder folder;
  const std::string path = folder.write("big.txt", std::string(17, 'x'));

  CHECK(refusal(input::readWholeFile(path, SMALL_KIND)) ==
        path + ": too large: 17 bytes (a test file may have at most 16 bytes)");
}

TEST_CASE("a file that grows past the limit after it was opened is refused while reading (#19)") {
  const test::TempFolder folder;
  const std::string path = folder.write("growing.txt", "0123456789");
  Result<input::InputFile> sut = input::InputFile::open(path, SMALL_KIND);
  REQUIRE(sut.ok());
  std::ofstream(path, std::ios::app) << std::string(20, 'y');

  char buffer[64];
  input::InputFile::ReadOutcome outcome = sut->read(buffer);
  while (outcome.status == input::InputFile::ReadStatus::Data) outcome = sut->read(buffer);

  CHECK(outcome.status == input::InputFile::ReadStatus::TooLarge);
  CHECK(sut->describe(outcome).toString() == path + ": too large: more than 16 bytes (a test file may have at most 16 bytes)");
}

TEST_CASE("a pending SIGTERM ends a read with an error that says so (#19)") {
  const test::TempFolder folder;
  const std::string path = folder.write("slow.txt", std::string(4096, 'z'));
  const test::PendingSigterm pending;

  REQUIRE(input::stopSignalPending());
  CHECK(refusal(input::readWholeFile(path, input::DBC_FILE)) == path + ": reading stopped: SIGTERM is pending");
}

TEST_CASE("no stop signal is pending in a plain test process") {
  CHECK_FALSE(input::stopSignalPending());
}

TEST_CASE("text::readFile follows the same rule: a directory is refused, not read as empty (#19)") {
  const test::TempFolder folder;
  std::string reason;

  const auto sut = text::readFile(folder.path(""), &reason);

  CHECK_FALSE(sut.has_value());
  CHECK(reason == "not a regular file (directory)");
}

TEST_CASE("limits are stated per kind") {
  CHECK(input::DBC_FILE.maxBytes == 64ull * 1024 * 1024);
  CHECK(input::CAN_LOG.maxBytes == 64ull * 1024 * 1024 * 1024);
  CHECK(input::TEXT_FILE.maxBytes == 64ull * 1024 * 1024);
}
