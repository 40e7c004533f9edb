#pragma once
// Option checks shared by vcu's commands (CLI11 validators with short messages), and how a
// path given as a vehicle configuration is read.

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <system_error>

#include "openvcu/core/error.hpp"
#include "openvcu/core/result.hpp"

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

/// The file a vehicle configuration path names: vehicle.json itself, or the folder holding it.
///   "config/hhea" -> "config/hhea/vehicle.json";  "config/hhea/vehicle.json" -> as given.
/// A path that is not a folder is returned as given (its loader reports a missing file); a
/// folder without vehicle.json is an error naming the file looked for.
inline Result<std::string> vehicleFileOf(const std::string& path) {
  std::error_code error;
  if (!std::filesystem::is_directory(path, error)) return path;
  const std::string file = (std::filesystem::path(path) / "vehicle.json").string();
  if (!std::filesystem::exists(file, error)) {
    return Error{"a folder given as the configuration must hold vehicle.json", Location{file, 0, 0, {}}};
  }
  return file;
}

/// Whether two configuration paths (files or folders) name the same vehicle.json.
inline bool sameVehicleFile(const std::string& first, const std::string& second) {
  const auto fileOf = [](const std::string& path) {
    Result<std::string> fileResult = vehicleFileOf(path);
    std::error_code error;
    const std::filesystem::path file = fileResult ? *fileResult : path;
    const std::filesystem::path canonical = std::filesystem::weakly_canonical(file, error);
    return error ? file.lexically_normal() : canonical;
  };
  return fileOf(first) == fileOf(second);
}

}  // namespace openvcu::cli
