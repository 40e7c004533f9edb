#pragma once
// JSON configuration files: reading with line:column errors, and a checker that walks a
// document, names every problem by its JSON path and catches unknown keys with a
// "did you mean" (the thesis' program silently ignored a mistyped key).
//
//   JsonChecker check("vehicle.json");
//   const auto& buses = check.array(root, "/buses", "buses");
//   -> errors like "vehicle.json: /buses/0/link: unknown link 'cam0'; expected socketcan:IFACE, sim:NAME or replay:FILE"

#include "openvcu/core/error.hpp"
#include "openvcu/core/result.hpp"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <initializer_list>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace openvcu::config {

using Json = nlohmann::json;

/// Parses JSON text (comments allowed). Every configuration file is read through here or
/// readJsonFile(). Refused, with line:column: a syntax error; a number too large for a
/// double ("1e999": no NaN or infinity ever reaches a loader), also with its JSON path; a
/// key given twice in one object, with both places and the object's path:
///   x.json:3:3: /states/0: key "name" given twice (first at 2:3)
/// Linear in the text: a 10 MB file takes a second pass of a few tens of ms.
/// @note thread-safe; never throws.
Result<Json> parseJson(std::string_view text, const std::string& fileName);
/// Reads and parses a JSON file (as parseJson()).
Result<Json> readJsonFile(const std::string& path);

/// parseJson()'s refusal of a message body (a request, a remote command: no file name), as
/// the answer states it: "/: key \"value\" given twice (first at 1:20), at 1:37" when the
/// error has a JSON path, else "/: not JSON (syntax error ..., at 1:2)".
std::string bodyErrorText(const Error& error);

/// A double for a message, short and exact: whole numbers below 10^15 in full ("3600000"),
/// others as the shortest text that reads back as the same double ("0.1", "1e+308",
/// "-2.5e-07"), "nan" / "inf" / "-inf" when not finite. Never the 309 digits
/// std::to_string gives for 1e308.
std::string formatNumber(double value);

/// A duration with a unit, "500ms", "2s", "1.5min" (also "0s"): nanoseconds, or empty for
/// anything else (no unit, negative, not finite, over 10^18 ns).
std::optional<std::int64_t> parseDurationNs(std::string_view text);
inline constexpr std::string_view DURATION_FORM = "a duration with a unit: \"500ms\", \"2s\", \"1min\"";

/// Collects errors and warnings while a loader walks a document. Getters never throw;
/// on a wrong or missing value they record an error and return the fallback.
class JsonChecker {
 public:
  explicit JsonChecker(std::string fileName) : m_file(std::move(fileName)) {}

  void error(const std::string& path, std::string message);
  void warning(const std::string& path, std::string message);
  [[nodiscard]] bool ok() const noexcept { return m_errorCount == 0; }
  [[nodiscard]] const std::vector<Error>& diagnostics() const noexcept { return m_diagnostics; }
  /// The first error, for Result<T> returns.
  [[nodiscard]] Error firstError() const;
  [[nodiscard]] const std::string& fileName() const noexcept { return m_file; }

  /// Reports keys of `object` not in `known` (with a suggestion) as errors.
  void onlyKeys(const Json& object, const std::string& path, std::initializer_list<std::string_view> known);

  bool isObject(const Json& value, const std::string& path);
  /// Member access: nullptr (and an error when `required`) if absent.
  const Json* member(const Json& object, const std::string& path, std::string_view key, bool required);

  std::optional<std::string> string(const Json& object, const std::string& path, std::string_view key,
                                    bool required = true);
  /// A number member; a value that is not finite is an error (parseJson never yields one,
  /// a document built in code may).
  std::optional<double> number(const Json& object, const std::string& path, std::string_view key,
                               bool required = true);
  std::optional<bool> boolean(const Json& object, const std::string& path, std::string_view key,
                              bool required = true);
  /// An array member; empty (and an error when required) if absent or not an array.
  const Json* array(const Json& object, const std::string& path, std::string_view key, bool required = true);

  static std::string join(const std::string& path, std::string_view key) {
    return path + "/" + std::string(key);
  }
  static std::string join(const std::string& path, std::size_t index) {
    return path + "/" + std::to_string(index);
  }

 private:
  std::string m_file;
  std::vector<Error> m_diagnostics;
  std::size_t m_errorCount{};
};

}  // namespace openvcu::config
