#pragma once
// Small pure helpers of the HTTP server (http_server.hpp): request targets, percent-decoding,
// content types, JSON string escaping. No I/O except resolveUnder (declared in http_server.hpp).

#include <map>
#include <optional>
#include <string>
#include <string_view>

namespace openvcu::web::detail {

/// "%2e%2E/a+b" -> "../a+b" (query: `plusIsSpace` -> "../a b"); empty optional on a '%' not
/// followed by two hex digits. Decodes once: "%252e" -> "%2e".
[[nodiscard]] std::optional<std::string> percentDecode(std::string_view text, bool plusIsSpace);

/// A request target split and decoded: "/api/live?signals=a%2Cb&x" -> path "/api/live",
/// query {"signals": "a,b", "x": ""}. Empty optional when the target does not start with '/'
/// or an encoding is malformed.
struct Target {
  std::string path;
  std::map<std::string, std::string> query;
};
[[nodiscard]] std::optional<Target> parseTarget(std::string_view target);

/// The Content-Type of a static file by its extension ("app.js" -> "text/javascript;
/// charset=utf-8"); "application/octet-stream" for anything else.
[[nodiscard]] std::string_view contentTypeFor(std::string_view fileName) noexcept;

/// `text` as the inside of a JSON string: quotes, backslashes and control characters escaped.
[[nodiscard]] std::string jsonEscape(std::string_view text);

/// ASCII lower case.
[[nodiscard]] std::string lowerCase(std::string_view text);

}  // namespace openvcu::web::detail
