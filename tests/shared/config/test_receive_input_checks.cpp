// Issue #19, "every bad input refused", for can-rx's receive.json: it is read through the
// one JSON reader (a key given twice refuses it with both places), and a numeric CAN ID
// above 29 bits is refused instead of being cut to its low 32 bits.

#include <doctest/doctest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "openvcu/config/receive.hpp"

using namespace openvcu;
namespace fs = std::filesystem;

namespace {

const std::string DATA = std::string(OPENVCU_SOURCE_DIR) + "/tests/data/can-rx/";

Result<config::ReceiveConfig> loadText(const std::string& text) {
  auto loaded = config::loadVehicleConfig(DATA + "vehicle.json");
  REQUIRE_MESSAGE(loaded, (loaded ? "" : loaded.error().toString()));
  const fs::path file = fs::temp_directory_path() / ("receive-input-" + std::to_string(::getpid()) + ".json");
  std::ofstream(file) << text;
  loaded->receiveFile = file.string();
  auto result = config::loadReceiveConfig(*loaded);
  fs::remove(file);
  return result;
}

}  // namespace

TEST_CASE("#19 a receive file with a key given twice is refused with both places") {
  const auto sut = loadText("{\"timeoutFactor\": 3,\n \"timeoutFactor\": 1}");
  REQUIRE_FALSE(sut);
  CHECK(sut.error().toString().ends_with(".json:2:2: /: key \"timeoutFactor\" given twice (first at 1:2)"));
}

TEST_CASE("#19 a numeric forwarding ID above 29 bits is refused, not truncated") {
  constexpr std::uint64_t ID_33_BITS = 0x100000123;  // was taken as 0x123
  const auto sut = loadText(R"({"forward": [{"from": "a", "to": "b", "id": )" + std::to_string(ID_33_BITS) + "}]}");
  REQUIRE_FALSE(sut);
  CHECK(sut.error().toString().find("/forward/0/id") != std::string::npos);
}
