#include "web_reports.hpp"

#include <nlohmann/json.hpp>

#include "openvcu/trace/report_job.hpp"

namespace openvcu::web {
namespace {

/// Frames one report reads at most: an upload of 256 MB of candump -L is about 5 million
/// frames; this bounds the worker's time on a bigger one (the report says it was cut short).
constexpr std::uint64_t MAX_REPORT_FRAMES = 20'000'000;

}  // namespace

TraceReports::TraceReports(std::string vehiclePath) : m_vehiclePath(std::move(vehiclePath)) {}

Result<trace::AnalysisSetup> TraceReports::setup() {
  if (!m_setup) {
    auto loaded = trace::loadSetupFromConfig(m_vehiclePath);
    if (!loaded) return loaded.error();
    m_setup = std::move(*loaded);
  }
  return *m_setup;
}

Result<trace::ReportJob> TraceReports::job(const std::string& path, bool folder) {
  auto vehicle = setup();
  if (!vehicle) return vehicle.error();
  trace::ReportJob made;
  if (folder) {
    auto found = trace::jobForFolder(path, std::move(*vehicle));
    if (!found) return found.error();
    made = std::move(*found);
  } else {
    made.setup = std::move(*vehicle);
    made.logs = {path};
  }
  made.maxFrames = MAX_REPORT_FRAMES;
  return made;
}

Result<std::string> TraceReports::report(const std::string& path, bool folder) {
  const std::lock_guard lock(m_mutex);
  auto jobResult = job(path, folder);
  if (!jobResult) return jobResult.error();
  auto made = trace::makeReport(*jobResult);
  if (!made) return made.error();
  return std::move(made->html);
}

Result<std::string> TraceReports::summary(const std::string& path, bool folder) {
  const std::lock_guard lock(m_mutex);
  auto jobResult = job(path, folder);
  if (!jobResult) return jobResult.error();
  std::vector<Error> inputErrors;
  auto summary = trace::summarize(*jobResult, &inputErrors);
  if (!summary) return summary.error();
  nlohmann::json buses = nlohmann::json::array();
  for (const trace::BusSummary& bus : summary->busLoad) {
    buses.push_back({{"name", bus.name}, {"frames", bus.frames}, {"loadMeanPct", bus.loadMeanPct},
                     {"loadMaxPct", bus.loadMaxPct}});
  }
  nlohmann::json problems = nlohmann::json::array();
  for (std::size_t i = 0; i < inputErrors.size() && i < 20; ++i) problems.push_back(inputErrors[i].toString());
  const nlohmann::json out = {{"frames", summary->frames},
                              {"durationS", summary->durationS},
                              {"buses", summary->buses},
                              {"busLoad", std::move(buses)},
                              {"messages", summary->messages},
                              {"findings", {{"errors", summary->errors}, {"warnings", summary->warnings},
                                            {"infos", summary->infos}}},
                              {"malformedLines", summary->malformedLines},
                              {"truncated", summary->truncated},
                              {"inputErrors", std::move(problems)}};
  return out.dump();
}

}  // namespace openvcu::web
