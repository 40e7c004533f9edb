#pragma once
// What the libFuzzer targets share: the HHEA configuration as the fixed context of the
// loaders that check against a vehicle (loaded once per process), a private scratch
// folder for the loaders that only take a path, and require() (abort = a finding).
//
//   const fuzz::Hhea& hhea = fuzz::hhea();                       // vehicle + catalog
//   const std::string path = fuzz::scratch().write("gpio.json", data, size);
//
// Built twice (fuzz/CMakeLists.txt): with -fsanitize=fuzzer (clang, build-fuzz/) and with
// replay_main.cpp as a corpus-replay ctest test (any compiler, every build).

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "fuzz_require.hpp"
#include "openvcu/config/catalog.hpp"
#include "openvcu/config/vehicle.hpp"
#include "openvcu/signals/catalog.hpp"

namespace openvcu::fuzz {

inline std::string_view asText(const std::uint8_t* data, std::size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

/// The source tree's folder (config/hhea, tests/data).
inline std::string sourceDir() {
  return OPENVCU_SOURCE_DIR;
}

struct Hhea {
  config::VehicleConfig vehicle;
  signals::Catalog catalog;
};

/// config/hhea/vehicle.json and its catalog, loaded at the first call (abort if broken).
const Hhea& hhea();

/// A folder of its own under $TMPDIR (default /tmp), removed at exit.
class Scratch {
 public:
  Scratch();
  ~Scratch();
  Scratch(const Scratch&) = delete;
  Scratch& operator=(const Scratch&) = delete;

  /// Writes `size` bytes to <folder>/<name> (replacing it) and returns its path.
  std::string write(std::string_view name, const std::uint8_t* data, std::size_t size);
  /// <folder>/<name> as a symbolic link to `target` (once), e.g. a DBC a vehicle.json names.
  void link(std::string_view name, const std::string& target);
  [[nodiscard]] const std::string& folder() const noexcept { return m_folder; }

 private:
  std::string m_folder;
};

Scratch& scratch();

}  // namespace openvcu::fuzz
