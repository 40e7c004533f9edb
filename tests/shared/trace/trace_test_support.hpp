#pragma once
// A small DBC and a scratch folder for the shared/trace tests.
#include <doctest/doctest.h>
#include <stdlib.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "openvcu/dbc/parser.hpp"

namespace openvcu::trace::test {

/// OBC 0x18FF50E5 (extended; State with value texts, Voltage 0.1 V) and Status 0x123.
inline constexpr const char* SMALL_DBC = R"(VERSION ""
NS_ :
BS_:
BU_: VCU OBC
BO_ 2566869221 OBC: 8 OBC
 SG_ State : 0|8@1+ (1,0) [0|255] "" VCU
 SG_ Voltage : 8|16@1+ (0.1,0) [0|1000] "V" VCU
BO_ 291 Status: 8 VCU
 SG_ Mode : 0|8@1+ (1,0) [0|255] "" OBC
VAL_ 2566869221 State 1 "On" 0 "Off" ;
)";

inline dbc::Database smallDatabase() {
  dbc::ParseOutput parsed = dbc::parse(SMALL_DBC, "small.dbc");
  REQUIRE_FALSE(parsed.hasErrors());
  return std::move(parsed.database);
}

/// A folder under /tmp removed with everything in it at the end of the test.
class ScratchFolder {
 public:
  ScratchFolder() {
    std::string pattern = "/tmp/openvcu-trace-XXXXXX";
    REQUIRE(::mkdtemp(pattern.data()) != nullptr);
    m_path = pattern;
  }
  ~ScratchFolder() {
    std::error_code ignored;
    std::filesystem::remove_all(m_path, ignored);
  }
  ScratchFolder(const ScratchFolder&) = delete;
  ScratchFolder& operator=(const ScratchFolder&) = delete;

  /// Writes `content` into the file `name` of the folder; returns its path.
  [[nodiscard]] std::string write(const std::string& name, const std::string& content) const {
    const std::string path = m_path + "/" + name;
    std::ofstream(path, std::ios::binary) << content;
    return path;
  }
  [[nodiscard]] std::string path(const std::string& name) const { return m_path + "/" + name; }

 private:
  std::string m_path;
};

}  // namespace openvcu::trace::test
