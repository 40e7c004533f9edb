#pragma once
// Test helpers: run `vcu` in-process with captured output, fixture paths, a scratch folder.

#include <doctest/doctest.h>

#include <unistd.h>

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

/// This test process's scratch folder in the build tree, created: work/<pid>. ctest runs each
/// test case as its own process in parallel, so cases writing the same file name must not share
/// a folder (one truncates the file while another reads it).
/// The folder is removed when the process that made it exits.
inline std::filesystem::path scratchFolder() {
  struct Folder {
    pid_t owner = ::getpid();
    std::filesystem::path path = std::filesystem::path(VCU_TEST_WORK_DIR) / std::to_string(owner);
    ~Folder() {
      if (::getpid() != owner) return;  // a forked child leaving through exit()
      std::error_code ignored;
      std::filesystem::remove_all(path, ignored);
    }
  };
  static const Folder folder;
  std::filesystem::create_directories(folder.path);
  return folder.path;
}

/// A file in scratchFolder(), overwritten with `content`.
inline std::string writeScratchFile(std::string_view name, std::string_view content) {
  const std::filesystem::path folder = scratchFolder();
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
