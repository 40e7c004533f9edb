#include "openvcu/config/json.hpp"

#include "openvcu/core/text.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <deque>
#include <unordered_map>

namespace openvcu::config {

namespace {
std::string kindName(const Json& value) {
  switch (value.type()) {
    case Json::value_t::null: return "null";
    case Json::value_t::object: return "an object";
    case Json::value_t::array: return "an array";
    case Json::value_t::string: return "a string";
    case Json::value_t::boolean: return "a boolean";
    case Json::value_t::number_integer:
    case Json::value_t::number_unsigned:
    case Json::value_t::number_float: return "a number";
    default: return "another type";
  }
}
}  // namespace

namespace {

struct TextPosition {
  std::uint32_t line{1};
  std::uint32_t column{1};
};

/// Line and column (1-based, columns in bytes as nlohmann counts them) of byte `offset`.
TextPosition positionOf(std::string_view text, std::size_t offset) {
  TextPosition position;
  std::size_t lineStart = 0;
  offset = std::min(offset, text.size());
  for (std::size_t i = 0; i < offset; ++i) {
    if (text[i] == '\n') {
      ++position.line;
      lineStart = i + 1;
    }
  }
  position.column = static_cast<std::uint32_t>(offset - lineStart + 1);
  return position;
}

/// A JSON pointer segment (RFC 6901): '~' -> "~0", '/' -> "~1".
void appendPointerSegment(std::string& path, std::string_view segment) {
  path += '/';
  for (const char c : segment) {
    if (c == '~') {
      path += "~0";
    } else if (c == '/') {
      path += "~1";
    } else {
      path += c;
    }
  }
}

/// A key for a message: quoted, control characters escaped (no raw newline or NUL).
std::string quotedKey(std::string_view key) {
  std::string out = "\"";
  for (const char c : key) {
    const auto byte = static_cast<unsigned char>(c);
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (byte < 0x20 || byte == 0x7F) {
      constexpr std::string_view HEX = "0123456789abcdef";
      out += "\\u00";
      out += HEX[byte >> 4];
      out += HEX[byte & 0xF];
    } else {
      out += c;
    }
  }
  return out + "\"";
}

using text::appendUtf8;

/// A second, light pass over JSON text, run after nlohmann::json accepted it (its DOM keeps
/// the last of two equal keys and knows no positions). Finds the first key given twice in
/// one object, comparing keys as decoded strings ("a" equals "\u0061"), and - when asked,
/// after nlohmann refused a number - the first number that overflows a double. Keeps a
/// path stack and, per open object, its keys (a short list, a hash map past 16 keys), so
/// it is linear in the text. On text it does not understand it reports nothing: nlohmann
/// is the judge of syntax.
class JsonScanner {
 public:
  JsonScanner(std::string_view text, const std::string& fileName) : m_text(text), m_file(fileName) {}

  std::optional<Error> run(bool findOverflow) {
    m_findOverflow = findOverflow;
    try {
      return scan();
    } catch (const std::exception&) {
      return std::nullopt;  // only allocation can throw here; nlohmann's verdict stands
    }
  }

 private:
  static constexpr std::size_t LINEAR_KEYS = 16;

  struct KeySeen {
    std::string_view key;
    std::size_t offset{};
  };
  struct Level {
    bool object{};
    bool expectKey{};
    std::size_t count{};       ///< arrays: elements begun so far
    std::string_view key;      ///< objects: the member being read
    std::vector<KeySeen> keys;
    std::unordered_map<std::string_view, std::size_t> index;  ///< used once keys outgrow LINEAR_KEYS
  };

  std::optional<Error> scan() {
    if (m_text.starts_with("\xEF\xBB\xBF")) m_at = 3;  // a UTF-8 byte order mark, which nlohmann skips too
    while (true) {
      skipSpace();
      if (m_at >= m_text.size()) return std::nullopt;
      const char c = m_text[m_at];
      if (c == '{' || c == '[') {
        beginValue();
        push(c == '{');
        ++m_at;
      } else if (c == '}' || c == ']') {
        if (m_depth == 0) return std::nullopt;
        --m_depth;
        ++m_at;
      } else if (c == ',') {
        if (m_depth > 0 && m_levels[m_depth - 1].object) m_levels[m_depth - 1].expectKey = true;
        ++m_at;
      } else if (c == ':') {
        if (m_depth > 0) m_levels[m_depth - 1].expectKey = false;
        ++m_at;
      } else if (c == '"') {
        const std::size_t start = m_at;
        const auto maybeString = readString();
        if (!maybeString) return std::nullopt;
        if (m_depth > 0 && m_levels[m_depth - 1].object && m_levels[m_depth - 1].expectKey) {
          if (auto duplicate = addKey(*maybeString, start)) return duplicate;
        } else {
          beginValue();
        }
      } else if (c == '-' || (c >= '0' && c <= '9')) {
        const std::size_t start = m_at;
        while (m_at < m_text.size() && isNumberChar(m_text[m_at])) ++m_at;
        beginValue();
        if (m_findOverflow && overflows(m_text.substr(start, m_at - start))) return overflowError(start);
      } else if (c >= 'a' && c <= 'z') {  // true, false, null
        beginValue();
        while (m_at < m_text.size() && m_text[m_at] >= 'a' && m_text[m_at] <= 'z') ++m_at;
      } else {
        return std::nullopt;
      }
    }
  }

  static bool isNumberChar(char c) {
    return (c >= '0' && c <= '9') || c == '-' || c == '+' || c == '.' || c == 'e' || c == 'E';
  }

  /// Whitespace and comments ("// to the end of the line", "/* ... */").
  void skipSpace() {
    while (m_at < m_text.size()) {
      const char c = m_text[m_at];
      if (c == ' ' || c == '\t' || c == '\n' || c == '\r') {
        ++m_at;
      } else if (c == '/' && m_at + 1 < m_text.size() && m_text[m_at + 1] == '/') {
        const std::size_t end = m_text.find('\n', m_at);
        m_at = end == std::string_view::npos ? m_text.size() : end;
      } else if (c == '/' && m_at + 1 < m_text.size() && m_text[m_at + 1] == '*') {
        const std::size_t end = m_text.find("*/", m_at + 2);
        m_at = end == std::string_view::npos ? m_text.size() : end + 2;
      } else {
        return;
      }
    }
  }

  /// A value begins at the current level: arrays count their elements for the path.
  void beginValue() {
    if (m_depth == 0) return;
    Level& level = m_levels[m_depth - 1];
    if (!level.object) ++level.count;
  }

  void push(bool object) {
    if (m_depth == m_levels.size()) m_levels.emplace_back();
    Level& level = m_levels[m_depth++];
    level.object = object;
    level.expectKey = object;
    level.count = 0;
    level.key = {};
    level.keys.clear();
    level.index.clear();
  }

  /// The string at m_at (on its opening quote), decoded only when it has escapes.
  std::optional<std::string_view> readString() {
    const std::size_t begin = ++m_at;
    bool escaped = false;
    while (m_at < m_text.size() && m_text[m_at] != '"') {
      if (m_text[m_at] == '\\') {
        escaped = true;
        ++m_at;
      }
      ++m_at;
    }
    if (m_at >= m_text.size()) return std::nullopt;
    const std::string_view raw = m_text.substr(begin, m_at - begin);
    ++m_at;
    if (!escaped) return raw;
    auto decoded = decode(raw);
    if (!decoded) return std::nullopt;
    return std::string_view(m_decoded.emplace_back(std::move(*decoded)));
  }

  static std::optional<std::uint32_t> hex4(std::string_view raw, std::size_t at) {
    if (at + 4 > raw.size()) return std::nullopt;
    std::uint32_t value = 0;
    const auto parsed = std::from_chars(raw.data() + at, raw.data() + at + 4, value, 16);
    if (parsed.ec != std::errc{} || parsed.ptr != raw.data() + at + 4) return std::nullopt;
    return value;
  }

  static std::optional<std::string> decode(std::string_view raw) {
    std::string out;
    out.reserve(raw.size());
    for (std::size_t i = 0; i < raw.size(); ++i) {
      if (raw[i] != '\\') {
        out += raw[i];
        continue;
      }
      if (++i >= raw.size()) return std::nullopt;
      switch (raw[i]) {
        case 'b': out += '\b'; break;
        case 'f': out += '\f'; break;
        case 'n': out += '\n'; break;
        case 'r': out += '\r'; break;
        case 't': out += '\t'; break;
        case 'u': {
          auto unit = hex4(raw, i + 1);
          if (!unit) return std::nullopt;
          i += 4;
          std::uint32_t codePoint = *unit;
          if (codePoint >= 0xD800 && codePoint < 0xDC00 && i + 2 < raw.size() && raw[i + 1] == '\\' &&
              raw[i + 2] == 'u') {
            if (auto low = hex4(raw, i + 3); low && *low >= 0xDC00 && *low < 0xE000) {
              codePoint = 0x10000 + ((codePoint - 0xD800) << 10) + (*low - 0xDC00);
              i += 6;
            }
          }
          appendUtf8(out, codePoint);
          break;
        }
        default: out += raw[i];  // '"', '\\', '/'
      }
    }
    return out;
  }

  std::optional<Error> addKey(std::string_view key, std::size_t offset) {
    Level& level = m_levels[m_depth - 1];
    level.key = key;
    std::optional<std::size_t> first;
    if (level.index.empty()) {
      for (const KeySeen& seen : level.keys) {
        if (seen.key == key) first = seen.offset;
      }
      if (!first) {
        level.keys.push_back(KeySeen{key, offset});
        if (level.keys.size() > LINEAR_KEYS) {
          for (const KeySeen& seen : level.keys) level.index.emplace(seen.key, seen.offset);
        }
      }
    } else {
      const auto [it, inserted] = level.index.emplace(key, offset);
      if (!inserted) first = it->second;
    }
    if (!first) return std::nullopt;
    const TextPosition firstAt = positionOf(m_text, *first);
    const TextPosition secondAt = positionOf(m_text, offset);
    return Error{"key " + quotedKey(key) + " given twice (first at " + std::to_string(firstAt.line) + ":" +
                     std::to_string(firstAt.column) + ")",
                 Location{m_file, secondAt.line, secondAt.column, path(m_depth - 1)}};
  }

  /// The JSON pointer of the value open at level `levels` (the levels below it and their
  /// current member or element); "/" for the root.
  std::string path(std::size_t levels) const {
    std::string out;
    for (std::size_t i = 0; i < levels; ++i) {
      const Level& level = m_levels[i];
      if (level.object) {
        appendPointerSegment(out, level.key);
      } else {
        out += '/' + std::to_string(level.count == 0 ? 0 : level.count - 1);
      }
    }
    return out.empty() ? "/" : out;
  }

  static bool overflows(std::string_view number) {
    const std::string copy(number);
    return !std::isfinite(std::strtod(copy.c_str(), nullptr));
  }

  Error overflowError(std::size_t offset) const {
    const TextPosition at = positionOf(m_text, offset);
    std::string_view number = m_text.substr(offset);
    number = number.substr(0, std::min<std::size_t>(40, std::find_if_not(number.begin(), number.end(), isNumberChar) -
                                                            number.begin()));
    return Error{"number " + std::string(number) + " is out of range (a configuration number must be a finite double)",
                 Location{m_file, at.line, at.column, path(m_depth)}};
  }

  std::string_view m_text;
  const std::string& m_file;
  bool m_findOverflow{};
  std::size_t m_at{};
  std::size_t m_depth{};
  std::vector<Level> m_levels;
  std::deque<std::string> m_decoded;  ///< keys with escapes, decoded; stable addresses for the views
};

}  // namespace

Result<Json> parseJson(std::string_view text, const std::string& fileName) {
  Json document;
  try {
    document = Json::parse(text.begin(), text.end(), nullptr, true, /*ignore_comments=*/true);
  } catch (const Json::parse_error& failure) {
    // failure.byte is 1-based, pointing just past the offending character.
    const std::size_t offset = failure.byte == 0 ? 0 : std::min<std::size_t>(failure.byte - 1, text.size());
    const TextPosition at = positionOf(text, offset);
    std::string reason = failure.what();
    // "[json.exception.parse_error.101] parse error at line 3, column 5: syntax error ..." -> the part after ": "
    if (const auto colon = reason.find(": "); colon != std::string::npos) reason = reason.substr(colon + 2);
    return Error{"invalid JSON: " + reason, Location{fileName, at.line, at.column, {}}};
  } catch (const Json::out_of_range&) {
    // nlohmann refuses a number that overflows a double (406) without a position: find it.
    if (auto located = JsonScanner(text, fileName).run(/*findOverflow=*/true)) return *located;
    return Error{"invalid JSON: a number is out of range", Location{fileName, 0, 0, {}}};
  } catch (const std::exception& failure) {
    return Error{std::string("invalid JSON: ") + failure.what(), Location{fileName, 0, 0, {}}};
  }
  if (auto duplicate = JsonScanner(text, fileName).run(/*findOverflow=*/false)) return *duplicate;
  return document;
}

Result<Json> readJsonFile(const std::string& path) {
  std::string reason;
  const auto content = text::readFile(path, &reason);
  if (!content) return Error{reason, Location{path, 0, 0, {}}};
  return parseJson(*content, path);
}

std::string bodyErrorText(const Error& error) {
  const std::string at = ", at " + std::to_string(error.location.line) + ":" + std::to_string(error.location.column);
  if (!error.location.jsonPath.empty()) return error.location.jsonPath + ": " + error.message + at;
  return "/: not JSON (" + error.message + at + ")";
}

std::string formatNumber(double value) {
  if (std::isnan(value)) return "nan";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  // whole numbers below 10^15 in full ("3600000", not to_chars' shorter "3.6e+06")
  if (value == std::trunc(value) && std::fabs(value) < 1e15) return std::to_string(static_cast<std::int64_t>(value));
  std::array<char, 32> buffer{};
  const auto written = std::to_chars(buffer.data(), buffer.data() + buffer.size(), value);
  return std::string(buffer.data(), written.ptr);
}

void JsonChecker::error(const std::string& path, std::string message) {
  m_diagnostics.push_back(Error{std::move(message), Location::json(m_file, path.empty() ? "/" : path)});
  ++m_errorCount;
}

void JsonChecker::warning(const std::string& path, std::string message) {
  m_diagnostics.push_back(
      Error{std::move(message), Location::json(m_file, path.empty() ? "/" : path), Severity::Warning});
}

Error JsonChecker::firstError() const {
  for (const Error& diagnostic : m_diagnostics) {
    if (diagnostic.severity == Severity::Error) return diagnostic;
  }
  return Error{"no error", Location{m_file, 0, 0, {}}};
}

void JsonChecker::onlyKeys(const Json& object, const std::string& path, std::initializer_list<std::string_view> known) {
  if (!object.is_object()) return;
  std::vector<std::string> candidates(known.begin(), known.end());
  for (const auto& item : object.items()) {
    const std::string& key = item.key();
    if (std::find(known.begin(), known.end(), key) != known.end()) continue;
    std::string message = "unknown key '" + key + "'";
    if (auto suggestion = text::didYouMean(key, candidates)) message += "; did you mean '" + *suggestion + "'?";
    error(join(path, key), std::move(message));
  }
}

bool JsonChecker::isObject(const Json& value, const std::string& path) {
  if (value.is_object()) return true;
  error(path, "must be an object, not " + kindName(value));
  return false;
}

const Json* JsonChecker::member(const Json& object, const std::string& path, std::string_view key, bool required) {
  if (!object.is_object()) return nullptr;
  const auto it = object.find(std::string(key));
  if (it == object.end()) {
    if (required) error(join(path, key), "missing (required)");
    return nullptr;
  }
  return &*it;
}

std::optional<std::string> JsonChecker::string(const Json& object, const std::string& path, std::string_view key,
                                               bool required) {
  const Json* value = member(object, path, key, required);
  if (!value) return std::nullopt;
  if (!value->is_string()) {
    error(join(path, key), "must be a string, not " + kindName(*value));
    return std::nullopt;
  }
  return value->get<std::string>();
}

std::optional<double> JsonChecker::number(const Json& object, const std::string& path, std::string_view key,
                                          bool required) {
  const Json* value = member(object, path, key, required);
  if (!value) return std::nullopt;
  if (!value->is_number()) {
    error(join(path, key), "must be a number, not " + kindName(*value));
    return std::nullopt;
  }
  const auto number = value->get<double>();
  if (!std::isfinite(number)) {
    error(join(path, key), "must be a finite number, not " + formatNumber(number));
    return std::nullopt;
  }
  return number;
}

std::optional<bool> JsonChecker::boolean(const Json& object, const std::string& path, std::string_view key,
                                         bool required) {
  const Json* value = member(object, path, key, required);
  if (!value) return std::nullopt;
  if (!value->is_boolean()) {
    error(join(path, key), "must be true or false, not " + kindName(*value));
    return std::nullopt;
  }
  return value->get<bool>();
}

const Json* JsonChecker::array(const Json& object, const std::string& path, std::string_view key, bool required) {
  const Json* value = member(object, path, key, required);
  if (!value) return nullptr;
  if (!value->is_array()) {
    error(join(path, key), "must be an array, not " + kindName(*value));
    return nullptr;
  }
  return value;
}

std::optional<std::int64_t> parseDurationNs(std::string_view text) {
  double amount = 0;
  const auto parsed = std::from_chars(text.data(), text.data() + text.size(), amount);
  if (parsed.ec != std::errc{} || parsed.ptr == text.data()) return std::nullopt;
  const std::string_view unit(parsed.ptr, static_cast<std::size_t>(text.data() + text.size() - parsed.ptr));
  double scale = 0;
  if (unit == "ms") scale = 1e6;
  if (unit == "s") scale = 1e9;
  if (unit == "min") scale = 60e9;
  if (scale == 0 || !std::isfinite(amount) || amount < 0 || amount * scale > 1e18) return std::nullopt;
  return static_cast<std::int64_t>(std::llround(amount * scale));
}

}  // namespace openvcu::config
