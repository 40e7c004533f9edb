#pragma once
// Which requests may change something (docs/design/web.md, "Same-origin requests"): a POST
// is taken only from vcu-web's own pages, never from a page of another origin that a
// logged-in operator's browser happens to show (another port of 127.0.0.1 is another origin
// too: SameSite cookies do not tell them apart). And a body is read as what its media type
// says, never by a substring of the Content-Type.
//
//   RequestGuard guard({"https://vcu.example"});   // origins of a TLS reverse proxy, if any
//   if (auto refused = guard.refuseCrossOrigin(request)) return respond(refused->response());
//   if (auto refused = refuseMediaType(request, "application/json")) return respond(refused->response());
//
// A refusal carries its kind and a message that names the header; as a Response it is 403
// (Sec-Fetch-Site, Origin) or 415 (Content-Type) with {"error": message}.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "http_server.hpp"

namespace openvcu::web {

enum class RefusalKind : std::uint8_t {
  CrossSiteFetch,  ///< Sec-Fetch-Site is same-site or cross-site
  ForeignOrigin,   ///< Origin is not the server's own nor a trusted one
  WrongMediaType,  ///< Content-Type's media type is not the one the route reads
};

/// Why a request is refused before its handler runs.
struct Refusal {
  RefusalKind kind;
  std::string message;  ///< names the header: "Origin 'http://127.0.0.1:9000' is not this server's (...)"
  /// 403 for the origin kinds, 415 for a media type.
  [[nodiscard]] unsigned status() const noexcept;
  /// {"error": message} with status().
  [[nodiscard]] Response response() const;
};

/// The media type of a Content-Type value: the part before ';', without surrounding blanks,
/// lower case. "Text/Plain ; x=application/json" -> "text/plain"; "" -> "".
[[nodiscard]] std::string mediaTypeOf(std::string_view contentType);

/// An origin as browsers serialise it, for comparing: lower case, the scheme's default port
/// left out. "HTTP://LocalHost:80" -> "http://localhost"; "https://a.b:8443" stays.
[[nodiscard]] std::string normalizedOrigin(std::string_view origin);

/// WrongMediaType naming the Content-Type unless the request's media type is exactly
/// `mediaType` (parameters such as "; charset=utf-8" are allowed).
[[nodiscard]] std::optional<Refusal> refuseMediaType(const Request& request, std::string_view mediaType);

/// @note thread-safe after construction (const).
class RequestGuard {
 public:
  /// `trustedOrigins`: origins besides the server's own ("https://vcu.example", the public
  /// address of a reverse proxy in front of vcu-web); normalised here.
  explicit RequestGuard(std::vector<std::string> trustedOrigins = {});

  /// A refusal (403) unless the request comes from vcu-web's own page:
  ///  - Sec-Fetch-Site, when sent, is "same-origin" or "none" (the user's own navigation);
  ///  - Origin, when sent, equals "http://" + the Host header (the origin the browser used to
  ///    reach this server) or one of the trusted origins; "null" (sandboxed frames, data:
  ///    pages, redirected requests) never matches.
  /// A request with neither header is not a browser's request on behalf of a page (browsers
  /// send Origin with every POST): a script or curl with a session, allowed.
  [[nodiscard]] std::optional<Refusal> refuseCrossOrigin(const Request& request) const;

 private:
  std::vector<std::string> m_trustedOrigins;
};

}  // namespace openvcu::web
