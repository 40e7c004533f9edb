#pragma once
// Option checks shared by vcu's commands (CLI11 validators with short messages).

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdlib>
#include <string>

namespace openvcu::cli {

/// A number of 0 or more, checked as text before CLI11 converts it ("-1" would wrap to
/// 2^64 - 1 in an unsigned option). Not CLI::NonNegativeNumber: its message prints the upper
/// bound, DBL_MAX, in 309 digits.
inline CLI::Validator nonNegativeNumber(const char* name = "NUMBER") {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        const char* begin = text.c_str();
        char* end = nullptr;
        const double value = std::strtod(begin, &end);
        if (end == begin || *end != '\0' || !std::isfinite(value)) return "'" + text + "' is not a number";
        if (value < 0 || text.find('-') != std::string::npos) return "must be 0 or more, not " + text;
        return {};
      },
      name);
}

}  // namespace openvcu::cli
