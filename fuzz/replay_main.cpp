// Corpus replay: the fuzz target's LLVMFuzzerTestOneInput fed every file of the folders
// (recursively, in name order) and files given, once each, without libFuzzer. Registered
// in ctest (label unit) so that every build, ASan+UBSan included, re-runs the corpora and
// the regression inputs of fuzz findings (tests/data/fuzz/<target>/).
//
//   replay_fuzz_cansend tests/data/fuzz/fuzz_cansend   -> "replay_fuzz_cansend: 41 inputs"
// Exit 0 when every input ran (a finding aborts), 1 when nothing was found to run.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace {

std::vector<std::filesystem::path> inputsOf(const std::filesystem::path& root) {
  std::vector<std::filesystem::path> files;
  std::error_code error;
  if (std::filesystem::is_regular_file(root, error)) {
    files.push_back(root);
  } else if (std::filesystem::is_directory(root, error)) {
    for (const auto& entry : std::filesystem::recursive_directory_iterator(root, error)) {
      if (entry.is_regular_file(error) && entry.path().filename().string().front() != '.' &&
          entry.path().filename() != "README.md") {
        files.push_back(entry.path());
      }
    }
  }
  std::sort(files.begin(), files.end());
  return files;
}

}  // namespace

int main(int argc, char** argv) {
  std::size_t count = 0;
  for (int i = 1; i < argc; ++i) {
    for (const std::filesystem::path& file : inputsOf(argv[i])) {
      std::ifstream in(file, std::ios::binary);
      const std::vector<char> bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
      std::fprintf(stderr, "%s\n", file.c_str());
      // A heap block of exactly the input's size, so that ASan sees any read past its end.
      const auto input = std::make_unique<std::uint8_t[]>(bytes.size());
      std::copy(bytes.begin(), bytes.end(), input.get());
      LLVMFuzzerTestOneInput(input.get(), bytes.size());
      ++count;
    }
  }
  std::printf("%s: %zu inputs\n", argc > 0 ? argv[0] : "replay", count);
  return count > 0 ? 0 : 1;
}
