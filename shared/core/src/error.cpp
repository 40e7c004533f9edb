#include "openvcu/core/error.hpp"

namespace openvcu {

/// Appends `text` with control characters escaped, so that a diagnostic quoting its input
/// stays one printable line: NUL -> "\0", LF -> "\n", CR -> "\r", other C0 bytes and DEL
/// -> "\xHH". TAB and every byte from 0x80 (UTF-8) are kept.
void appendEscapedControlCharacters(std::string& out, std::string_view text) {
  static constexpr char HEX[] = "0123456789ABCDEF";
  for (const char c : text) {
    const auto u = static_cast<unsigned char>(c);
    if (u >= 0x20 && u != 0x7F) {
      out += c;
    } else if (c == '\t') {
      out += c;
    } else if (c == '\0') {
      out += "\\0";
    } else if (c == '\n') {
      out += "\\n";
    } else if (c == '\r') {
      out += "\\r";
    } else {
      out += "\\x";
      out += HEX[u >> 4];
      out += HEX[u & 0xF];
    }
  }
}

std::string escapeControlCharacters(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  appendEscapedControlCharacters(out, text);
  return out;
}

std::string Location::toString() const {
  std::string out;
  appendEscapedControlCharacters(out, file);
  if (line > 0) {
    out += ':' + std::to_string(line);
    if (column > 0) out += ':' + std::to_string(column);
  }
  if (!jsonPath.empty()) {
    if (!out.empty()) out += ": ";
    appendEscapedControlCharacters(out, jsonPath);
  }
  return out;
}

std::string Error::toString() const {
  std::string out = location.toString();
  if (!out.empty()) out += ": ";
  if (severity == Severity::Warning) out += "warning: ";
  if (severity == Severity::Note) out += "note: ";
  appendEscapedControlCharacters(out, message);
  return out;
}

}  // namespace openvcu
