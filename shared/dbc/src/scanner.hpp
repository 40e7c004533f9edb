#pragma once
// Character-level scanner for DBC text, driven by the parser (DBC tokens are
// context-dependent: "64_BIT_LE" is a name, "64" a number, "0-3" a range).
// Skips //-line and /* */ block comments outside strings; tracks positions so errors
// carry line:column.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace openvcu::dbc::detail {

class Scanner {
 public:
  explicit Scanner(std::string_view text);

  /// Skips blanks and comments on the current line only (not the newline).
  void skipBlanks() noexcept;
  /// Skips blanks, comments and newlines.
  void skipSpace() noexcept;
  [[nodiscard]] bool atEnd() const noexcept { return m_pos >= m_text.size(); }
  /// True when only blanks/comments remain on the current line.
  [[nodiscard]] bool atLineEnd() noexcept;
  [[nodiscard]] char peek() const noexcept { return atEnd() ? '\0' : m_text[m_pos]; }
  [[nodiscard]] std::size_t position() const noexcept { return m_pos; }
  void setPosition(std::size_t position) noexcept { m_pos = position; }
  /// Consumes `c` after skipping space (newlines too when `acrossLines`).
  bool accept(char c, bool acrossLines = true) noexcept;

  /// A run of [A-Za-z0-9_] (DBC names may start with a digit). Empty when none.
  std::string_view word() noexcept;
  /// Peeks the next word without consuming it.
  std::string_view peekWord() noexcept;
  /// Decimal (optionally signed, fraction, exponent) or 0x-hex number.
  std::optional<double> number(bool* outOfRange = nullptr) noexcept;
  /// Unsigned decimal integer up to 2^64-1.
  std::optional<std::uint64_t> unsignedInteger() noexcept;
  /// Signed decimal integer.
  std::optional<std::int64_t> signedInteger() noexcept;
  /// Double-quoted string with \" and \\ escapes; may span lines.
  std::optional<std::string> quoted(bool* unterminated = nullptr);

  /// Moves to the start of the next line.
  void skipLine() noexcept;
  /// Is the current position the first non-blank character of its line?
  [[nodiscard]] bool atLineStart() const noexcept;

  /// 1-based line and column of a position.
  [[nodiscard]] std::pair<std::uint32_t, std::uint32_t> lineColumn(std::size_t position) const;

 private:
  bool skipComment() noexcept;

  std::string_view m_text;
  std::size_t m_pos{};
  std::vector<std::size_t> m_lineStarts;
};

}  // namespace openvcu::dbc::detail
