#pragma once
// Test helper: a fresh folder under /tmp, removed with everything in it at scope end.

#include <stdlib.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

namespace openvcu::test {

class TempFolder {
 public:
  TempFolder() {
    std::string pattern = (std::filesystem::temp_directory_path() / "openvcu-test-XXXXXX").string();
    if (::mkdtemp(pattern.data()) != nullptr) m_path = pattern;
  }
  TempFolder(const TempFolder&) = delete;
  TempFolder& operator=(const TempFolder&) = delete;
  ~TempFolder() {
    std::error_code ignored;
    if (!m_path.empty()) std::filesystem::remove_all(m_path, ignored);
  }

  [[nodiscard]] std::string path(std::string_view name) const { return (std::filesystem::path(m_path) / name).string(); }

  /// Writes `content` to a file in the folder and returns its path.
  std::string write(std::string_view name, std::string_view content) const {
    const std::string file = path(name);
    std::ofstream out(file, std::ios::binary);
    out.write(content.data(), static_cast<std::streamsize>(content.size()));
    return file;
  }

 private:
  std::string m_path;
};

}  // namespace openvcu::test
