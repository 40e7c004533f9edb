// Issue 22: Service::open runs the whole-vehicle checks (check::checkVehicle) and refuses to
// start on their first error, before it opens the signal table or the event bus. Inside the
// sandbox: a broken hook would go on to open them.
#include <doctest/doctest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "harness.hpp"
#include "openvcu/service/service.hpp"
#include "skip.hpp"

namespace harness = openvcu::harness;
namespace service = openvcu::service;
namespace fs = std::filesystem;

TEST_CASE("Service::open refuses a vehicle whose files clash as a whole, with the whole-vehicle error (#22)") {
  if (!harness::isolated()) OPENVCU_SKIP(harness::NOT_ISOLATED);
  // config/hhea with the charger's NmStationAddress set to the battery's (0xF3): each file
  // loads on its own, the two together do not
  const fs::path folder = fs::temp_directory_path() / ("openvcu-service-check-" + std::to_string(::getpid()));
  fs::remove_all(folder);
  fs::create_directories(folder);
  for (const auto& entry : fs::directory_iterator(fs::path(OPENVCU_SOURCE_DIR) / "config/hhea")) {
    if (entry.is_regular_file()) fs::copy_file(entry.path(), folder / entry.path().filename());
  }
  std::string dbc;
  {
    std::ifstream in(folder / "hhea.dbc");
    dbc.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  const std::string charger = "BA_ \"NmStationAddress\" BU_ OBC 229;";
  REQUIRE(dbc.find(charger) != std::string::npos);
  dbc.replace(dbc.find(charger), charger.size(), "BA_ \"NmStationAddress\" BU_ OBC 243;");
  std::ofstream(folder / "hhea.dbc") << dbc;
  service::ServiceOptions options;
  options.configPath = (folder / "vehicle.json").string();
  service::ServiceInfo info;
  info.name = "fixture";
  info.program = "vcu-demo";
  info.writerId = 0xF0;

  const auto refused = service::Service::open(info, options);

  REQUIRE_FALSE(refused.ok());
  const std::string text = refused.error().toString();
  CHECK_MESSAGE(
      text.find("hhea.dbc: bus 'vehicle': J1939 source address 0xF3 (243) is used by 2 nodes") != std::string::npos,
      text);
  CHECK(text.find("OBC (NmStationAddress)") != std::string::npos);
  fs::remove_all(folder);
}
