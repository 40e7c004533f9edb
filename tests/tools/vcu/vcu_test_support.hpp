#pragma once
// Test helpers: run `vcu` in-process with captured output, fixture paths, a scratch folder.

#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <vector>

#include "cli.hpp"
#include "sink.hpp"

namespace openvcu::cli::test {

struct RunResult {
  int exitCode{};
  std::string out;
  std::string err;
};

/// Runs `vcu ARGUMENTS...` with stdout and stderr captured.
inline RunResult runVcu(const std::vector<std::string>& arguments) {
  StringSink out;
  StringSink err;
  const int exitCode = run(arguments, Streams{out, err});
  return RunResult{exitCode, out.text(), err.text()};
}

/// A fixture in tests/tools/vcu/data/.
inline std::string dataPath(std::string_view name) {
  return std::string(VCU_TEST_DATA) + "/" + std::string(name);
}

/// A scratch file in the build tree (its folder is created), overwritten with `content`.
inline std::string writeScratchFile(std::string_view name, std::string_view content) {
  const std::filesystem::path folder(VCU_TEST_WORK_DIR);
  std::filesystem::create_directories(folder);
  const std::filesystem::path path = folder / name;
  std::ofstream file(path, std::ios::binary | std::ios::trunc);
  file << content;
  REQUIRE(file.good());
  return path.string();
}

inline std::vector<std::string> splitLines(const std::string& text) {
  std::vector<std::string> lines;
  std::size_t begin = 0;
  while (begin < text.size()) {
    std::size_t end = text.find('\n', begin);
    if (end == std::string::npos) end = text.size();
    lines.push_back(text.substr(begin, end - begin));
    begin = end + 1;
  }
  return lines;
}

inline bool contains(std::string_view text, std::string_view part) {
  return text.find(part) != std::string_view::npos;
}

inline constexpr int EXIT_OK = static_cast<int>(ExitCode::Ok);
inline constexpr int EXIT_INPUT_ERROR = static_cast<int>(ExitCode::Failure);
inline constexpr int EXIT_USAGE = static_cast<int>(ExitCode::Usage);

}  // namespace openvcu::cli::test
