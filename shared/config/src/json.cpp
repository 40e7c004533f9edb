#include "openvcu/config/json.hpp"

#include "openvcu/core/text.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>

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

Result<Json> parseJson(std::string_view text, const std::string& fileName) {
  try {
    return Json::parse(text.begin(), text.end(), nullptr, true, /*ignore_comments=*/true);
  } catch (const Json::parse_error& failure) {
    // failure.byte is 1-based, pointing just past the offending character.
    const std::size_t offset = failure.byte == 0 ? 0 : std::min<std::size_t>(failure.byte - 1, text.size());
    std::uint32_t line = 1;
    std::size_t lineStart = 0;
    for (std::size_t i = 0; i < offset; ++i) {
      if (text[i] == '\n') {
        ++line;
        lineStart = i + 1;
      }
    }
    std::string reason = failure.what();
    // "[json.exception.parse_error.101] parse error at line 3, column 5: syntax error ..." -> the part after ": "
    if (const auto colon = reason.find(": "); colon != std::string::npos) reason = reason.substr(colon + 2);
    return Error{"invalid JSON: " + reason,
                 Location{fileName, line, static_cast<std::uint32_t>(offset - lineStart + 1), {}}};
  }
}

Result<Json> readJsonFile(const std::string& path) {
  std::string reason;
  const auto content = text::readFile(path, &reason);
  if (!content) return Error{reason, Location{path, 0, 0, {}}};
  return parseJson(*content, path);
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
  return value->get<double>();
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
