// vcu-telemetry: this VCU's state, faults, service health and chosen signals to an MQTT broker,
// through a disk queue that keeps them across link outages (docs/design/telemetry.md).
// `vcu-telemetry --config vehicle.json` (vehicle.json's "telemetry" names telemetry.json).

#include "openvcu/config/services.hpp"
#include "openvcu/service/service.hpp"
#include "telemetry_app.hpp"

namespace service = openvcu::service;
namespace telemetry = openvcu::telemetry;

int main(int argc, char** argv) {
  const openvcu::config::ServiceEntry& entry = openvcu::config::serviceEntry(openvcu::config::ServiceId::Telemetry);
  const service::ServiceInfo info{.name = std::string(entry.name),
                                  .program = {},
                                  .description = "Fleet telemetry: state, faults, health and the configured signals "
                                                 "to an MQTT broker (telemetry.json), queued on disk while it is away",
                                  .version = {},
                                  .writerId = entry.writer,
                                  .usesFrameStreams = false};
  telemetry::TelemetryOverrides overrides;
  service::CommandLine commandLine(info);
  commandLine.addOption("--queue-folder", overrides.queueFolder, "the disk queue's folder instead of telemetry.json's");
  commandLine.addOption("--vehicle-id", overrides.vehicleId, "the vehicle id (topic openvcu/<id>/...) instead of telemetry.json's");
  commandLine.addOption("--broker", overrides.broker, "mqtt://HOST[:PORT] instead of telemetry.json's (same scheme)");
  if (const auto maybeExit = commandLine.parseOrExit(argc, argv)) return *maybeExit;
  auto serviceResult = service::Service::open(info, commandLine.options());
  if (!serviceResult) return service::reportStartupError(info, serviceResult.error());
  service::Service& runtime = **serviceResult;
  auto appResult = telemetry::TelemetryApp::create(runtime, overrides);
  if (!appResult) return service::reportStartupError(info, appResult.error());
  return runtime.run();
}
