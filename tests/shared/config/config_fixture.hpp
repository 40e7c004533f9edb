#pragma once
// Writes a configuration beside the test data's small.dbc and removes it afterwards.
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>

namespace openvcu::test {

inline const std::string CONFIG_DATA_DIR = std::string(OPENVCU_SOURCE_DIR) + "/tests/data/config";

class TempConfig {
 public:
  explicit TempConfig(const std::string& json) {
    m_dir = std::filesystem::temp_directory_path() / ("openvcu-config-test-" + std::to_string(::getpid()) + "-" +
                                                     std::to_string(s_counter++));
    std::filesystem::create_directories(m_dir);
    std::filesystem::copy_file(CONFIG_DATA_DIR + "/small.dbc", m_dir / "small.dbc");
    std::ofstream(m_dir / "vehicle.json") << json;
  }
  ~TempConfig() { std::filesystem::remove_all(m_dir); }
  TempConfig(const TempConfig&) = delete;
  TempConfig& operator=(const TempConfig&) = delete;
  [[nodiscard]] std::string path() const { return (m_dir / "vehicle.json").string(); }
  [[nodiscard]] std::string dir() const { return m_dir.string(); }

 private:
  std::filesystem::path m_dir;
  static inline int s_counter = 0;
};

}  // namespace openvcu::test
