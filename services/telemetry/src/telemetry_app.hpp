#pragma once
// vcu-telemetry's application (docs/design/telemetry.md): the events and the signal table into
// the engine, its records through the disk queue, the queue to the broker through the sender.
// Everything but libmosquitto's network thread runs on the service's loop thread:
//   every 10 ms  engine.sample (the configured signals), sender.pump (acks, hand-outs)
//   every 1 s    engine.tick -> one queue batch (one fdatasync), then sender.pump
//   sender.wakeFd() readable (a connect; half the window confirmed while records wait): sender.pump
//
//   auto appResult = telemetry::TelemetryApp::create(runtime, overrides);
//   return runtime.run();

#include <memory>
#include <string>
#include <vector>

#include "openvcu/core/result.hpp"
#include "openvcu/service/service.hpp"

namespace openvcu::telemetry {

/// Command-line overrides of telemetry.json (empty: the file's value).
struct TelemetryOverrides {
  std::string queueFolder;  ///< --queue-folder DIR
  std::string vehicleId;    ///< --vehicle-id ID (several simulated vehicles from one configuration)
  std::string broker;       ///< --broker URL
};

struct TelemetryAppImpl;

/// @note restricted thread-safe: created and destroyed on the service's loop thread.
class TelemetryApp {
 public:
  static Result<std::unique_ptr<TelemetryApp>> create(service::Service& runtime, const TelemetryOverrides& overrides);
  ~TelemetryApp();
  TelemetryApp(const TelemetryApp&) = delete;
  TelemetryApp& operator=(const TelemetryApp&) = delete;

 private:
  explicit TelemetryApp(std::unique_ptr<TelemetryAppImpl> impl);
  std::unique_ptr<TelemetryAppImpl> m_impl;
};

/// "sha256:<hex>" of the files' bytes in order (each preceded by its name); an error names a file it cannot read.
Result<std::string> hashFiles(const std::vector<std::string>& files);

}  // namespace openvcu::telemetry
