#include <doctest/doctest.h>

#include <charconv>
#include <cmath>
#include <limits>
#include <string>

#include "openvcu/trace/frame_writer.hpp"

using openvcu::trace::appendCsvField;
using openvcu::trace::appendJsonString;
using openvcu::trace::appendNumber;
using openvcu::trace::appendRaw;
using openvcu::trace::appendSeconds;
using openvcu::dbc::DecodedValue;
using openvcu::dbc::RawKind;

namespace {

constexpr bool JSON = true;
constexpr bool CSV = false;
constexpr double TWO_POW_53 = 9007199254740992.0;

std::string number(double value, bool quoteNonFinite = JSON) {
  std::string out;
  appendNumber(out, value, quoteNonFinite);
  return out;
}

std::string seconds(std::int64_t nanoseconds) {
  std::string out;
  appendSeconds(out, nanoseconds);
  return out;
}

std::string jsonString(std::string_view text) {
  std::string out;
  appendJsonString(out, text);
  return out;
}

std::string csvField(std::string_view text) {
  std::string out;
  appendCsvField(out, text);
  return out;
}

double parsed(const std::string& text) {
  double value = 0;
  std::from_chars(text.data(), text.data() + text.size(), value);
  return value;
}

}  // namespace

TEST_CASE("integral physical values below 2^53 print as integers, like the oracle's jnum") {
  CHECK(number(1250.0) == "1250");
  CHECK(number(-40.0) == "-40");
  CHECK(number(-0.0) == "0");
  CHECK(number(TWO_POW_53 - 1) == "9007199254740991");
}

TEST_CASE("other physical values print as the shortest text that reads back exactly") {
  const double values[] = {0.1, 12.34, -0.3788945312499994, 1e-7, TWO_POW_53, 1e300};
  for (const double value : values) {
    const std::string text = number(value);
    CHECK(parsed(text) == value);
    CHECK(text.find(' ') == std::string::npos);
  }
  CHECK(number(0.1) == "0.1");
}

TEST_CASE("NaN and infinities are strings in JSON and bare words in CSV") {
  constexpr double INF = std::numeric_limits<double>::infinity();

  CHECK(number(std::nan(""), JSON) == "\"nan\"");
  CHECK(number(INF, JSON) == "\"inf\"");
  CHECK(number(-INF, JSON) == "\"-inf\"");
  CHECK(number(std::nan(""), CSV) == "nan");
  CHECK(number(-INF, CSV) == "-inf");
}

TEST_CASE("raw values print exactly: 64-bit integers in full, floats like physical values") {
  DecodedValue unsignedRaw;
  unsignedRaw.kind = RawKind::Unsigned;
  unsignedRaw.rawUnsigned = 18446744073709551615u;
  DecodedValue signedRaw;
  signedRaw.kind = RawKind::Signed;
  signedRaw.rawSigned = -9223372036854775807 - 1;
  DecodedValue floatRaw;
  floatRaw.kind = RawKind::Float32;
  floatRaw.rawFloat = 3.0;
  std::string out;

  appendRaw(out, unsignedRaw, JSON);
  out += ' ';
  appendRaw(out, signedRaw, JSON);
  out += ' ';
  appendRaw(out, floatRaw, JSON);

  CHECK(out == "18446744073709551615 -9223372036854775808 3");
}

TEST_CASE("times print as logged: 6 decimals for microseconds, 9 when there are nanoseconds") {
  CHECK(seconds(1700000000000100000) == "1700000000.000100");
  CHECK(seconds(1000000001) == "1.000000001");
  CHECK(seconds(0) == "0.000000");
  CHECK(seconds(-1500000) == "-0.001500");
}

TEST_CASE("JSON strings escape quotes, backslashes and control characters and keep UTF-8") {
  CHECK(jsonString("EngineSpeed") == "\"EngineSpeed\"");
  CHECK(jsonString("a\"b\\c\n") == "\"a\\\"b\\\\c\\u000a\"");
  CHECK(jsonString("\xC2\xB0"
                   "C") ==
        "\"\xC2\xB0"
        "C\"");
  CHECK(jsonString("\xB0"
                   "C") == "\"\\u00b0C\"");  // not UTF-8: read as Latin-1
}

TEST_CASE("CSV fields are quoted only when they hold a comma, a quote or a line break") {
  CHECK(csvField("can0") == "can0");
  CHECK(csvField("a,b") == "\"a,b\"");
  CHECK(csvField("say \"hi\"") == "\"say \"\"hi\"\"\"");
}
