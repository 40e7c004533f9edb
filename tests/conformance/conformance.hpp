#pragma once
// The vocabulary of the canmatrix conformance test: what kind of difference was seen,
// and an entry of the list of known canmatrix faults that explains one.

#include <cstdint>
#include <string_view>

namespace openvcu::conformance {

/// How openvcu's decode of an oracle vector differs from canmatrix's.
enum class DiffKind : std::uint8_t {
  MessageMissing,       ///< the vector names a message openvcu does not have
  MessageOnlyOurs,      ///< openvcu has a (non-pseudo) message canmatrix made no vectors for
  Id,                   ///< same message, another (ID, extended) pair
  Pseudo,               ///< openvcu treats the message as pseudo (never matched), canmatrix as a frame
  SignalOnlyCanmatrix,  ///< canmatrix decoded a signal openvcu did not (inactive, absent or outside the data)
  SignalOnlyOurs,       ///< openvcu decoded a signal canmatrix did not
  Raw,                  ///< raw values differ
  Physical,             ///< raw values agree, physical values differ beyond 1e-9 relative
  Choice,               ///< the VAL_ text for the raw value differs
};

constexpr std::string_view toString(DiffKind kind) noexcept {
  switch (kind) {
    case DiffKind::MessageMissing:
      return "message-missing";
    case DiffKind::MessageOnlyOurs:
      return "message-only-ours";
    case DiffKind::Id:
      return "id";
    case DiffKind::Pseudo:
      return "pseudo";
    case DiffKind::SignalOnlyCanmatrix:
      return "signal-only-canmatrix";
    case DiffKind::SignalOnlyOurs:
      return "signal-only-ours";
    case DiffKind::Raw:
      return "raw";
    case DiffKind::Physical:
      return "physical";
    case DiffKind::Choice:
      return "choice";
  }
  return "?";
}

/// A difference that is canmatrix's fault, with the fault's number in the corpus README
/// ("Where canmatrix itself is wrong", 1..7). `message` and `signal` may be "*" (any);
/// message-level kinds have signal "".
struct KnownFault {
  std::string_view file;     ///< path below corpus/dbc
  std::string_view message;  ///< as the vectors name it (canmatrix's long name)
  std::string_view signal;
  DiffKind kind;
  int fault;
  std::string_view reason;
};

}  // namespace openvcu::conformance
