// TraceStats: bus load (exact wire bits, sliding window, series), per-node traffic and
// per-stream period statistics, accumulated frame by frame in bounded memory.
//
//   stream 0x18FEF121 on can0, frames at 0, 10, 20, 45 ms with GenMsgCycleTime 10 ms
//   -> periods 10, 10, 25 ms: mean 15 ms, max 25 ms, 1 gap (25 > 15), 1 missing (round(2.5) - 1 = 2 - 1)
#include "openvcu/trace/stats.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <limits>

#include "openvcu/can/wire_time.hpp"

namespace openvcu::trace {
namespace {

constexpr double NS_PER_S = 1e9;
constexpr double NS_PER_MS = 1e6;
constexpr double PERCENT = 100.0;

/// Buckets of the sliding window (1 s / 10 ms = 100).
constexpr std::size_t LOAD_BUCKETS = static_cast<std::size_t>(LOAD_WINDOW_NS / LOAD_STEP_NS);
static_assert(LOAD_WINDOW_NS % LOAD_STEP_NS == 0);

/// Period histogram: linear bins centred on multiples of PERIOD_BIN_NS up to
/// PERIOD_LINEAR_NS (bin i holds [i - 0.5, i + 0.5) x PERIOD_BIN_NS, so an exact 10 ms cycle
/// reads 10.000), PERIOD_OCTAVE_BINS per octave above it up to PERIOD_RANGE_NS, one
/// overflow bin. 2,770 32-bit counters = 11 KB per stream with at least one period
/// (45 MB for MAX_STREAMS such streams).
constexpr std::int64_t HALF_BIN_NS = PERIOD_BIN_NS / 2;
constexpr std::size_t LINEAR_BINS = static_cast<std::size_t>(PERIOD_LINEAR_NS / PERIOD_BIN_NS) + 1;
constexpr int PERIOD_OCTAVES = 6;
static_assert((PERIOD_LINEAR_NS << PERIOD_OCTAVES) == PERIOD_RANGE_NS);
constexpr std::size_t HISTOGRAM_BINS =
    LINEAR_BINS + static_cast<std::size_t>(PERIOD_OCTAVES * PERIOD_OCTAVE_BINS) + 1;
constexpr std::size_t OVERFLOW_BIN = HISTOGRAM_BINS - 1;

/// Index of the stream table: open addressing, twice MAX_STREAMS slots (load <= 0.5).
constexpr std::size_t STREAM_SLOTS = 2 * MAX_STREAMS;
static_assert(std::has_single_bit(STREAM_SLOTS));
constexpr std::int32_t EMPTY_SLOT = -1;

/// The "node" of all 11-bit frames, after the 256 source addresses.
constexpr std::size_t STANDARD_NODE = 256;
constexpr std::size_t NODE_SLOTS = 257;

std::size_t periodBin(std::int64_t periodNs) noexcept {
  if (periodNs < PERIOD_LINEAR_NS + HALF_BIN_NS) return static_cast<std::size_t>((periodNs + HALF_BIN_NS) / PERIOD_BIN_NS);
  if (periodNs >= PERIOD_RANGE_NS) return OVERFLOW_BIN;
  const auto octave = std::bit_width(static_cast<std::uint64_t>(periodNs / PERIOD_LINEAR_NS)) - 1;
  const std::int64_t base = PERIOD_LINEAR_NS << octave;
  const std::int64_t sub = (periodNs - base) * PERIOD_OCTAVE_BINS / base;
  return LINEAR_BINS + static_cast<std::size_t>(octave * PERIOD_OCTAVE_BINS + sub);
}

/// The value a bin stands for: its centre (an octave bin: the middle of [lower, upper)).
double binValueNs(std::size_t bin) noexcept {
  if (bin < LINEAR_BINS) return static_cast<double>(static_cast<std::int64_t>(bin) * PERIOD_BIN_NS);
  const auto index = static_cast<std::int64_t>(bin - LINEAR_BINS);
  const std::int64_t octave = index / PERIOD_OCTAVE_BINS;
  const std::int64_t sub = index % PERIOD_OCTAVE_BINS;
  const std::int64_t base = PERIOD_LINEAR_NS << octave;
  const double lower = static_cast<double>(base) + static_cast<double>(base * sub) / PERIOD_OCTAVE_BINS;
  return lower + 0.5 * static_cast<double>(base) / PERIOD_OCTAVE_BINS;
}

struct NodeCount {
  std::uint64_t frames{};
  std::uint64_t bits{};
};

struct Stream {
  std::uint64_t key{};
  std::uint16_t bus{};
  std::uint32_t id{};
  bool extended{};
  std::int32_t message{-1};
  std::int64_t expectedNs{};
  std::uint64_t count{};
  std::int64_t lastNs{};
  std::uint64_t periods{};
  std::int64_t sumNs{};
  std::int64_t minNs{std::numeric_limits<std::int64_t>::max()};
  std::int64_t maxNs{};
  std::uint64_t gaps{};
  std::uint64_t missing{};
  std::unique_ptr<std::uint32_t[]> histogram;  ///< HISTOGRAM_BINS, allocated at the first period
};

struct BusState {
  std::uint32_t bitrate{};
  std::uint32_t dataBitrate{};
  std::int64_t firstNs{};
  std::int64_t lastNs{};
  std::uint64_t frames{};
  std::uint64_t errorFrames{};
  std::uint64_t bits{};
  std::int64_t wireNs{};
  // Sliding window: ring[k % LOAD_BUCKETS] holds the wire time of bucket k (10 ms from
  // firstNs + k x LOAD_STEP_NS) for the last LOAD_BUCKETS buckets; ringSum is their sum.
  std::array<std::int64_t, LOAD_BUCKETS> ring{};
  std::int64_t ringSum{};
  std::int64_t currentBucket{};
  std::int64_t peakWindowNs{};
  bool fullWindow{};  ///< a complete window has been evaluated
  // Load over time: series[i] = wire time in [start + i x width, start + (i+1) x width).
  std::array<std::int64_t, LOAD_SERIES_POINTS> series{};
  std::int64_t seriesWidthNs{LOAD_STEP_NS};
  std::size_t seriesUsed{};
  std::array<NodeCount, NODE_SLOTS> nodes{};

  /// Closes bucket currentBucket (its window, if complete, is a peak candidate) and opens the next.
  void stepBucket() noexcept {
    if (currentBucket >= static_cast<std::int64_t>(LOAD_BUCKETS) - 1) {
      peakWindowNs = std::max(peakWindowNs, ringSum);
      fullWindow = true;
    }
    ++currentBucket;
    std::int64_t& slot = ring[static_cast<std::size_t>(currentBucket) % LOAD_BUCKETS];
    ringSum -= slot;
    slot = 0;
  }

  /// Moves the window to bucket `bucket` (>= currentBucket). Past LOAD_BUCKETS empty
  /// buckets every later window is empty, so the loop stops there.
  void advanceTo(std::int64_t bucket) noexcept {
    for (std::size_t steps = 0; currentBucket < bucket && steps <= LOAD_BUCKETS; ++steps) stepBucket();
    if (currentBucket < bucket) currentBucket = bucket;  // the ring is all zero by now
  }

  void addToSeries(std::int64_t sinceStartNs, std::int64_t wireTimeNs) noexcept {
    auto index = static_cast<std::size_t>(sinceStartNs / seriesWidthNs);
    while (index >= LOAD_SERIES_POINTS) {
      for (std::size_t i = 0; i < LOAD_SERIES_POINTS / 2; ++i) series[i] = series[2 * i] + series[2 * i + 1];
      std::fill(series.begin() + LOAD_SERIES_POINTS / 2, series.end(), 0);
      seriesWidthNs *= 2;
      seriesUsed = (seriesUsed + 1) / 2;
      index = static_cast<std::size_t>(sinceStartNs / seriesWidthNs);
    }
    series[index] += wireTimeNs;
    seriesUsed = std::max(seriesUsed, index + 1);
  }
};

/// The value of the quantile `q` (nearest rank) from a histogram: the value its bin stands
/// for, clamped to the exact [min, max].
double quantileMs(const Stream& stream, double q) noexcept {
  const auto rank = std::max<std::uint64_t>(1, static_cast<std::uint64_t>(std::ceil(q * static_cast<double>(stream.periods))));
  std::uint64_t seen = 0;
  for (std::size_t bin = 0; bin < HISTOGRAM_BINS; ++bin) {
    seen += stream.histogram[bin];
    if (seen < rank) continue;
    if (bin == OVERFLOW_BIN) return static_cast<double>(stream.maxNs) / NS_PER_MS;
    return std::clamp(binValueNs(bin), static_cast<double>(stream.minNs), static_cast<double>(stream.maxNs)) / NS_PER_MS;
  }
  return static_cast<double>(stream.maxNs) / NS_PER_MS;
}

}  // namespace

struct TraceStats::Impl {
  const AnalysisSetup* setup{};
  const std::vector<std::string>* busNames{};  ///< null: default bit rates
  std::vector<std::unique_ptr<BusState>> buses;
  std::vector<Stream> streams;
  std::unique_ptr<std::uint64_t[]> slotKeys;
  std::unique_ptr<std::int32_t[]> slotStreams;
  bool started{};
  std::int64_t startNs{};
  std::int64_t lastNs{};
  std::uint64_t frames{};
  std::uint64_t skippedFrames{};
  std::uint64_t backwardSteps{};

  explicit Impl(const AnalysisSetup& analysisSetup, const std::vector<std::string>* names)
      : setup(&analysisSetup),
        busNames(names),
        slotKeys(std::make_unique<std::uint64_t[]>(STREAM_SLOTS)),
        slotStreams(std::make_unique<std::int32_t[]>(STREAM_SLOTS)) {
    std::fill_n(slotStreams.get(), STREAM_SLOTS, EMPTY_SLOT);
  }

  BusState& busState(const TraceFrame& frame) {
    if (frame.bus >= buses.size()) buses.resize(static_cast<std::size_t>(frame.bus) + 1);
    std::unique_ptr<BusState>& state = buses[frame.bus];
    if (!state) {
      state = std::make_unique<BusState>();
      AnalysisBus rates;
      if (busNames != nullptr && frame.bus < busNames->size()) rates = setup->bus((*busNames)[frame.bus]);
      state->bitrate = rates.bitrate;
      state->dataBitrate = rates.dataBitrate;
      state->firstNs = frame.timeNs;
      state->lastNs = frame.timeNs;
    }
    return *state;
  }

  /// The stream of `key`, created on first sight; null when MAX_STREAMS are tracked.
  Stream* stream(std::uint64_t key, const TraceFrame& frame) {
    // Fibonacci hashing: the top bits of key x 2^64/phi spread neighbouring identifiers.
    constexpr std::uint64_t GOLDEN = 0x9E3779B97F4A7C15ull;
    constexpr int SHIFT = 64 - std::countr_zero(STREAM_SLOTS);
    auto slot = static_cast<std::size_t>((key * GOLDEN) >> SHIFT);
    while (slotStreams[slot] != EMPTY_SLOT) {
      if (slotKeys[slot] == key) return &streams[static_cast<std::size_t>(slotStreams[slot])];
      slot = (slot + 1) & (STREAM_SLOTS - 1);
    }
    if (streams.size() >= MAX_STREAMS) return nullptr;
    Stream& created = streams.emplace_back();
    created.key = key;
    created.bus = frame.bus;
    created.id = frame.frame.id;
    created.extended = frame.frame.extended();
    created.message = frame.message;
    if (frame.message >= 0 && static_cast<std::size_t>(frame.message) < setup->expectedCycleNs.size()) {
      created.expectedNs = setup->expectedCycleNs[static_cast<std::size_t>(frame.message)];
    }
    slotKeys[slot] = key;
    slotStreams[slot] = static_cast<std::int32_t>(streams.size() - 1);
    return &created;
  }

  void measurePeriod(Stream& stream, std::int64_t timeNs) {
    const std::int64_t period = timeNs - stream.lastNs;
    if (period < 0) {
      ++backwardSteps;
      return;
    }
    if (!stream.histogram) stream.histogram = std::make_unique<std::uint32_t[]>(HISTOGRAM_BINS);
    std::uint32_t& counter = stream.histogram[periodBin(period)];
    if (counter != std::numeric_limits<std::uint32_t>::max()) ++counter;
    ++stream.periods;
    stream.sumNs += period;
    stream.minNs = std::min(stream.minNs, period);
    stream.maxNs = std::max(stream.maxNs, period);
    const std::int64_t expected = stream.expectedNs;
    if (expected > 0 && 2 * period > 3 * expected) {
      ++stream.gaps;
      const std::int64_t cycles = (2 * period + expected) / (2 * expected);  // round half up
      stream.missing += static_cast<std::uint64_t>(cycles - 1);
    }
  }

  void add(const TraceFrame& frame) {
    const std::int64_t timeNs = frame.timeNs;
    if (!started) {
      started = true;
      startNs = timeNs;
      lastNs = timeNs;
    }
    lastNs = std::max(lastNs, timeNs);
    ++frames;
    BusState& bus = busState(frame);
    const bool isError = (frame.frame.flags & can::FLAG_ERROR) != 0;

    Stream* maybeStream = nullptr;
    if (!isError) {
      const std::uint64_t key = (static_cast<std::uint64_t>(frame.bus) << 32) |
                                (frame.frame.extended() ? 0x8000'0000ull : 0ull) | frame.frame.id;
      maybeStream = stream(key, frame);
      if (maybeStream == nullptr) {
        ++skippedFrames;
      } else {
        if (maybeStream->count > 0) measurePeriod(*maybeStream, timeNs);
        maybeStream->lastNs = timeNs;
        ++maybeStream->count;
      }
    }

    const can::WireBits bits = can::wireBits(frame.frame);
    const std::uint32_t frameBits = bits.nominalBits + bits.dataBits;
    // The same arithmetic as can::wireTimeNs (one rounding per frame).
    std::int64_t wireNs = 0;
    if (bus.bitrate != 0) {
      const double dataRate = bus.dataBitrate != 0 ? bus.dataBitrate : bus.bitrate;
      wireNs = std::llround(static_cast<double>(bits.nominalBits) * NS_PER_S / bus.bitrate +
                            static_cast<double>(bits.dataBits) * NS_PER_S / dataRate);
    }
    ++bus.frames;
    bus.bits += frameBits;
    bus.wireNs += wireNs;
    bus.lastNs = std::max(bus.lastNs, timeNs);
    if (isError) {
      ++bus.errorFrames;
    } else {
      NodeCount& node = bus.nodes[frame.frame.extended() ? (frame.frame.id & 0xFFu) : STANDARD_NODE];
      ++node.frames;
      node.bits += frameBits;
    }
    // A frame older than the window's current bucket (time went back) counts in that bucket.
    const std::int64_t bucket = std::max<std::int64_t>(0, timeNs - bus.firstNs) / LOAD_STEP_NS;
    if (bucket > bus.currentBucket) bus.advanceTo(bucket);
    bus.ring[static_cast<std::size_t>(bus.currentBucket) % LOAD_BUCKETS] += wireNs;
    bus.ringSum += wireNs;
    bus.addToSeries(std::max<std::int64_t>(0, timeNs - startNs), wireNs);
  }

  [[nodiscard]] StatsReport finish(const std::vector<std::string>& names) const {
    StatsReport report;
    report.startS = static_cast<double>(startNs) / NS_PER_S;
    report.durationS = static_cast<double>(lastNs - startNs) / NS_PER_S;
    report.frames = frames;
    report.skippedFrames = skippedFrames;
    report.backwardSteps = backwardSteps;
    auto busName = [&names](std::size_t index) {
      return index < names.size() ? names[index] : "bus" + std::to_string(index);
    };

    for (std::size_t b = 0; b < buses.size(); ++b) {
      if (!buses[b]) continue;
      const BusState& state = *buses[b];
      BusStats bus;
      bus.bus = busName(b);
      bus.bitrate = state.bitrate;
      bus.frames = state.frames;
      bus.errorFrames = state.errorFrames;
      const std::int64_t durationNs = state.lastNs - state.firstNs;
      bus.durationS = static_cast<double>(durationNs) / NS_PER_S;
      bus.loadMeanPct = durationNs > 0 ? PERCENT * static_cast<double>(state.wireNs) / static_cast<double>(durationNs) : 0.0;
      // The window ending with the current (last, maybe partial) bucket is a candidate too.
      std::int64_t peakNs = state.peakWindowNs;
      bool anyWindow = state.fullWindow;
      if (state.currentBucket >= static_cast<std::int64_t>(LOAD_BUCKETS) - 1) {
        peakNs = std::max(peakNs, state.ringSum);
        anyWindow = true;
      }
      bus.loadMaxPct = anyWindow ? PERCENT * static_cast<double>(peakNs) / static_cast<double>(LOAD_WINDOW_NS)
                                 : bus.loadMeanPct;
      bus.loadBucketS = static_cast<double>(state.seriesWidthNs) / NS_PER_S;
      bus.loadSeries.reserve(state.seriesUsed);
      for (std::size_t i = 0; i < state.seriesUsed; ++i) {
        bus.loadSeries.emplace_back(static_cast<double>(i) * bus.loadBucketS,
                                    PERCENT * static_cast<double>(state.series[i]) /
                                        static_cast<double>(state.seriesWidthNs));
      }
      report.buses.push_back(std::move(bus));

      const std::size_t firstNode = report.nodes.size();
      for (std::size_t n = 0; n < NODE_SLOTS; ++n) {
        const NodeCount& count = state.nodes[n];
        if (count.frames == 0) continue;
        NodeStats node;
        node.bus = busName(b);
        node.standard = n == STANDARD_NODE;
        node.sa = node.standard ? 0 : static_cast<std::uint8_t>(n);
        if (!node.standard) node.name = setup->nodeNames[n];
        node.frames = count.frames;
        node.bitsPerS = durationNs > 0 ? static_cast<double>(count.bits) * NS_PER_S / static_cast<double>(durationNs) : 0.0;
        node.sharePct = state.bits > 0 ? PERCENT * static_cast<double>(count.bits) / static_cast<double>(state.bits) : 0.0;
        report.nodes.push_back(std::move(node));
      }
      std::stable_sort(report.nodes.begin() + static_cast<std::ptrdiff_t>(firstNode), report.nodes.end(),
                       [](const NodeStats& left, const NodeStats& right) { return left.bitsPerS > right.bitsPerS; });
    }

    std::vector<const Stream*> ordered;
    ordered.reserve(streams.size());
    for (const Stream& stream : streams) ordered.push_back(&stream);
    std::sort(ordered.begin(), ordered.end(), [](const Stream* a, const Stream* b) {
      if (a->bus != b->bus) return a->bus < b->bus;
      if (a->id != b->id) return a->id < b->id;
      return a->extended < b->extended;
    });
    for (const Stream* stream : ordered) {
      MessageStats message;
      message.bus = busName(stream->bus);
      message.id = stream->id;
      message.extended = stream->extended;
      if (stream->message >= 0 && static_cast<std::size_t>(stream->message) < setup->database.messages.size()) {
        message.name = setup->database.messages[static_cast<std::size_t>(stream->message)].name;
        if (static_cast<std::size_t>(stream->message) < setup->cycleSource.size()) {
          message.cycleSource = setup->cycleSource[static_cast<std::size_t>(stream->message)];
        }
      }
      message.sa = stream->extended ? static_cast<std::uint8_t>(stream->id & 0xFFu) : 0;
      message.count = stream->count;
      message.expectedMs = static_cast<double>(stream->expectedNs) / NS_PER_MS;
      if (stream->expectedNs <= 0) message.cycleSource = CycleSource::None;
      if (stream->periods > 0) {
        message.meanMs = static_cast<double>(stream->sumNs) / static_cast<double>(stream->periods) / NS_PER_MS;
        message.p50Ms = quantileMs(*stream, 0.50);
        message.p99Ms = quantileMs(*stream, 0.99);
        message.maxMs = static_cast<double>(stream->maxNs) / NS_PER_MS;
        message.minMs = static_cast<double>(stream->minNs) / NS_PER_MS;
        if (stream->expectedNs > 0) message.deviationMs = message.meanMs - message.expectedMs;
      }
      message.periods = stream->periods;
      message.gaps = stream->gaps;
      message.missing = stream->missing;
      report.messages.push_back(std::move(message));
    }
    return report;
  }
};

TraceStats::TraceStats(const AnalysisSetup& setup) : m_impl(std::make_unique<Impl>(setup, nullptr)) {}
TraceStats::TraceStats(const AnalysisSetup& setup, const std::vector<std::string>& busNames)
    : m_impl(std::make_unique<Impl>(setup, &busNames)) {}
TraceStats::TraceStats(TraceStats&&) noexcept = default;
TraceStats& TraceStats::operator=(TraceStats&&) noexcept = default;
TraceStats::~TraceStats() = default;

void TraceStats::add(const TraceFrame& frame) { m_impl->add(frame); }

StatsReport TraceStats::finish(const std::vector<std::string>& buses) const { return m_impl->finish(buses); }

}  // namespace openvcu::trace
