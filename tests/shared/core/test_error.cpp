// Error::toString(): one printable line whatever the input held (issue 19).

#include <doctest/doctest.h>

#include <string>

#include "openvcu/core/error.hpp"

using namespace openvcu;

TEST_CASE("a diagnostic quoting a NUL, a newline and a CR from the input stays one printable line (#19)") {
  const Error sut{std::string("unknown name 'a\0b\nc\rd\x1B'", 23), Location{"x\ny.dbc", 3, 7, {}}};

  CHECK(sut.toString() == "x\\ny.dbc:3:7: unknown name 'a\\0b\\nc\\rd\\x1B'");
}

TEST_CASE("escaping keeps tabs and UTF-8 and is idempotent") {
  const std::string text = "Tab\there \xC3\xA4 back\\slash";

  CHECK(escapeControlCharacters(text) == text);
  CHECK(escapeControlCharacters(escapeControlCharacters("a\nb")) == "a\\nb");
}
