// The chosen signals' pass and the event lanes of makeReport() (report_job.cpp).
#include "report_passes.hpp"

#include <algorithm>
#include <optional>
#include <string_view>
#include <utility>

#include "openvcu/config/catalog.hpp"
#include "openvcu/ipc/event_log.hpp"
#include "openvcu/trace/frame_decoder.hpp"

namespace openvcu::trace::detail {
namespace {

/// Min and max of each of SIGNAL_BUCKETS equal slices of [0, durationS]: the points a chart
/// needs whatever the number of samples.
class BucketedSeries {
 public:
  explicit BucketedSeries(double durationS) : m_durationS(durationS > 0 ? durationS : 1.0), m_buckets(SIGNAL_BUCKETS) {}

  void add(double s, double value) {
    if (!(value == value)) return;  // NaN: not drawn
    const auto index = std::min(SIGNAL_BUCKETS - 1, static_cast<std::size_t>(std::max(0.0, s) / m_durationS *
                                                                             static_cast<double>(SIGNAL_BUCKETS)));
    Bucket& bucket = m_buckets[index];
    if (bucket.count == 0 || value < bucket.min.second) bucket.min = {s, value};
    if (bucket.count == 0 || value > bucket.max.second) bucket.max = {s, value};
    ++bucket.count;
  }

  [[nodiscard]] std::vector<std::pair<double, double>> points() const {
    std::vector<std::pair<double, double>> out;
    for (const Bucket& bucket : m_buckets) {
      if (bucket.count == 0) continue;
      if (bucket.count == 1 || bucket.min == bucket.max) {
        out.push_back(bucket.min);
      } else if (bucket.min.first <= bucket.max.first) {
        out.push_back(bucket.min);
        out.push_back(bucket.max);
      } else {
        out.push_back(bucket.max);
        out.push_back(bucket.min);
      }
    }
    return out;
  }

 private:
  struct Bucket {
    std::pair<double, double> min{}, max{};
    std::uint64_t count{};
  };
  double m_durationS;
  std::vector<Bucket> m_buckets;
};

/// MESSAGE.SIGNAL, or the signal table's key of a bus signal (config::signalKey:
/// TRANSMITTER.MESSAGE.SIGNAL, as `vcu signal list` shows it).
std::optional<SignalRef> findSignalByName(const dbc::Database& database, const std::string& name) {
  if (std::optional<SignalRef> ref = findSignal(database, name)) return ref;
  const std::size_t dot = name.find('.');
  if (dot == std::string::npos) return std::nullopt;
  std::optional<SignalRef> ref = findSignal(database, std::string_view(name).substr(dot + 1));
  if (!ref) return std::nullopt;
  const dbc::Message& message = database.messages[static_cast<std::size_t>(ref->message)];
  if (config::signalKey(message, message.signals[ref->signal]) != name) return std::nullopt;
  return ref;
}

Severity faultSeverity(ipc::FaultSeverity severity) {
  switch (severity) {
    case ipc::FaultSeverity::Info:
      return Severity::Info;
    case ipc::FaultSeverity::Warning:
      return Severity::Warning;
    default:
      return Severity::Fault;
  }
}

}  // namespace

Error cancelledError() {
  return Error{"cancelled"};
}

std::vector<SignalRef> resolveSignals(const dbc::Database& database, const std::vector<std::string>& names,
                                      std::vector<Error>& errors) {
  std::vector<SignalRef> refs;
  for (const std::string& name : names) {
    std::optional<SignalRef> ref = findSignalByName(database, name);
    if (!ref) {
      errors.push_back(Error{"signal " + name +
                             ": no such signal in the DBC (MESSAGE.SIGNAL as `vcu dbc info` lists them, or the table "
                             "key NODE.MESSAGE.SIGNAL as `vcu signal list` does)"});
      continue;
    }
    refs.push_back(*ref);
  }
  return refs;
}

Result<std::vector<SignalSeries>> extractSignalSeries(const ReportJob& job, const std::vector<std::string>& logs,
                                                      const std::vector<SignalRef>& refs, std::int64_t startNs,
                                                      double durationS) {
  std::vector<SignalSeries> series;
  if (refs.empty()) return series;
  // The logs' problems were listed by the first pass.
  Result<LogTimeline> timelineResult = LogTimeline::open(logs, job.setup);
  if (!timelineResult) return timelineResult.error();
  const dbc::Database& database = job.setup.database;
  FrameDecoder decoder(database, job.setup.match);
  std::vector<BucketedSeries> buckets(refs.size(), BucketedSeries(durationS));
  FrameBudget budget(job);
  TraceFrame frame;
  while (budget.allowsAnother() && timelineResult->next(frame)) {
    if (frame.message < 0) continue;
    bool decoded = false;
    std::span<const SignalValue> values;
    for (std::size_t i = 0; i < refs.size(); ++i) {
      if (refs[i].message != frame.message) continue;
      if (!decoded) {
        values = decoder.decode(frame.frame, frame.message);
        decoded = true;
      }
      for (const SignalValue& value : values) {
        if (value.signalIndex == refs[i].signal) {
          buckets[i].add(static_cast<double>(frame.timeNs - startNs) / 1e9, value.value.physical);
        }
      }
    }
  }
  if (budget.cancelled()) return cancelledError();
  for (std::size_t i = 0; i < refs.size(); ++i) {
    const dbc::Message& message = database.messages[static_cast<std::size_t>(refs[i].message)];
    const dbc::Signal& signal = message.signals[refs[i].signal];
    series.push_back(SignalSeries{message.name + "." + signal.name, signal.unit, buckets[i].points()});
  }
  return series;
}

std::vector<EventLane> recordedEventLanes(const std::string& path, std::int64_t startNs, std::vector<Error>& errors) {
  std::vector<EventLane> lanes;
  auto eventsResult = ipc::readEventLog(path);
  if (!eventsResult) {
    errors.push_back(eventsResult.error());
    return lanes;
  }
  const auto seconds = [startNs](std::int64_t ns) { return static_cast<double>(ns - startNs) / 1e9; };
  EventLane states{"FSM state", {}};
  for (const ipc::FsmTransition& transition : eventsResult->transitions) {
    states.events.push_back(ReportEvent{seconds(transition.timestampNs), transition.toState, Severity::Info});
  }
  EventLane faults{"Faults", {}};
  for (const ipc::FaultEvent& fault : eventsResult->faults) {
    faults.events.push_back(ReportEvent{seconds(fault.timestampNs),
                                        (fault.active ? "raised " : "cleared ") + fault.name,
                                        fault.active ? faultSeverity(fault.severity) : Severity::Info});
  }
  lanes.push_back(std::move(states));
  lanes.push_back(std::move(faults));
  if (eventsResult->undecodable > 0 || eventsResult->dropped > 0) {
    errors.push_back(Error{std::to_string(eventsResult->undecodable) + " events did not decode, " +
                               std::to_string(eventsResult->dropped) + " beyond the limit were left out",
                           Location{path, 0, 0, {}}, openvcu::Severity::Warning});
  }
  return lanes;
}

}  // namespace openvcu::trace::detail
