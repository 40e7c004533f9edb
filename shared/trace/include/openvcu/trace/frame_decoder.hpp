#pragma once
// FrameDecoder: a frame -> its DBC message (MessageMatcher) -> its decoded signals
// (DatabaseCodec), into one preallocated value buffer. What `vcu dbc decode`, the HMI's
// trace viewer and its live frame trace decode with.
//
//   FrameDecoder decoder(database, dbc::MatchMode::J1939);
//   const std::int32_t message = decoder.match(frame);          // index or NO_MATCH
//   for (const SignalValue& v : decoder.decode(frame, message)) use(v.signalIndex, v.value);
//
//   decodedText(database.messages[m], values) -> "EngineSpeed=1250.5 rpm  Mode=1 \"On\"  "

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "openvcu/can/frame.hpp"
#include "openvcu/can/log_reader.hpp"
#include "openvcu/dbc/codec.hpp"
#include "openvcu/dbc/matcher.hpp"
#include "openvcu/dbc/model.hpp"
#include "openvcu/trace/frame_writer.hpp"

namespace openvcu::trace {

/// Matches frames to the messages of one database and decodes their signals.
/// The database must outlive the decoder.
/// @note restricted thread-safe: decode() writes the decoder's buffer (one thread per
///       decoder); match() and decode() are noexcept and allocate nothing.
class FrameDecoder {
 public:
  static constexpr std::int32_t NO_MATCH = dbc::MessageMatcher::NO_MATCH;

  FrameDecoder(const dbc::Database& database, dbc::MatchMode mode);

  [[nodiscard]] const dbc::Database& database() const noexcept { return *m_database; }
  [[nodiscard]] const dbc::MessageMatcher& matcher() const noexcept { return m_matcher; }

  /// The index of the frame's message in Database::messages, or NO_MATCH.
  [[nodiscard]] std::int32_t match(const can::Frame& frame) const noexcept {
    return m_matcher.match(frame.id, frame.extended());
  }

  /// The signals of `frame` decoded as message `messageIndex`, in the codec's order; empty
  /// for NO_MATCH, an index out of range and remote requests (they carry no data).
  /// The span stays valid until the next decode().
  [[nodiscard]] std::span<const SignalValue> decode(const can::Frame& frame, std::int32_t messageIndex) noexcept;

 private:
  const dbc::Database* m_database;
  dbc::MessageMatcher m_matcher;
  dbc::DatabaseCodec m_codecs;
  std::vector<SignalValue> m_values;  ///< sized once for the message with the most signals
};

/// The time of a log record as the log writes it: candump's time as is; ASC's offset
/// (timeSeconds, like python-can), not the reader's header date + offset. timeSeconds holds
/// it exactly enough for 104 days.
[[nodiscard]] std::int64_t loggedTimeNs(const can::LogRecord& record, can::LogFormat format) noexcept;

/// Appends "Name=value unit  " per signal (the value text instead of the unit when the
/// signal has one for the raw value: `Mode=1 "On"  `); values with 6 significant digits.
void appendDecodedText(std::string& out, const dbc::Message& message, std::span<const SignalValue> values);

}  // namespace openvcu::trace
