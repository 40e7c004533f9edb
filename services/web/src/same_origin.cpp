#include "same_origin.hpp"

#include <algorithm>

#include "http_util.hpp"

namespace openvcu::web {
namespace {

std::string_view trimmed(std::string_view text) {
  const auto first = text.find_first_not_of(" \t");
  if (first == std::string_view::npos) return {};
  const auto last = text.find_last_not_of(" \t");
  return text.substr(first, last - first + 1);
}

/// A header value quoted for a message, cut so a long value cannot flood the log.
std::string shownValue(std::string_view value) {
  constexpr std::size_t MAX_SHOWN = 100;
  std::string shown(value.substr(0, MAX_SHOWN));
  for (char& c : shown) {
    if (static_cast<unsigned char>(c) < 0x20 || c == '\x7f') c = '?';
  }
  return "'" + shown + (value.size() > MAX_SHOWN ? "...'" : "'");
}

}  // namespace

unsigned Refusal::status() const noexcept {
  return kind == RefusalKind::WrongMediaType ? 415 : 403;
}

Response Refusal::response() const {
  return Response::error(status(), message);
}

std::string mediaTypeOf(std::string_view contentType) {
  return detail::lowerCase(trimmed(contentType.substr(0, contentType.find(';'))));
}

std::string normalizedOrigin(std::string_view origin) {
  std::string result = detail::lowerCase(trimmed(origin));
  const auto withoutPort = [&result](std::string_view scheme, std::string_view port) {
    if (result.starts_with(scheme) && result.ends_with(port) && result.size() > scheme.size() + port.size()) {
      result.resize(result.size() - port.size());
    }
  };
  withoutPort("http://", ":80");
  withoutPort("https://", ":443");
  return result;
}

std::optional<Refusal> refuseMediaType(const Request& request, std::string_view mediaType) {
  const std::string sent = request.header("content-type");
  if (mediaTypeOf(sent) == mediaType) return std::nullopt;
  return Refusal{RefusalKind::WrongMediaType, "Content-Type " +
                                                  (sent.empty() ? std::string("missing") : shownValue(sent)) +
                                                  ": the body must be " + std::string(mediaType)};
}

RequestGuard::RequestGuard(std::vector<std::string> trustedOrigins) {
  for (const std::string& origin : trustedOrigins) m_trustedOrigins.push_back(normalizedOrigin(origin));
}

std::optional<Refusal> RequestGuard::refuseCrossOrigin(const Request& request) const {
  const std::string site = detail::lowerCase(trimmed(request.header("sec-fetch-site")));
  if (!site.empty() && site != "same-origin" && site != "none") {
    return Refusal{RefusalKind::CrossSiteFetch, "Sec-Fetch-Site " + shownValue(site) +
                                                    ": only vcu-web's own pages may send this request (same-origin)"};
  }
  const std::string origin = request.header("origin");
  if (origin.empty()) return std::nullopt;
  const std::string sent = normalizedOrigin(origin);
  const std::string own = normalizedOrigin("http://" + request.header("host"));
  const bool trusted = std::find(m_trustedOrigins.begin(), m_trustedOrigins.end(), sent) != m_trustedOrigins.end();
  if (sent != "null" && (sent == own || trusted)) return std::nullopt;
  return Refusal{RefusalKind::ForeignOrigin, "Origin " + shownValue(origin) + " is not this server's (" + own +
                                                 "): only vcu-web's own pages may send this request"};
}

}  // namespace openvcu::web
