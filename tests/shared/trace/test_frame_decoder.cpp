// Frames matched to the DBC and decoded into the decoder's buffer; the decoded text.
#include <doctest/doctest.h>

#include "openvcu/trace/frame_decoder.hpp"
#include "trace_test_support.hpp"

using namespace openvcu;
using namespace openvcu::trace;

namespace {

constexpr std::uint32_t OBC_ID = 0x18FF50E5;
constexpr std::uint32_t STATUS_ID = 0x123;
constexpr std::uint32_t VOLTAGE_RAW = 0x2710;  // 10000 * 0.1 V = 1000 V

can::Frame obcFrame() {
  can::Frame frame{};
  frame.id = OBC_ID;
  frame.flags = can::FLAG_EXTENDED;
  frame.length = 8;
  frame.data[0] = 1;
  frame.data[1] = VOLTAGE_RAW & 0xFF;
  frame.data[2] = VOLTAGE_RAW >> 8;
  return frame;
}

}  // namespace

TEST_CASE("the decoder matches a frame to its message and decodes its signals in DBC order") {
  const dbc::Database database = test::smallDatabase();
  FrameDecoder sut(database, dbc::MatchMode::J1939);
  const can::Frame frame = obcFrame();

  const std::int32_t message = sut.match(frame);
  REQUIRE(message >= 0);
  const auto values = sut.decode(frame, message);

  CHECK(database.messages[static_cast<std::size_t>(message)].name == "OBC");
  REQUIRE(values.size() == 2);
  CHECK(values[0].signalIndex == 0);
  CHECK(values[0].value.physical == 1);
  CHECK(values[1].value.physical == doctest::Approx(1000));
}

TEST_CASE("the decoder returns no values for an unknown frame, a bad index and a remote request") {
  const dbc::Database database = test::smallDatabase();
  FrameDecoder sut(database, dbc::MatchMode::Exact);
  can::Frame unknown{};
  unknown.id = 0x7FF;
  CHECK(sut.match(unknown) == FrameDecoder::NO_MATCH);
  CHECK(sut.decode(unknown, FrameDecoder::NO_MATCH).empty());
  CHECK(sut.decode(unknown, 99).empty());
  can::Frame request{};
  request.id = STATUS_ID;
  request.flags = can::FLAG_RTR;
  const std::int32_t message = sut.match(request);
  REQUIRE(message >= 0);
  CHECK(sut.decode(request, message).empty());
}

TEST_CASE("the decoded text names each signal with its value and its unit or value text") {
  const dbc::Database database = test::smallDatabase();
  FrameDecoder sut(database, dbc::MatchMode::J1939);
  const can::Frame frame = obcFrame();
  const std::int32_t message = sut.match(frame);
  REQUIRE(message >= 0);
  std::string text;

  appendDecodedText(text, database.messages[static_cast<std::size_t>(message)], sut.decode(frame, message));

  CHECK(text == "State=1 \"On\"  Voltage=1000 V  ");
}

TEST_CASE("the logged time of an ASC record is its offset, of a candump record its timestamp") {
  can::LogRecord record;
  record.frame.timestampNs = 1'700'000'000'001'234'000;
  record.timeSeconds = 0.001234;
  CHECK(loggedTimeNs(record, can::LogFormat::VectorAsc) == 1'234'000);
  CHECK(loggedTimeNs(record, can::LogFormat::Candump) == 1'700'000'000'001'234'000);
}
