// TEMPORARY STUB (drop at merge): a simple TraceStats so that the HMI links and its
// Statistics page can be developed before the real stats.cpp (branch wt-stats) is merged.
// It keeps every period in memory (unbounded: not for real logs), fixed 1 s load windows,
// and writes no text or JSON. The real implementation replaces this file entirely.
#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>

#include "openvcu/can/wire_time.hpp"
#include "openvcu/trace/stats.hpp"

namespace openvcu::trace {

struct TraceStats::Impl {
  const AnalysisSetup* setup{};
  struct Bus {
    std::uint64_t frames{}, errors{};
    std::int64_t first{-1}, last{};
    std::int64_t wireNs{};
    std::map<std::int64_t, std::int64_t> windows;  // window index -> wire ns
  };
  struct Stream {
    std::uint64_t count{};
    std::int64_t last{};
    std::int32_t message{-1};
    std::vector<std::int64_t> periods;
  };
  struct Node {
    std::uint64_t frames{};
    std::int64_t wireBits{};
  };
  std::int64_t start{-1};
  std::uint64_t frames{};
  std::map<std::uint16_t, Bus> buses;
  std::map<std::tuple<std::uint16_t, bool, std::uint32_t>, Stream> streams;
  std::map<std::tuple<std::uint16_t, bool, std::uint8_t>, Node> nodes;
};

TraceStats::TraceStats(const AnalysisSetup& setup) : m_impl(std::make_unique<Impl>()) {
  m_impl->setup = &setup;
}
TraceStats::TraceStats(TraceStats&&) noexcept = default;
TraceStats& TraceStats::operator=(TraceStats&&) noexcept = default;
TraceStats::~TraceStats() = default;

void TraceStats::add(const TraceFrame& frame) {
  Impl& s = *m_impl;
  if (s.start < 0) s.start = frame.timeNs;
  ++s.frames;
  Impl::Bus& bus = s.buses[frame.bus];
  if (bus.first < 0) bus.first = frame.timeNs;
  bus.last = frame.timeNs;
  ++bus.frames;
  if ((frame.frame.flags & can::FLAG_ERROR) != 0) {
    ++bus.errors;
    return;
  }
  const std::int64_t wire = can::wireTimeNs(frame.frame, 500'000, 2'000'000);
  bus.wireNs += wire;
  bus.windows[(frame.timeNs - s.start) / LOAD_WINDOW_NS] += wire;
  Impl::Stream& stream = s.streams[{frame.bus, frame.frame.extended(), frame.frame.id}];
  if (stream.count > 0 && frame.timeNs >= stream.last) stream.periods.push_back(frame.timeNs - stream.last);
  stream.last = frame.timeNs;
  stream.message = frame.message;
  ++stream.count;
  const bool standard = !frame.frame.extended();
  Impl::Node& node = s.nodes[{frame.bus, standard, standard ? 0 : static_cast<std::uint8_t>(frame.frame.id & 0xFFu)}];
  ++node.frames;
  node.wireBits += can::frameBits(frame.frame);
}

StatsReport TraceStats::finish(const std::vector<std::string>& names) const {
  const Impl& s = *m_impl;
  StatsReport report;
  report.frames = s.frames;
  std::int64_t end = s.start;
  for (const auto& [index, bus] : s.buses) end = std::max(end, bus.last);
  report.startS = static_cast<double>(s.start) / 1e9;
  report.durationS = static_cast<double>(end - s.start) / 1e9;
  const auto name = [&](std::uint16_t index) { return index < names.size() ? names[index] : std::string("?"); };
  std::map<std::uint16_t, double> busSeconds;
  std::map<std::uint16_t, std::int64_t> busBits;
  for (const auto& [index, bus] : s.buses) {
    BusStats out;
    out.bus = name(index);
    out.bitrate = s.setup->bus(out.bus).bitrate;
    out.frames = bus.frames;
    out.errorFrames = bus.errors;
    out.durationS = static_cast<double>(bus.last - bus.first) / 1e9;
    busSeconds[index] = out.durationS;
    out.loadMeanPct = out.durationS > 0 ? 100.0 * static_cast<double>(bus.wireNs) / (out.durationS * 1e9) : 0;
    out.loadBucketS = static_cast<double>(LOAD_WINDOW_NS) / 1e9;
    for (const auto& [window, wire] : bus.windows) {
      const double pct = 100.0 * static_cast<double>(wire) / static_cast<double>(LOAD_WINDOW_NS);
      out.loadMaxPct = std::max(out.loadMaxPct, pct);
      out.loadSeries.emplace_back(static_cast<double>(window) * out.loadBucketS, pct);
    }
    report.buses.push_back(std::move(out));
  }
  for (const auto& [key, node] : s.nodes) busBits[std::get<0>(key)] += node.wireBits;
  for (const auto& [key, node] : s.nodes) {
    NodeStats out;
    out.bus = name(std::get<0>(key));
    out.standard = std::get<1>(key);
    out.sa = std::get<2>(key);
    if (!out.standard) out.name = s.setup->nodeNames[out.sa];
    out.frames = node.frames;
    const double seconds = busSeconds[std::get<0>(key)];
    out.bitsPerS = seconds > 0 ? static_cast<double>(node.wireBits) / seconds : 0;
    const std::int64_t all = busBits[std::get<0>(key)];
    out.sharePct = all > 0 ? 100.0 * static_cast<double>(node.wireBits) / static_cast<double>(all) : 0;
    report.nodes.push_back(std::move(out));
  }
  std::stable_sort(report.nodes.begin(), report.nodes.end(), [](const NodeStats& a, const NodeStats& b) {
    return a.bus != b.bus ? a.bus < b.bus : a.bitsPerS > b.bitsPerS;
  });
  for (const auto& [key, stream] : s.streams) {
    MessageStats out;
    out.bus = name(std::get<0>(key));
    out.extended = std::get<1>(key);
    out.id = std::get<2>(key);
    out.sa = out.extended ? static_cast<std::uint8_t>(out.id & 0xFFu) : 0;
    out.count = stream.count;
    if (stream.message >= 0 && static_cast<std::size_t>(stream.message) < s.setup->database.messages.size()) {
      const auto m = static_cast<std::size_t>(stream.message);
      out.name = s.setup->database.messages[m].name;
      if (m < s.setup->expectedCycleNs.size()) out.expectedMs = static_cast<double>(s.setup->expectedCycleNs[m]) / 1e6;
      if (m < s.setup->cycleSource.size()) out.cycleSource = s.setup->cycleSource[m];
    }
    std::vector<std::int64_t> periods = stream.periods;
    std::sort(periods.begin(), periods.end());
    if (!periods.empty()) {
      double sum = 0;
      for (const std::int64_t p : periods) sum += static_cast<double>(p);
      out.meanMs = sum / static_cast<double>(periods.size()) / 1e6;
      const auto at = [&](double q) {
        const auto rank = static_cast<std::size_t>(std::ceil(q * static_cast<double>(periods.size())));
        return static_cast<double>(periods[std::max<std::size_t>(rank, 1) - 1]) / 1e6;
      };
      out.p50Ms = at(0.5);
      out.p99Ms = at(0.99);
      out.maxMs = static_cast<double>(periods.back()) / 1e6;
      out.minMs = static_cast<double>(periods.front()) / 1e6;
    }
    if (out.expectedMs > 0) {
      out.deviationMs = out.meanMs - out.expectedMs;
      for (const std::int64_t p : periods) {
        const double ms = static_cast<double>(p) / 1e6;
        if (ms > 1.5 * out.expectedMs) {
          ++out.gaps;
          out.missing += static_cast<std::uint64_t>(std::llround(ms / out.expectedMs) - 1);
        }
      }
    }
    report.messages.push_back(std::move(out));
  }
  return report;
}

void appendStatsText(std::string& out, const StatsReport&) { out += "(stub)\n"; }
void appendStatsJson(std::string& out, const StatsReport&) { out += "{}"; }

}  // namespace openvcu::trace
