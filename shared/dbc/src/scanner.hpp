#pragma once
// Character-level scanner for DBC text, driven by the parser (DBC tokens are
// context-dependent: "64_BIT_LE" is a name, "64" a number, "0-3" a range).
// Skips //-line and /* */ block comments outside strings; tracks positions so errors
// carry line:column. Expects LF line ends (parse() turns CRLF and CR-only into LF).
//
// Text that would swallow the rest of the file is a problem, kept for the parser to
// report as an error at its opening (takeProblems()):
//   CM_ SG_ 100 S "cut here          -> "string never closed" at the '"' (end of file)
//   CM_ SG_ 100 S "cut here          -> "string not closed before line 2, which starts a
//   BA_ "GenMsgCycleTime" BO_ 100 10;    BA_ statement" at the '"'
//   /* stray                         -> "comment '/*' never closed"; the comment then
//                                       ends with its line

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace openvcu::dbc::detail {

/// Is `word` a DBC statement keyword (BO_, SG_, CM_, BA_DEF_, VAL_ ... and the ones only
/// listed in NS_)?
[[nodiscard]] bool isStatementKeyword(std::string_view word) noexcept;

class Scanner {
 public:
  explicit Scanner(std::string_view text);

  /// Skips blanks and comments on the current line only (not the newline).
  void skipBlanks();
  /// Skips blanks, comments and newlines.
  void skipSpace();
  [[nodiscard]] bool atEnd() const noexcept { return m_pos >= m_text.size(); }
  /// True when only blanks/comments remain on the current line.
  [[nodiscard]] bool atLineEnd();
  [[nodiscard]] char peek() const noexcept { return atEnd() ? '\0' : m_text[m_pos]; }
  [[nodiscard]] std::size_t position() const noexcept { return m_pos; }
  void setPosition(std::size_t position) noexcept { m_pos = position; }
  /// Consumes `c` after skipping space (newlines too when `acrossLines`).
  bool accept(char c, bool acrossLines = true);

  /// A run of [A-Za-z0-9_] (DBC names may start with a digit). Empty when none.
  std::string_view word() noexcept;
  /// Peeks the next word without consuming it.
  std::string_view peekWord();
  /// Decimal (optionally signed, fraction, exponent) or 0x-hex number.
  std::optional<double> number(bool* outOfRange = nullptr) noexcept;
  /// Unsigned decimal integer up to 2^64-1.
  std::optional<std::uint64_t> unsignedInteger() noexcept;
  /// Signed decimal integer.
  std::optional<std::int64_t> signedInteger() noexcept;
  /// Double-quoted string with \" and \\ escapes; may span lines, but not into a line
  /// that starts with a statement keyword: that string, or one open at the end of the
  /// file, is unterminated (nullopt, *unterminated set, a problem kept, position unchanged).
  std::optional<std::string> quoted(bool* unterminated = nullptr);

  /// A stretch of text the scanner could not make sense of (see the top of this file).
  struct Problem {
    std::size_t position{};
    std::string message;
  };
  /// The problems found since the last call, each position once.
  std::vector<Problem> takeProblems();

  /// Moves to the start of the next line.
  void skipLine() noexcept;
  /// Is the current position the first non-blank character of its line?
  [[nodiscard]] bool atLineStart() const noexcept;

  /// 1-based line and column of a position.
  [[nodiscard]] std::pair<std::uint32_t, std::uint32_t> lineColumn(std::size_t position) const;

 private:
  bool skipComment();
  /// Does the line starting at `lineStart` begin (after blanks) with a statement keyword?
  [[nodiscard]] bool startsStatement(std::size_t lineStart) const noexcept;
  void addProblem(std::size_t position, std::string message);

  std::string_view m_text;
  std::size_t m_pos{};
  std::vector<std::size_t> m_lineStarts;
  std::vector<Problem> m_problems;
  std::vector<std::size_t> m_reported;  // positions of problems already kept (sorted)
};

}  // namespace openvcu::dbc::detail
