#include "scanner.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <limits>

namespace openvcu::dbc::detail {

namespace {
bool isBlank(char c) noexcept { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }
bool isWordChar(char c) noexcept {
  return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_';
}
bool isDigit(char c) noexcept { return c >= '0' && c <= '9'; }

/// Every keyword that may start a statement (the ones only listed inside NS_ too).
constexpr std::array<std::string_view, 35> KEYWORDS = {
    "VERSION",        "NS_",          "BS_",           "BU_",          "VAL_TABLE_",
    "BO_",            "SG_",          "BO_TX_BU_",     "CM_",          "BA_DEF_",
    "BA_DEF_DEF_",    "BA_",          "BA_DEF_REL_",   "BA_DEF_DEF_REL_", "BA_REL_",
    "VAL_",           "SIG_VALTYPE_", "SIG_GROUP_",    "EV_",          "ENVVAR_DATA_",
    "SG_MUL_VAL_",    "NS_DESC_",     "CAT_DEF_",      "CAT_",         "FILTER",
    "EV_DATA_",       "SGTYPE_",      "SGTYPE_VAL_",   "SIG_TYPE_REF_", "SIGTYPE_VALTYPE_",
    "BA_DEF_SGTYPE_", "BA_SGTYPE_",   "BU_SG_REL_",    "BU_EV_REL_",   "BU_BO_REL_"};
}  // namespace

bool isStatementKeyword(std::string_view word) noexcept {
  return std::find(KEYWORDS.begin(), KEYWORDS.end(), word) != KEYWORDS.end();
}

void Scanner::addProblem(std::size_t position, std::string message) {
  const auto it = std::lower_bound(m_reported.begin(), m_reported.end(), position);
  if (it != m_reported.end() && *it == position) return;  // the parser looked at it twice
  m_reported.insert(it, position);
  m_problems.push_back(Problem{position, std::move(message)});
}

std::vector<Scanner::Problem> Scanner::takeProblems() {
  std::vector<Problem> out;
  out.swap(m_problems);
  return out;
}

Scanner::Scanner(std::string_view text) : m_text(text) {
  m_lineStarts.push_back(0);
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '\n') m_lineStarts.push_back(i + 1);
  }
}

bool Scanner::skipComment() {
  if (m_pos + 1 >= m_text.size() || m_text[m_pos] != '/') return false;
  if (m_text[m_pos + 1] == '/') {
    while (m_pos < m_text.size() && m_text[m_pos] != '\n') ++m_pos;
    return true;
  }
  if (m_text[m_pos + 1] == '*') {
    const std::size_t close = m_text.find("*/", m_pos + 2);
    if (close != std::string_view::npos) {
      m_pos = close + 2;
      return true;
    }
    // Never closed: reported, and taken to end with its line so that the statements after
    // it are still read (and checked) instead of vanishing.
    addProblem(m_pos, "comment '/*' never closed");
    while (m_pos < m_text.size() && m_text[m_pos] != '\n') ++m_pos;
    return true;
  }
  return false;
}

void Scanner::skipBlanks() {
  while (m_pos < m_text.size()) {
    if (isBlank(m_text[m_pos])) {
      ++m_pos;
    } else if (!skipComment()) {
      return;
    }
  }
}

void Scanner::skipSpace() {
  while (m_pos < m_text.size()) {
    if (isBlank(m_text[m_pos]) || m_text[m_pos] == '\n') {
      ++m_pos;
    } else if (!skipComment()) {
      return;
    }
  }
}

bool Scanner::atLineEnd() {
  skipBlanks();
  return atEnd() || m_text[m_pos] == '\n';
}

bool Scanner::accept(char c, bool acrossLines) {
  const std::size_t saved = m_pos;
  acrossLines ? skipSpace() : skipBlanks();
  if (m_pos < m_text.size() && m_text[m_pos] == c) {
    ++m_pos;
    return true;
  }
  m_pos = saved;
  return false;
}

std::string_view Scanner::word() noexcept {
  const std::size_t begin = m_pos;
  while (m_pos < m_text.size() && isWordChar(m_text[m_pos])) ++m_pos;
  return m_text.substr(begin, m_pos - begin);
}

std::string_view Scanner::peekWord() {
  const std::size_t saved = m_pos;
  skipSpace();
  const std::string_view result = word();
  m_pos = saved;
  return result;
}

std::optional<double> Scanner::number(bool* outOfRange) noexcept {
  const std::size_t begin = m_pos;
  std::size_t i = m_pos;
  if (i < m_text.size() && (m_text[i] == '+' || m_text[i] == '-')) ++i;
  // Hexadecimal integer (seen in HEX attribute values of some tools).
  if (i + 1 < m_text.size() && m_text[i] == '0' && (m_text[i + 1] == 'x' || m_text[i + 1] == 'X')) {
    std::uint64_t value = 0;
    const auto* first = m_text.data() + i + 2;
    const auto* last = m_text.data() + m_text.size();
    const auto parsed = std::from_chars(first, last, value, 16);
    if (parsed.ec != std::errc{} || parsed.ptr == first) return std::nullopt;
    m_pos = static_cast<std::size_t>(parsed.ptr - m_text.data());
    const double magnitude = static_cast<double>(value);
    return m_text[begin] == '-' ? -magnitude : magnitude;
  }
  const std::size_t digitsBegin = i;
  while (i < m_text.size() && isDigit(m_text[i])) ++i;
  if (i < m_text.size() && m_text[i] == '.') {
    ++i;
    while (i < m_text.size() && isDigit(m_text[i])) ++i;
  }
  if (i == digitsBegin || (i == digitsBegin + 1 && m_text[digitsBegin] == '.')) return std::nullopt;
  if (i < m_text.size() && (m_text[i] == 'e' || m_text[i] == 'E')) {
    std::size_t j = i + 1;
    if (j < m_text.size() && (m_text[j] == '+' || m_text[j] == '-')) ++j;
    if (j < m_text.size() && isDigit(m_text[j])) {
      while (j < m_text.size() && isDigit(m_text[j])) ++j;
      i = j;
    }
  }
  // A number is never directly followed by a name character ("64_BIT_LE" is a name).
  if (i < m_text.size() && isWordChar(m_text[i])) return std::nullopt;
  const char* first = m_text.data() + begin;
  if (*first == '+') ++first;
  double value = 0.0;
  const auto parsed = std::from_chars(first, m_text.data() + i, value);
  if (parsed.ec == std::errc::result_out_of_range) {
    // from_chars leaves value untouched; clamp to the largest finite double.
    const bool negative = m_text[begin] == '-';
    // Underflow (negative exponent) becomes 0, overflow the largest finite double.
    const std::string_view literal(first, static_cast<std::size_t>(m_text.data() + i - first));
    const std::size_t exponent = literal.find_first_of("eE");
    const bool tiny = exponent != std::string_view::npos && exponent + 1 < literal.size() &&
                      literal[exponent + 1] == '-';
    value = tiny ? 0.0 : std::numeric_limits<double>::max();
    if (negative) value = -value;
    if (outOfRange) *outOfRange = true;
  } else if (parsed.ec != std::errc{} || parsed.ptr != m_text.data() + i) {
    return std::nullopt;
  }
  m_pos = i;
  return value;
}

namespace {

// An integer at `pos` (optional '+'), not followed by a word character or '.'; moves `pos`
// past it on success and leaves it on failure.
template <typename Integer>
std::optional<Integer> integerAt(std::string_view text, std::size_t& pos) noexcept {
  std::size_t i = pos;
  if (i < text.size() && text[i] == '+') ++i;
  Integer value = 0;
  const auto parsed = std::from_chars(text.data() + i, text.data() + text.size(), value);
  if (parsed.ec != std::errc{}) return std::nullopt;
  const auto end = static_cast<std::size_t>(parsed.ptr - text.data());
  if (end < text.size() && (isWordChar(text[end]) || text[end] == '.')) return std::nullopt;
  pos = end;
  return value;
}

}  // namespace

std::optional<std::uint64_t> Scanner::unsignedInteger() noexcept {
  return integerAt<std::uint64_t>(m_text, m_pos);
}

std::optional<std::int64_t> Scanner::signedInteger() noexcept {
  return integerAt<std::int64_t>(m_text, m_pos);
}

std::optional<std::string> Scanner::quoted(bool* unterminated) {
  if (m_pos >= m_text.size() || m_text[m_pos] != '"') return std::nullopt;
  std::string out;
  std::size_t i = m_pos + 1;
  while (i < m_text.size()) {
    const char c = m_text[i];
    if (c == '\\' && i + 1 < m_text.size() && (m_text[i + 1] == '"' || m_text[i + 1] == '\\')) {
      out += m_text[i + 1];
      i += 2;
    } else if (c == '"') {
      m_pos = i + 1;
      return out;
    } else if (c == '\n' && startsStatement(i + 1)) {
      // A comment may span lines, but a line starting with a statement keyword means the
      // closing quote is missing: reading on would swallow statements (issue 19).
      const std::size_t keywordAt = m_text.find_first_not_of(" \t", i + 1);
      std::size_t keywordEnd = keywordAt;
      while (keywordEnd < m_text.size() && isWordChar(m_text[keywordEnd])) ++keywordEnd;
      const auto line = lineColumn(i + 1).first;
      addProblem(m_pos, "string not closed before line " + std::to_string(line) + ", which starts a " +
                            std::string(m_text.substr(keywordAt, keywordEnd - keywordAt)) + " statement");
      if (unterminated) *unterminated = true;
      return std::nullopt;
    } else {
      out += c;
      ++i;
    }
  }
  addProblem(m_pos, "string never closed");
  if (unterminated) *unterminated = true;
  return std::nullopt;
}

bool Scanner::startsStatement(std::size_t lineStart) const noexcept {
  std::size_t i = lineStart;
  while (i < m_text.size() && (m_text[i] == ' ' || m_text[i] == '\t')) ++i;
  const std::size_t begin = i;
  while (i < m_text.size() && isWordChar(m_text[i])) ++i;
  if (i == begin || !isStatementKeyword(m_text.substr(begin, i - begin))) return false;
  // "BO_ 100 ...", "BU_: A B", "NS_ :" -- a keyword followed by a blank, ':' or the line end.
  return i == m_text.size() || m_text[i] == ' ' || m_text[i] == '\t' || m_text[i] == ':' || m_text[i] == '\n';
}

void Scanner::skipLine() noexcept {
  while (m_pos < m_text.size() && m_text[m_pos] != '\n') ++m_pos;
  if (m_pos < m_text.size()) ++m_pos;
}

bool Scanner::atLineStart() const noexcept {
  std::size_t i = m_pos;
  while (i > 0 && isBlank(m_text[i - 1])) --i;
  return i == 0 || m_text[i - 1] == '\n';
}

std::pair<std::uint32_t, std::uint32_t> Scanner::lineColumn(std::size_t position) const {
  const auto it = std::upper_bound(m_lineStarts.begin(), m_lineStarts.end(), position);
  const auto line = static_cast<std::size_t>(it - m_lineStarts.begin());
  const std::size_t column = position - m_lineStarts[line - 1] + 1;
  return {static_cast<std::uint32_t>(line), static_cast<std::uint32_t>(column)};
}

}  // namespace openvcu::dbc::detail
