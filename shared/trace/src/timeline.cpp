// AnalysisSetup from a vehicle configuration or DBC files, and LogTimeline: several CAN
// logs merged by time, one pending record per log.
#include "openvcu/trace/timeline.hpp"

#include <algorithm>
#include <limits>
#include <utility>

#include "openvcu/can/log_reader.hpp"
#include "openvcu/config/catalog.hpp"
#include "openvcu/config/receive.hpp"
#include "openvcu/config/vehicle.hpp"
#include "openvcu/dbc/parser.hpp"
#include "openvcu/schedule/schedule_config.hpp"
#include "openvcu/trace/frame_decoder.hpp"

namespace openvcu::trace {
namespace {

constexpr std::int64_t NS_PER_MS = 1'000'000;

/// Cycles and node names from the database alone.
void fillFromDatabase(AnalysisSetup& setup) {
  const std::size_t count = setup.database.messages.size();
  setup.expectedCycleNs.assign(count, 0);
  setup.cycleSource.assign(count, CycleSource::None);
  for (std::size_t m = 0; m < count; ++m) {
    const dbc::Message& message = setup.database.messages[m];
    if (message.cycleTimeMs) {
      setup.expectedCycleNs[m] = static_cast<std::int64_t>(*message.cycleTimeMs) * NS_PER_MS;
      setup.cycleSource[m] = CycleSource::Attribute;
    }
    if (!message.extended || message.pseudo || message.transmitter.empty() || message.transmitter == dbc::NO_NODE) {
      continue;
    }
    // Several DBC nodes may send with one address (hhea.dbc: the VCU's HC*_Demands and the
    // HVLP string's HS* feedback both use 0x71): all are named, in DBC order.
    std::string& name = setup.nodeNames[message.id & 0xFFu];
    const std::string& node = message.transmitter;
    bool listed = false;
    for (std::size_t start = 0; start <= name.size() && !name.empty();) {
      const std::size_t end = std::min(name.find('/', start), name.size());
      if (name.compare(start, end - start, node) == 0) listed = true;
      start = end + 1;
    }
    if (!listed) name += (name.empty() ? "" : "/") + node;
  }
}

}  // namespace

AnalysisBus AnalysisSetup::bus(const std::string& name) const {
  for (const AnalysisBus& known : buses) {
    if (known.name == name) return known;
  }
  AnalysisBus defaults;
  defaults.name = name;
  return defaults;
}

AnalysisSetup emptySetup() {
  AnalysisSetup setup;
  setup.source = "no DBC";
  return setup;
}

Result<AnalysisSetup> loadSetupFromDbc(const std::vector<std::string>& paths) {
  auto databaseResult = dbc::loadFiles(paths);
  if (!databaseResult) return databaseResult.error();
  AnalysisSetup setup;
  for (const std::string& path : paths) setup.source += (setup.source.empty() ? "" : ", ") + path;
  setup.database = std::move(*databaseResult);
  fillFromDatabase(setup);
  return setup;
}

Result<AnalysisSetup> loadSetupFromConfig(const std::string& path) {
  auto vehicleResult = config::loadVehicleConfig(path);
  if (!vehicleResult) return vehicleResult.error();
  const config::VehicleConfig& vehicle = *vehicleResult;
  auto catalogResult = config::buildCatalog(vehicle);
  if (!catalogResult) return catalogResult.error();
  auto scheduleResult = schedule::loadSchedule(vehicle, *catalogResult);
  if (!scheduleResult) return scheduleResult.error();
  auto receiveResult = config::loadReceiveConfig(vehicle);
  if (!receiveResult) return receiveResult.error();

  AnalysisSetup setup;
  setup.source = path;
  setup.database = vehicle.database;
  fillFromDatabase(setup);
  for (const config::BusConfig& bus : vehicle.buses) {
    setup.buses.push_back(AnalysisBus{bus.name, bus.bitrate, bus.dataBitrate});
  }
  for (const schedule::ScheduledMessage& scheduled : scheduleResult->messages) {
    const auto index = static_cast<std::int32_t>(scheduled.message);
    if (scheduled.cycleNs > 0) {
      setup.expectedCycleNs[scheduled.message] = scheduled.cycleNs;
      setup.cycleSource[scheduled.message] = CycleSource::Schedule;
    }
    if (scheduled.safetyDeltaNs) {
      const std::int64_t cycle = scheduled.cycleNs > 0 ? scheduled.cycleNs : 0;
      setup.safetyPairs.push_back(SafetyPairSetup{
          index, scheduled.canId, *scheduled.safetyDeltaNs, DEFAULT_SRVT_NS,
          cycle > 0 ? DEFAULT_SCT_CYCLES * cycle : std::numeric_limits<std::int64_t>::max(),
          scheduled.group ? scheduleResult->groups[*scheduled.group].name : std::string()});
    }
  }
  for (const config::SafetyGroup& group : receiveResult->safety) {
    const dbc::Message& message = setup.database.messages[group.dataMessage];
    setup.safetyPairs.push_back(SafetyPairSetup{static_cast<std::int32_t>(group.dataMessage), message.id, 0,
                                                group.maxHeaderToDataNs, group.maxHeaderCycleNs, {}});
  }
  return setup;
}

// --- LogTimeline ------------------------------------------------------------------------

struct LogTimeline::Impl {
  struct Source {
    can::LogReader reader;
    TraceFrame pending{};
    bool hasPending{};
    std::int64_t lastTimeNs{std::numeric_limits<std::int64_t>::min()};
  };

  std::vector<Source> sources;
  std::vector<LogCounts> counts;
  std::vector<std::string> buses;
  dbc::MessageMatcher matcher;
  ErrorHandler onError;
  std::int64_t startNs{};
  bool started{};

  std::uint16_t busIndex(std::string_view channel) {
    for (std::size_t i = 0; i < buses.size(); ++i) {
      if (buses[i] == channel) return static_cast<std::uint16_t>(i);
    }
    buses.emplace_back(channel);
    return static_cast<std::uint16_t>(buses.size() - 1);
  }

  /// Reads the next usable record of source `s` into its pending slot.
  void refill(std::size_t s) {
    Source& source = sources[s];
    LogCounts& count = counts[s];
    source.hasPending = false;
    while (std::optional<can::LogRecord> record = source.reader.next()) {
      if (!record->hasTime) {
        ++count.untimed;
        continue;
      }
      TraceFrame& frame = source.pending;
      frame.frame = record->frame;
      frame.timeNs = loggedTimeNs(*record, source.reader.format());
      frame.frame.timestampNs = frame.timeNs;
      frame.bus = busIndex(record->channel);
      frame.log = static_cast<std::uint16_t>(s);
      frame.line = record->line;
      const bool isError = (frame.frame.flags & can::FLAG_ERROR) != 0;
      frame.message = isError ? -1 : matcher.match(frame.frame.id, frame.frame.extended());
      if (frame.timeNs < source.lastTimeNs) {
        if (count.backwards == 0 && onError) {
          onError(Error{"time goes backwards (" + std::to_string(frame.timeNs - source.lastTimeNs) +
                            " ns); the periods across such steps are not measured",
                        Location{count.path, static_cast<std::uint32_t>(record->line), 0, {}}, openvcu::Severity::Warning});
        }
        ++count.backwards;
      }
      source.lastTimeNs = frame.timeNs;
      if (isError) ++count.errorFrames;
      source.hasPending = true;
      return;
    }
    count.malformedLines = source.reader.errorCount();
  }
};

LogTimeline::LogTimeline(std::unique_ptr<Impl> impl) noexcept : m_impl(std::move(impl)) {}
LogTimeline::LogTimeline(LogTimeline&&) noexcept = default;
LogTimeline& LogTimeline::operator=(LogTimeline&&) noexcept = default;
LogTimeline::~LogTimeline() = default;

Result<LogTimeline> LogTimeline::open(const std::vector<std::string>& paths, const AnalysisSetup& setup,
                                      ErrorHandler onError) {
  auto impl = std::make_unique<Impl>();
  impl->matcher = dbc::MessageMatcher(setup.database, setup.match);
  impl->onError = std::move(onError);
  impl->sources.reserve(paths.size());
  for (const std::string& path : paths) {
    Result<can::LogReader> readerResult = can::LogReader::open(path);
    if (!readerResult) return readerResult.error();
    impl->sources.push_back(Impl::Source{std::move(*readerResult)});
    LogCounts count;
    count.path = path;
    impl->counts.push_back(std::move(count));
  }
  Impl* raw = impl.get();
  for (std::size_t s = 0; s < raw->sources.size(); ++s) {
    raw->sources[s].reader.setErrorHandler([raw](const Error& error) {
      if (raw->onError) raw->onError(error);
    });
  }
  for (std::size_t s = 0; s < raw->sources.size(); ++s) raw->refill(s);
  return LogTimeline(std::move(impl));
}

bool LogTimeline::next(TraceFrame& frame) {
  Impl& impl = *m_impl;
  std::size_t best = impl.sources.size();
  for (std::size_t s = 0; s < impl.sources.size(); ++s) {
    if (!impl.sources[s].hasPending) continue;
    if (best == impl.sources.size() || impl.sources[s].pending.timeNs < impl.sources[best].pending.timeNs) best = s;
  }
  if (best == impl.sources.size()) {
    for (std::size_t s = 0; s < impl.sources.size(); ++s) impl.counts[s].malformedLines = impl.sources[s].reader.errorCount();
    return false;
  }
  frame = impl.sources[best].pending;
  ++impl.counts[best].frames;
  if (!impl.started) {
    impl.started = true;
    impl.startNs = frame.timeNs;
  }
  impl.refill(best);
  return true;
}

const std::vector<std::string>& LogTimeline::buses() const noexcept { return m_impl->buses; }
const std::vector<LogCounts>& LogTimeline::counts() const noexcept { return m_impl->counts; }
std::int64_t LogTimeline::startNs() const noexcept { return m_impl->startNs; }

}  // namespace openvcu::trace
