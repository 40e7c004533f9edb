// vcu-web's same-origin check and media types (services/web/src/same_origin.hpp): what a page of
// another origin can make a logged-in browser send (forms, fetch with mode no-cors, text/plain
// bodies) is refused with the header's name; vcu-web's own page and scripts without a browser pass.
#include <doctest/doctest.h>

#include <nlohmann/json.hpp>

#include "same_origin.hpp"

namespace {

using namespace openvcu;

constexpr const char* OWN_HOST = "127.0.0.1:18080";
constexpr const char* OWN_ORIGIN = "http://127.0.0.1:18080";
constexpr const char* PROXY_ORIGIN = "https://vcu.example";

web::Request post(std::map<std::string, std::string> headers) {
  web::Request request;
  request.method = web::Method::Post;
  request.path = "/api/command";
  request.headers = std::move(headers);
  request.headers.emplace("host", OWN_HOST);
  return request;
}

/// The refusal's message as a client reads it from the response body.
std::string errorOf(const std::optional<web::Refusal>& refusal) {
  REQUIRE(refusal);
  const web::Response response = refusal->response();
  CHECK(response.status == refusal->status());
  return nlohmann::json::parse(response.body).at("error").get<std::string>();
}

}  // namespace

TEST_CASE("the media type is the part before the first semicolon, trimmed and in lower case") {
  CHECK(web::mediaTypeOf("application/json") == "application/json");
  CHECK(web::mediaTypeOf(" Application/JSON ; charset=utf-8") == "application/json");
  CHECK(web::mediaTypeOf("text/plain; x=application/json") == "text/plain");
  CHECK(web::mediaTypeOf("multipart/form-data; boundary=application/json") == "multipart/form-data");
  CHECK(web::mediaTypeOf("") == "");
}

TEST_CASE("a JSON body is refused 415 naming Content-Type when the media type only mentions application/json") {
  for (const char* type : {"text/plain; x=application/json", "application/x-www-form-urlencoded; x=application/json",
                           "multipart/form-data; boundary=application/json", "application/jsonp", ""}) {
    const auto sut = web::refuseMediaType(post({{"content-type", type}}), "application/json");
    REQUIRE(sut);
    CHECK(sut->kind == web::RefusalKind::WrongMediaType);
    CHECK(sut->status() == 415);
    CHECK(errorOf(sut).starts_with("Content-Type "));
  }
  CHECK_FALSE(web::refuseMediaType(post({{"content-type", "application/json; charset=utf-8"}}), "application/json"));
  CHECK_FALSE(web::refuseMediaType(post({{"content-type", "Application/Json"}}), "application/json"));
}

TEST_CASE("origins compare in lower case without the scheme's default port") {
  CHECK(web::normalizedOrigin("HTTP://LocalHost:80") == "http://localhost");
  CHECK(web::normalizedOrigin("https://vcu.example:443") == "https://vcu.example");
  CHECK(web::normalizedOrigin("http://127.0.0.1:8080") == "http://127.0.0.1:8080");
  CHECK(web::normalizedOrigin("http://[::1]:80") == "http://[::1]");
}

TEST_CASE("vcu-web's own page passes the same-origin check") {
  const web::RequestGuard sut;
  CHECK_FALSE(sut.refuseCrossOrigin(post({{"origin", OWN_ORIGIN}, {"sec-fetch-site", "same-origin"}})));
  CHECK_FALSE(sut.refuseCrossOrigin(post({{"origin", OWN_ORIGIN}})));
}

TEST_CASE("a script without a browser (no Origin, no Sec-Fetch-Site) passes the same-origin check") {
  const web::RequestGuard sut;
  CHECK_FALSE(sut.refuseCrossOrigin(post({})));
}

TEST_CASE("a page on another port of the same host is refused 403 naming the Origin") {
  const web::RequestGuard sut;
  const auto refused = sut.refuseCrossOrigin(post({{"origin", "http://127.0.0.1:9000"}}));
  REQUIRE(refused);
  CHECK(refused->kind == web::RefusalKind::ForeignOrigin);
  CHECK(refused->status() == 403);
  CHECK(
      errorOf(refused) ==
      "Origin 'http://127.0.0.1:9000' is not this server's (http://127.0.0.1:18080): only vcu-web's own pages may send "
      "this request");
}

TEST_CASE("Sec-Fetch-Site same-site or cross-site is refused 403 naming the header even with a matching Origin") {
  const web::RequestGuard sut;
  for (const char* site : {"same-site", "cross-site"}) {
    const auto refused = sut.refuseCrossOrigin(post({{"origin", OWN_ORIGIN}, {"sec-fetch-site", site}}));
    REQUIRE(refused);
    CHECK(refused->kind == web::RefusalKind::CrossSiteFetch);
    CHECK(refused->status() == 403);
    CHECK(errorOf(refused).starts_with("Sec-Fetch-Site '" + std::string(site) + "'"));
  }
  CHECK_FALSE(sut.refuseCrossOrigin(post({{"sec-fetch-site", "none"}})));
}

TEST_CASE("Origin null, another scheme and a longer host are refused") {
  const web::RequestGuard sut;
  for (const char* origin : {"null", "https://127.0.0.1:18080", "http://127.0.0.1:180800", "http://127.0.0.1"}) {
    CAPTURE(origin);
    CHECK(sut.refuseCrossOrigin(post({{"origin", origin}})));
  }
}

TEST_CASE("a trusted origin (a TLS reverse proxy's) passes, others stay refused") {
  const web::RequestGuard sut({PROXY_ORIGIN});
  CHECK_FALSE(sut.refuseCrossOrigin(post({{"origin", "https://vcu.example"}, {"sec-fetch-site", "same-origin"}})));
  CHECK_FALSE(sut.refuseCrossOrigin(post({{"origin", "https://vcu.example:443"}})));
  CHECK(sut.refuseCrossOrigin(post({{"origin", "http://vcu.example"}})));
  CHECK(sut.refuseCrossOrigin(post({{"origin", "https://vcu.example.evil"}})));
}
