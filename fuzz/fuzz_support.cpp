#include "fuzz_support.hpp"

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <vector>

namespace openvcu::fuzz {

const Hhea& hhea() {
  static const Hhea loaded = [] {
    Hhea result;
    auto vehicleResult = config::loadVehicleConfig(sourceDir() + "/config/hhea/vehicle.json");
    if (!vehicleResult) {
      std::fprintf(stderr, "fuzz: config/hhea/vehicle.json: %s\n", vehicleResult.error().toString().c_str());
      std::abort();
    }
    result.vehicle = std::move(*vehicleResult);
    auto catalogResult = config::buildCatalog(result.vehicle);
    if (!catalogResult) {
      std::fprintf(stderr, "fuzz: HHEA catalog: %s\n", catalogResult.error().toString().c_str());
      std::abort();
    }
    result.catalog = std::move(*catalogResult);
    return result;
  }();
  return loaded;
}

Scratch::Scratch() {
  const char* tmp = std::getenv("TMPDIR");
  std::string pattern = std::string(tmp != nullptr && *tmp != '\0' ? tmp : "/tmp") + "/openvcu-fuzz-XXXXXX";
  std::vector<char> buffer(pattern.begin(), pattern.end());
  buffer.push_back('\0');
  if (::mkdtemp(buffer.data()) == nullptr) {
    std::perror("fuzz: mkdtemp");
    std::abort();
  }
  m_folder = buffer.data();
}

Scratch::~Scratch() {
  std::error_code ignored;
  std::filesystem::remove_all(m_folder, ignored);
}

std::string Scratch::write(std::string_view name, const std::uint8_t* data, std::size_t size) {
  const std::string path = m_folder + "/" + std::string(name);
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  out.close();
  require(out.good());
  return path;
}

void Scratch::link(std::string_view name, const std::string& target) {
  const std::filesystem::path path = m_folder + "/" + std::string(name);
  std::error_code ignored;
  if (!std::filesystem::is_symlink(path, ignored)) std::filesystem::create_symlink(target, path);
}

Scratch& scratch() {
  static Scratch folder;
  return folder;
}

}  // namespace openvcu::fuzz
