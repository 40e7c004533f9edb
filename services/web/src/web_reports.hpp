#pragma once
// The trace analysis of a recording folder or an uploaded log for vcu-web (shared/trace's
// report pipeline, the same as `vcu trace report` and `vcu trace stats|check`), with the
// vehicle's DBC files and schedule.
//
//   web::TraceReports reports("config/hhea/vehicle.json");
//   auto html = reports.report("/var/lib/openvcu/recordings/drive1", true);  // the whole HTML document
//   auto json = reports.summary("/var/lib/openvcu/uploads/bench.log", false); // {"frames":...}

#include <mutex>
#include <optional>
#include <string>

#include "openvcu/core/result.hpp"
#include "openvcu/trace/report_job.hpp"
#include "openvcu/trace/timeline.hpp"

namespace openvcu::web {

/// @note thread-safe (a mutex); blocks for as long as the analysis takes: call on a worker.
class TraceReports {
 public:
  explicit TraceReports(std::string vehiclePath);
  /// The self-contained HTML report; `folder`: a `vcu record` folder (its *.log and events.lcmlog), else one log file.
  Result<std::string> report(const std::string& path, bool folder);
  /// {"frames","durationS","buses":[...],"findings":{"errors","warnings"}} as JSON text.
  Result<std::string> summary(const std::string& path, bool folder);

 private:
  Result<trace::AnalysisSetup> setup();
  /// The job for a folder or a log, read at most MAX_REPORT_FRAMES frames.
  Result<trace::ReportJob> job(const std::string& path, bool folder);
  std::string m_vehiclePath;
  std::mutex m_mutex;
  std::optional<trace::AnalysisSetup> m_setup;
};

}  // namespace openvcu::web
