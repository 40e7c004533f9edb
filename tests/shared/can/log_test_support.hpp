#pragma once
// Test helpers: read a whole log into owned records (LogRecord::channel is only valid
// until the next next(), so the helpers copy it).

#include <doctest/doctest.h>

#include <cstdint>
#include <sstream>
#include <string>
#include <vector>

#include "openvcu/can/log_reader.hpp"

namespace openvcu::can::test {

struct OwnedRecord {
  Frame frame{};
  std::string channel;
  double timeSeconds{};
  bool hasTime{};
  std::uint64_t line{};
  char direction{};
};

struct ReadResult {
  std::vector<OwnedRecord> records;
  std::vector<Error> errors;  ///< every error, in order, from the error handler
  std::uint64_t errorCount{};
  std::uint64_t lineCount{};
  LogFormat format{LogFormat::Auto};
};

inline ReadResult readAll(LogReader& sut) {
  ReadResult result;
  sut.setErrorHandler([&result](const Error& error) { result.errors.push_back(error); });
  while (auto maybeRecord = sut.next()) {
    result.records.push_back(OwnedRecord{maybeRecord->frame, std::string(maybeRecord->channel),
                                         maybeRecord->timeSeconds, maybeRecord->hasTime, maybeRecord->line,
                                         maybeRecord->direction});
  }
  result.errorCount = sut.errorCount();
  result.lineCount = sut.lineCount();
  result.format = sut.format();
  return result;
}

inline ReadResult readText(const std::string& text, LogFormat format = LogFormat::Auto) {
  std::istringstream input(text);
  LogReader sut(input, "test.log", format);
  return readAll(sut);
}

/// The log fixtures (tests/data/logs/).
inline const std::string LOG_FIXTURE_DIR = OPENVCU_SOURCE_DIR "/tests/data/logs/";

/// Reads the whole fixture `name`; fails the test when it does not open.
inline ReadResult readFixture(const std::string& name) {
  auto openResult = LogReader::open(LOG_FIXTURE_DIR + name);
  REQUIRE(openResult.ok());
  return readAll(*openResult);
}

inline std::vector<std::uint8_t> payloadOf(const Frame& frame) {
  return {frame.data.begin(), frame.data.begin() + frame.length};
}

}  // namespace openvcu::can::test
