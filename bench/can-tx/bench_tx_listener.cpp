// bench_tx_listener: the measuring end of the can-tx benchmark. Attaches its own link to a
// sim:NAME bus, records every frame for a fixed time with the sender's send stamp, then
// checks the timing and the J1939-76 safety pairs of what was sent, independently of
// vcu-can-tx's code (it reads the DBC and the schedule file itself; it does not link
// openvcu_can_tx).
//
//   bench_tx_listener --config config/hhea/vehicle.json --seconds 60
//
// Needs a running iox-roudi and the sender (vcu-can-tx) on the same bus: run it inside
// tests/harness/run_isolated.sh (see bench/can-tx/run_can_tx_bench.sh).
//
// Time base: ReceivedFrame::monotonicNs, which on a sim link is the sender's CLOCK_MONOTONIC
// taken in Link::send() just before the frame is published. So the figures are the times at
// which vcu-can-tx handed each frame to its link; how late this program takes the frames
// out of its queue does not enter them.
//
// Recording: after opening the link it waits --connect-ms (default 1000; RouDi connects new
// ports within ~100 ms, frames sent before that are not delivered) and discards what came.
// Then the window [start, start + seconds) begins: every --poll-ms (default 5) it takes what
// the link queued (256 samples: 200 ms at 1,300 frames/s) into a vector reserved before the
// window (--max-rate x seconds records); frames stamped in the window are kept. A tail of
// --tail-ms (default 50) after the window is also kept, only to complete the safety pairs
// whose SHM went out at the very end. Nothing is allocated or analysed during the window.
//
// Analysis (after the window):
//   - streams: one per CAN ID; SHMs (PGN 0x0E00) one per SDM they guard (several SDMs can
//     share one SHM identifier: CCVS1, AMB and CN all use 0x180EFF21 in HHEA), found from the
//     inverted SDM fields in the SHM's bytes 1-3 and the SHM's priority;
//   - nominal cycle per stream: the schedule file's "cycleMs", else the DBC GenMsgCycleTime,
//     else the median period (such a stream is listed but kept out of the targets); an SHM
//     stream has its SDM's cycle;
//   - period error per interval: |t(i) - t(i-1) - cycle| (the first frame has none);
//     p50/p99 are nearest-rank percentiles, max exact. Two counts of cycles without a frame:
//     "gaps": intervals longer than 1.5 cycles (a frame sent more than half a cycle late makes
//     one too, though nothing was skipped); "missed": the slots between the first and the
//     last frame minus the frames, round((t(last) - t(first)) / cycle) + 1 - frames (exact
//     while the first and last frame are less than half a cycle apart in lateness; the
//     sender keeps absolute deadlines). Either way the interval's error stays in the statistics;
//   - safety pairs (every schedule message with "safety": {"deltaUs": N}): for each SDM the
//     latest SHM for it must have come first and not been used: delta error
//     |t(SDM) - t(SHM) - deltaUs|; the SHM's CRC-32 (crc32J1939_76) must equal that of the
//     SDM's 8 bytes; its sequence number must be the previous pair's + 1 mod 32; SHM and SDM
//     must be 8 bytes. Order faults: an SDM without an unused SHM before it, an SHM replaced
//     by another before its SDM, an SHM left without SDM at the end (other than in the tail),
//     an SHM on a pair's identifier that names no configured SDM. An SDM before the pair's
//     first SHM in the window is not a fault (the window began between the two).
//
//   - late events: intervals over the max target, grouped when they end within 50 ms of each
//     other, so that one stall of the sender shows as one event hitting many streams; the
//     --late-events N worst are listed with their time in the window.
//
// Output (stdout): a line "listening on ..." when the window starts (the run script starts
// its CPU window there), one line per stream, the late events, one line per safety pair, a
// summary, the targets with met / BROKEN, and a final line of key=value pairs starting
// "bench_tx_listener:". --dump FILE also writes every recorded frame as CSV (offset from the
// window's start in ns, ID, length, data) for analyses of one's own.
// Targets: per stream (cyclic) and per pair p99 <= --target-p99-us (200), max <=
// --target-max-us (1000); no pair fault, no missed slot, no frame lost in the listener's
// queue, every configured pair seen.
// Exit: 0 every target met, 1 start-up error, 2 a target broken or nothing measured.

#include <sys/resource.h>
#include <time.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <iostream>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "openvcu/can_links/open_link.hpp"
#include "openvcu/config/json.hpp"
#include "openvcu/config/vehicle.hpp"
#include "openvcu/dbc/matcher.hpp"
#include "openvcu/ipc/runtime.hpp"
#include "openvcu/j1939/id.hpp"
#include "openvcu/j1939/safety.hpp"

namespace {

using namespace openvcu;

constexpr std::int64_t NS_PER_US = 1'000;
constexpr std::int64_t NS_PER_MS = 1'000'000;
constexpr std::int64_t NS_PER_S = 1'000'000'000;
constexpr std::size_t RECEIVE_BATCH = 64;
/// A stream's p99 counts in tx_p99 from this many intervals on: at least 10 lie beyond it (in a
/// 60 s window the 10 and 20 ms streams); below it the p99 is one of its few worst (a 1 s stream:
/// its maximum), which the max and the pooled p99 cover.
constexpr std::size_t P99_MIN_INTERVALS = 1000;
constexpr std::uint8_t SAFETY_HEADER_PF = 0x0E;  ///< PF of PGN 0x0E00 (3584), the J1939-76 SHM
constexpr std::uint64_t SHM_STREAM_TAG = 1ull << 40;

std::int64_t monotonicNs() noexcept {
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC, &now);
  return static_cast<std::int64_t>(now.tv_sec) * NS_PER_S + now.tv_nsec;
}

void sleepUntil(std::int64_t deadlineNs) noexcept {
  const timespec deadline{static_cast<time_t>(deadlineNs / NS_PER_S), static_cast<long>(deadlineNs % NS_PER_S)};
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &deadline, nullptr) != 0) {
  }
}

double toUs(std::int64_t ns) noexcept {
  return static_cast<double>(ns) / static_cast<double>(NS_PER_US);
}

std::string hexId(std::uint32_t id, bool extended) {
  char text[16];
  std::snprintf(text, sizeof text, extended ? "0x%08X" : "0x%03X", id);
  return text;
}

std::int64_t processCpuNs() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return (static_cast<std::int64_t>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) * NS_PER_S) +
         static_cast<std::int64_t>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec) * NS_PER_US;
}

// ---- recording ---------------------------------------------------------------------------------

/// One recorded frame: the send stamp and the first 8 bytes (J1939-76 frames are 8 bytes).
struct Record {
  std::int64_t sentNs{};
  std::uint32_t id{};
  std::uint8_t flags{};
  std::uint8_t length{};
  std::array<std::uint8_t, can::CLASSIC_DATA_LENGTH> data{};

  [[nodiscard]] bool extended() const noexcept { return (flags & can::FLAG_EXTENDED) != 0; }
};

struct Recording {
  std::vector<Record> records;  ///< reserved before the window; sent order
  std::int64_t startNs{};
  std::int64_t endNs{};          ///< the window is [startNs, endNs); the tail follows
  std::uint64_t overflow{};      ///< frames not kept because the reserve was full
  std::uint64_t queueLost{};     ///< the link's receiveDropped over the window (queue overflow)
  std::uint64_t beforeWindow{};  ///< frames taken in the window but stamped before it
  std::int64_t tailNs{};
  std::int64_t cpuNs{};  ///< this process's CPU time from the window's start to the tail's end
};

/// Takes everything queued on `link`; keeps frames stamped in [keepFromNs, keepUntilNs).
void take(can::Link& link, std::span<can::ReceivedFrame> batch, Recording& recording, std::int64_t keepFromNs,
          std::int64_t keepUntilNs) noexcept {
  for (;;) {
    const std::size_t count = link.receive(batch);
    for (std::size_t i = 0; i < count; ++i) {
      const can::ReceivedFrame& received = batch[i];
      if (received.monotonicNs < keepFromNs) {
        ++recording.beforeWindow;
        continue;
      }
      if (received.monotonicNs >= keepUntilNs) continue;
      if (recording.records.size() == recording.records.capacity()) {
        ++recording.overflow;
        continue;
      }
      Record& record = recording.records.emplace_back();  // within the reserve: no allocation
      record.sentNs = received.monotonicNs;
      record.id = received.frame.id;
      record.flags = received.frame.flags;
      record.length = received.frame.length;
      const std::size_t bytes = std::min<std::size_t>(received.frame.length, record.data.size());
      std::copy_n(received.frame.data.begin(), bytes, record.data.begin());
    }
    if (count < batch.size()) return;
  }
}

Recording record(can::Link& link, std::int64_t seconds, std::int64_t maxRate, std::int64_t connectMs,
                 std::int64_t pollMs, std::int64_t tailMs) {
  Recording recording;
  recording.records.reserve(static_cast<std::size_t>(maxRate * (seconds + 1)));
  std::array<can::ReceivedFrame, RECEIVE_BATCH> batch{};

  // Connection set-up (not measured): RouDi connects our subscriber to the publishers.
  const std::int64_t connected = monotonicNs() + connectMs * NS_PER_MS;
  while (monotonicNs() < connected) {
    take(link, batch, recording, INT64_MAX, INT64_MAX);
    sleepUntil(std::min(connected, monotonicNs() + pollMs * NS_PER_MS));
  }
  take(link, batch, recording, INT64_MAX, INT64_MAX);
  recording.beforeWindow = 0;
  const std::uint64_t lostBefore = link.stats().receiveDropped;

  const std::int64_t cpuStart = processCpuNs();
  recording.startNs = monotonicNs();
  recording.endNs = recording.startNs + seconds * NS_PER_S;
  recording.tailNs = tailMs * NS_PER_MS;
  const std::int64_t tailEnd = recording.endNs + recording.tailNs;
  std::printf("listening on %s for %lld s (+%lld ms tail), reserve %zu frames\n", link.name().c_str(),
              static_cast<long long>(seconds), static_cast<long long>(tailMs), recording.records.capacity());
  std::fflush(stdout);
  for (std::int64_t deadline = recording.startNs + pollMs * NS_PER_MS;; deadline += pollMs * NS_PER_MS) {
    sleepUntil(std::min(deadline, tailEnd));
    take(link, batch, recording, recording.startNs, tailEnd);
    if (monotonicNs() >= tailEnd) break;
  }
  // Frames of the tail still in flight were stamped before tailEnd; one more look.
  take(link, batch, recording, recording.startNs, tailEnd);
  recording.queueLost = link.stats().receiveDropped - lostBefore;
  recording.cpuNs = processCpuNs() - cpuStart;
  std::printf("window closed: %zu frames recorded\n", recording.records.size());
  std::fflush(stdout);
  return recording;
}

/// CSV "offset_ns,id,extended,length,data": offset from the window's start, data in hex.
bool dump(const Recording& recording, const std::string& path) {
  std::FILE* file = std::fopen(path.c_str(), "w");
  if (file == nullptr) return false;
  std::fprintf(file, "offset_ns,id,extended,length,data\n");
  for (const Record& record : recording.records) {
    std::fprintf(file, "%lld,0x%X,%d,%u,", static_cast<long long>(record.sentNs - recording.startNs), record.id,
                 record.extended() ? 1 : 0, record.length);
    for (std::size_t i = 0; i < std::min<std::size_t>(record.length, record.data.size()); ++i) {
      std::fprintf(file, "%02X", record.data[i]);
    }
    std::fputc('\n', file);
  }
  return std::fclose(file) == 0;
}

// ---- the schedule as configured ----------------------------------------------------------------

struct ScheduleInfo {
  std::map<std::string, double, std::less<>> cycleMs;  ///< "cycleMs" of the schedule file
  struct Pair {
    std::string sdmName;
    std::int64_t deltaNs{};
    std::optional<std::uint8_t> destination;  ///< the schedule's substitutions, if any
    std::optional<std::uint8_t> source;
  };
  std::vector<Pair> pairs;
};

std::optional<std::uint8_t> address(const config::Json& entry, const char* key) {
  const auto found = entry.find(key);
  if (found == entry.end()) return std::nullopt;
  if (found->is_number_unsigned()) return static_cast<std::uint8_t>(found->get<std::uint64_t>() & 0xFF);
  if (found->is_string()) return static_cast<std::uint8_t>(std::stoul(found->get<std::string>(), nullptr, 0) & 0xFF);
  return std::nullopt;
}

Result<ScheduleInfo> readSchedule(const std::string& path) {
  ScheduleInfo info;
  if (path.empty()) return info;
  auto jsonResult = config::readJsonFile(path);
  if (!jsonResult) return jsonResult.error();
  const config::Json& root = *jsonResult;
  const auto messages = root.find("messages");
  if (messages == root.end() || !messages->is_object()) return info;
  try {
    for (const auto& [name, entry] : messages->items()) {
      if (!entry.is_object()) continue;
      if (const auto cycle = entry.find("cycleMs"); cycle != entry.end() && cycle->is_number()) {
        info.cycleMs[name] = cycle->get<double>();
      }
      const auto safety = entry.find("safety");
      if (safety == entry.end() || !safety->is_object()) continue;
      const auto delta = safety->find("deltaUs");
      if (delta == safety->end() || !delta->is_number()) continue;
      info.pairs.push_back(ScheduleInfo::Pair{name, std::llround(delta->get<double>() * NS_PER_US),
                                              address(entry, "destination"), address(entry, "source")});
    }
  } catch (const std::exception& error) {
    return Error{path + ": " + error.what()};
  }
  return info;
}

// ---- analysis ----------------------------------------------------------------------------------

struct ErrorSummary {
  std::size_t count{};
  std::int64_t p50Ns{};
  std::int64_t p99Ns{};
  std::int64_t maxNs{};
};

/// Nearest-rank percentiles; sorts `errors`.
ErrorSummary summarise(std::vector<std::int64_t>& errors) {
  ErrorSummary summary;
  summary.count = errors.size();
  if (errors.empty()) return summary;
  std::sort(errors.begin(), errors.end());
  auto rank = [&](double fraction) {
    const auto index = static_cast<std::size_t>(std::ceil(fraction * static_cast<double>(errors.size())));
    return errors[std::max<std::size_t>(index, 1) - 1];
  };
  summary.p50Ns = rank(0.50);
  summary.p99Ns = rank(0.99);
  summary.maxNs = errors.back();
  return summary;
}

enum class CycleSource : std::uint8_t { Schedule, Dbc, Median };

const char* cycleSourceName(CycleSource source) {
  switch (source) {
    case CycleSource::Schedule:
      return "schedule";
    case CycleSource::Dbc:
      return "dbc";
    case CycleSource::Median:
      return "median";
  }
  return "?";
}

struct Stream {
  std::string name;
  std::uint32_t canId{};
  bool extended{};
  std::vector<std::int64_t> times;  ///< send stamps in the window
  std::int64_t cycleNs{};
  CycleSource cycleSource{CycleSource::Median};
  ErrorSummary error;
  std::uint64_t gaps{};    ///< intervals > 1.5 cycles
  std::uint64_t missed{};  ///< slots without a frame
};

struct PairResult {
  std::string name;
  std::uint32_t sdmCanId{};
  std::uint32_t shmCanId{};
  std::int64_t deltaNs{};
  std::vector<std::int64_t> deltaErrors;
  ErrorSummary error;
  std::uint64_t pairs{};
  std::uint64_t leadingSdm{};     ///< SDM before the pair's first SHM in the window: not a fault
  std::uint64_t sdmWithoutShm{};  ///< order fault
  std::uint64_t shmReplaced{};    ///< order fault: SHM followed by another SHM, no SDM between
  std::uint64_t shmWithoutSdm{};  ///< an SHM unused at the end, sent before the tail
  std::uint64_t sequenceErrors{};
  std::uint64_t crcErrors{};
  std::uint64_t lengthErrors{};
  // state while walking the frames
  bool pending{};
  std::int64_t pendingNs{};
  j1939::SafetyHeader pendingHeader{};
  bool pendingLengthOk{};
  bool sawHeader{};
  bool hasSequence{};
  std::uint8_t lastSequence{};

  [[nodiscard]] std::uint64_t orderFaults() const noexcept { return sdmWithoutShm + shmReplaced + shmWithoutSdm; }
  [[nodiscard]] std::uint64_t faults() const noexcept {
    return orderFaults() + sequenceErrors + crcErrors + lengthErrors;
  }
};

/// The SDM CAN ID an SHM guards: its inverted fields, with the SHM's priority.
std::optional<std::uint32_t> guardedSdm(const Record& record) {
  if (!record.extended() || record.length != j1939::SAFETY_MESSAGE_LENGTH) return std::nullopt;
  const j1939::Id id = j1939::Id::fromCanId(record.id);
  if (id.pduFormat != SAFETY_HEADER_PF) return std::nullopt;
  const auto header = j1939::parseSafetyHeader(std::span<const std::uint8_t>(record.data.data(), record.length));
  if (!header) return std::nullopt;
  j1939::Id sdm;
  sdm.priority = id.priority;
  sdm.extendedDataPage = header->sdmExtendedDataPage;
  sdm.dataPage = header->sdmDataPage;
  sdm.pduFormat = header->sdmPduFormat;
  sdm.pduSpecific = header->sdmPduSpecific;
  sdm.sourceAddress = header->sdmSourceAddress;
  return sdm.toCanId();
}

std::uint64_t streamKey(std::uint32_t id, bool extended) {
  return (static_cast<std::uint64_t>(extended) << 32) | id;
}

struct Analysis {
  std::vector<Stream> streams;
  std::vector<PairResult> pairs;
  std::uint64_t unknownShm{};  ///< SHMs on a pair's identifier guarding no configured SDM: fault
  std::size_t windowFrames{};
};

Analysis analyse(const Recording& recording, const config::VehicleConfig& vehicle, const ScheduleInfo& schedule) {
  Analysis analysis;
  const dbc::Database& database = vehicle.database;
  const dbc::MessageMatcher matcher(database, dbc::MatchMode::J1939);

  auto nameOf = [&](std::uint32_t id, bool extended) -> std::string {
    const std::int32_t index = matcher.match(id, extended);
    return index == dbc::MessageMatcher::NO_MATCH ? hexId(id, extended)
                                                  : database.messages[static_cast<std::size_t>(index)].name;
  };
  auto cycleOf = [&](std::uint32_t id, bool extended) -> std::pair<std::int64_t, CycleSource> {
    const std::int32_t index = matcher.match(id, extended);
    if (index == dbc::MessageMatcher::NO_MATCH) return {0, CycleSource::Median};
    const dbc::Message& message = database.messages[static_cast<std::size_t>(index)];
    if (const auto found = schedule.cycleMs.find(message.name); found != schedule.cycleMs.end()) {
      return {std::llround(found->second * NS_PER_MS), CycleSource::Schedule};
    }
    if (message.cycleTimeMs) return {static_cast<std::int64_t>(*message.cycleTimeMs) * NS_PER_MS, CycleSource::Dbc};
    return {0, CycleSource::Median};
  };

  // Safety pairs from the schedule.
  for (const ScheduleInfo::Pair& configured : schedule.pairs) {
    const dbc::Message* message = database.findMessage(configured.sdmName);
    if (message == nullptr || !message->extended) continue;
    j1939::Id id = j1939::Id::fromCanId(message->id);
    if (configured.destination && id.isPdu1()) id.pduSpecific = *configured.destination;
    if (configured.source) id.sourceAddress = *configured.source;
    PairResult& pair = analysis.pairs.emplace_back();
    pair.name = configured.sdmName;
    pair.sdmCanId = id.toCanId();
    pair.shmCanId = j1939::safetyHeaderCanId(pair.sdmCanId);
    pair.deltaNs = configured.deltaNs;
  }

  // Streams, in the order their first frame came.
  std::map<std::uint64_t, std::size_t> streamOf;
  for (const Record& record : recording.records) {
    if (record.sentNs >= recording.endNs) continue;  // the tail only completes pairs
    ++analysis.windowFrames;
    std::uint64_t key = streamKey(record.id, record.extended());
    const std::optional<std::uint32_t> sdm = guardedSdm(record);
    if (sdm) key = SHM_STREAM_TAG | streamKey(*sdm, true);
    auto [found, inserted] = streamOf.try_emplace(key, analysis.streams.size());
    if (inserted) {
      Stream& stream = analysis.streams.emplace_back();
      stream.canId = record.id;
      stream.extended = record.extended();
      if (sdm) {
        stream.name = "SHM>" + nameOf(*sdm, true);
        std::tie(stream.cycleNs, stream.cycleSource) = cycleOf(*sdm, true);
      } else {
        stream.name = nameOf(record.id, record.extended());
        std::tie(stream.cycleNs, stream.cycleSource) = cycleOf(record.id, record.extended());
      }
    }
    analysis.streams[found->second].times.push_back(record.sentNs);
  }

  for (Stream& stream : analysis.streams) {
    std::vector<std::int64_t> periods;
    for (std::size_t i = 1; i < stream.times.size(); ++i) periods.push_back(stream.times[i] - stream.times[i - 1]);
    if (stream.cycleSource == CycleSource::Median && !periods.empty()) {
      std::vector<std::int64_t> sorted = periods;
      std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2), sorted.end());
      stream.cycleNs = sorted[sorted.size() / 2];
    }
    std::vector<std::int64_t> errors;
    errors.reserve(periods.size());
    for (const std::int64_t period : periods) {
      errors.push_back(std::llabs(period - stream.cycleNs));
      if (stream.cycleNs > 0 && 2 * period > 3 * stream.cycleNs) {
        stream.gaps += static_cast<std::uint64_t>(
                           std::llround(static_cast<double>(period) / static_cast<double>(stream.cycleNs))) -
                       1;
      }
    }
    if (stream.cycleNs > 0 && stream.times.size() > 1) {
      const double span = static_cast<double>(stream.times.back() - stream.times.front());
      const auto slots = std::llround(span / static_cast<double>(stream.cycleNs)) + 1;
      const auto frames = static_cast<long long>(stream.times.size());
      stream.missed = slots > frames ? static_cast<std::uint64_t>(slots - frames) : 0;
    }
    stream.error = summarise(errors);
  }

  // Safety pairs: walk the frames in send order (window and tail).
  for (const Record& record : recording.records) {
    const bool inWindow = record.sentNs < recording.endNs;
    if (const std::optional<std::uint32_t> sdm = guardedSdm(record)) {
      if (!inWindow) continue;  // an SHM of the tail: its SDM would fall outside
      PairResult* owner = nullptr;
      for (PairResult& pair : analysis.pairs) {
        if (pair.shmCanId == record.id && pair.sdmCanId == *sdm) owner = &pair;
      }
      if (owner == nullptr) {
        for (const PairResult& pair : analysis.pairs) {
          if (pair.shmCanId == record.id) {
            ++analysis.unknownShm;
            break;
          }
        }
        continue;
      }
      if (owner->pending) ++owner->shmReplaced;
      owner->pending = true;
      owner->sawHeader = true;
      owner->pendingNs = record.sentNs;
      owner->pendingHeader =
          *j1939::parseSafetyHeader(std::span<const std::uint8_t>(record.data.data(), record.length));
      continue;
    }
    for (PairResult& pair : analysis.pairs) {
      if (!record.extended() || record.id != pair.sdmCanId) continue;
      if (!pair.sawHeader) {
        if (inWindow) ++pair.leadingSdm;
        break;
      }
      if (!pair.pending) {
        if (inWindow) ++pair.sdmWithoutShm;
        break;
      }
      pair.pending = false;
      ++pair.pairs;
      pair.deltaErrors.push_back(std::llabs(record.sentNs - pair.pendingNs - pair.deltaNs));
      if (record.length != j1939::SAFETY_MESSAGE_LENGTH) {
        ++pair.lengthErrors;
      } else if (j1939::crc32J1939_76(std::span<const std::uint8_t>(record.data.data(), record.length)) !=
                 pair.pendingHeader.sdmCrc) {
        ++pair.crcErrors;
      }
      const std::uint8_t sequence = pair.pendingHeader.sequence;
      if (pair.hasSequence && sequence != (pair.lastSequence + 1) % j1939::SAFETY_SEQUENCE_MODULO) {
        ++pair.sequenceErrors;
      }
      pair.hasSequence = true;
      pair.lastSequence = sequence;
      break;
    }
  }
  for (PairResult& pair : analysis.pairs) {
    // An SHM still unused: a fault unless it went out so late that its SDM is due after the tail.
    if (pair.pending && pair.pendingNs + pair.deltaNs < recording.endNs) ++pair.shmWithoutSdm;
    pair.error = summarise(pair.deltaErrors);
  }
  return analysis;
}

// ---- report ------------------------------------------------------------------------------------

struct Targets {
  double p99Us{200.0};
  double maxUs{1000.0};
  std::size_t eventsShown{10};  ///< late events listed (not a target: how much of the report)
};

int report(const Recording& recording, const Analysis& analysis, const Targets& targets, const std::string& linkName) {
  const double windowS = static_cast<double>(recording.endNs - recording.startNs) / static_cast<double>(NS_PER_S);
  const double framesPerSecond = static_cast<double>(analysis.windowFrames) / windowS;
  std::printf(
      "== %s: %.3f s window, %zu frames (%.1f frames/s), %zu streams; lost in the listener's queue %llu, "
      "reserve overflow %llu\n",
      linkName.c_str(), windowS, analysis.windowFrames, framesPerSecond, analysis.streams.size(),
      static_cast<unsigned long long>(recording.queueLost), static_cast<unsigned long long>(recording.overflow));

  // Streams, sorted by name.
  std::vector<const Stream*> streams;
  for (const Stream& stream : analysis.streams) streams.push_back(&stream);
  std::sort(streams.begin(), streams.end(), [](const Stream* a, const Stream* b) { return a->name < b->name; });
  std::printf("   %-28s %-10s %7s %9s %-8s %9s %9s %9s %5s %6s\n", "message", "id", "frames", "cycle_ms", "source",
              "p50_us", "p99_us", "max_us", "gaps", "missed");
  std::vector<std::int64_t> pooled;
  const Stream* worstP99 = nullptr;
  // the worst p99 among streams with at least P99_MIN_INTERVALS intervals: below that the
  // nearest-rank p99 of a stream is its maximum (a 1 s stream has 59 in a minute)
  const Stream* worstSampledP99 = nullptr;
  const Stream* worstMax = nullptr;
  std::uint64_t missed = 0;
  std::uint64_t gaps = 0;
  std::size_t cyclic = 0;
  for (const Stream* stream : streams) {
    std::printf("   %-28s %-10s %7zu %9.3f %-8s %9.1f %9.1f %9.1f %5llu %6llu%s\n", stream->name.c_str(),
                hexId(stream->canId, stream->extended).c_str(), stream->times.size(),
                static_cast<double>(stream->cycleNs) / static_cast<double>(NS_PER_MS),
                cycleSourceName(stream->cycleSource), toUs(stream->error.p50Ns), toUs(stream->error.p99Ns),
                toUs(stream->error.maxNs), static_cast<unsigned long long>(stream->gaps),
                static_cast<unsigned long long>(stream->missed),
                stream->cycleSource == CycleSource::Median ? "  (no configured cycle: not in the targets)" : "");
    if (stream->cycleSource == CycleSource::Median || stream->error.count == 0) continue;
    ++cyclic;
    missed += stream->missed;
    gaps += stream->gaps;
    for (std::size_t i = 1; i < stream->times.size(); ++i) {
      pooled.push_back(std::llabs(stream->times[i] - stream->times[i - 1] - stream->cycleNs));
    }
    if (worstP99 == nullptr || stream->error.p99Ns > worstP99->error.p99Ns) worstP99 = stream;
    if (stream->error.count >= P99_MIN_INTERVALS &&
        (worstSampledP99 == nullptr || stream->error.p99Ns > worstSampledP99->error.p99Ns)) {
      worstSampledP99 = stream;
    }
    if (worstMax == nullptr || stream->error.maxNs > worstMax->error.maxNs) worstMax = stream;
  }
  const ErrorSummary overall = summarise(pooled);

  // Late events: intervals whose error is over the max target, grouped when they end within
  // EVENT_GAP of each other, so that one stall of the sender shows as one event with the
  // number of streams it hit (a common cause) rather than as many unrelated errors.
  struct Late {
    std::int64_t endNs;
    std::int64_t errorNs;
    const Stream* stream;
  };
  std::vector<Late> late;
  const auto maxTargetNs = static_cast<std::int64_t>(targets.maxUs * NS_PER_US);
  for (const Stream* stream : streams) {
    if (stream->cycleSource == CycleSource::Median) continue;
    for (std::size_t i = 1; i < stream->times.size(); ++i) {
      const std::int64_t error = std::llabs(stream->times[i] - stream->times[i - 1] - stream->cycleNs);
      if (error > maxTargetNs) late.push_back(Late{stream->times[i], error, stream});
    }
  }
  std::sort(late.begin(), late.end(), [](const Late& a, const Late& b) { return a.endNs < b.endNs; });
  struct Event {
    std::int64_t firstNs{};
    std::int64_t lastNs{};
    const Late* worst{};
    std::size_t intervals{};
  };
  constexpr std::int64_t EVENT_GAP_NS = 50 * NS_PER_MS;
  std::vector<Event> events;
  for (const Late& item : late) {
    if (events.empty() || item.endNs - events.back().lastNs > EVENT_GAP_NS)
      events.push_back(Event{item.endNs, item.endNs, &item, 0});
    Event& event = events.back();
    event.lastNs = item.endNs;
    ++event.intervals;
    if (item.errorNs > event.worst->errorNs) event.worst = &item;
  }
  std::sort(events.begin(), events.end(),
            [](const Event& a, const Event& b) { return a.worst->errorNs > b.worst->errorNs; });
  std::printf("   late events (intervals with error > %.0f us, grouped within 50 ms): %zu; the worst:\n", targets.maxUs,
              events.size());
  for (std::size_t e = 0; e < std::min(events.size(), targets.eventsShown); ++e) {
    const Event& event = events[e];
    std::printf("     at +%.3f s: %zu intervals over %.1f ms, worst %.1f us (%s)\n",
                static_cast<double>(event.firstNs - recording.startNs) / static_cast<double>(NS_PER_S), event.intervals,
                static_cast<double>(event.lastNs - event.firstNs) / static_cast<double>(NS_PER_MS),
                toUs(event.worst->errorNs), event.worst->stream->name.c_str());
  }

  std::printf("   %-24s %-10s %8s %6s %9s %9s %9s %5s %5s %5s %5s %7s\n", "safety pair (SDM)", "SHM id", "delta_us",
              "pairs", "p50_us", "p99_us", "max_us", "order", "seq", "crc", "len", "leading");
  std::vector<std::int64_t> pooledDelta;
  std::uint64_t pairFaults = analysis.unknownShm;
  std::uint64_t orderFaults = 0, sequenceErrors = 0, crcErrors = 0, lengthErrors = 0, pairs = 0;
  bool everyPairSeen = true;
  const PairResult* worstDelta = nullptr;
  for (const PairResult& pair : analysis.pairs) {
    std::printf("   %-24s %-10s %8.0f %6llu %9.1f %9.1f %9.1f %5llu %5llu %5llu %5llu %7llu%s\n", pair.name.c_str(),
                hexId(pair.shmCanId, true).c_str(), toUs(pair.deltaNs), static_cast<unsigned long long>(pair.pairs),
                toUs(pair.error.p50Ns), toUs(pair.error.p99Ns), toUs(pair.error.maxNs),
                static_cast<unsigned long long>(pair.orderFaults()),
                static_cast<unsigned long long>(pair.sequenceErrors), static_cast<unsigned long long>(pair.crcErrors),
                static_cast<unsigned long long>(pair.lengthErrors), static_cast<unsigned long long>(pair.leadingSdm),
                pair.pairs == 0 ? "  <- NO PAIR SEEN" : "");
    pooledDelta.insert(pooledDelta.end(), pair.deltaErrors.begin(), pair.deltaErrors.end());
    pairFaults += pair.faults();
    orderFaults += pair.orderFaults();
    sequenceErrors += pair.sequenceErrors;
    crcErrors += pair.crcErrors;
    lengthErrors += pair.lengthErrors;
    pairs += pair.pairs;
    if (pair.pairs == 0) everyPairSeen = false;
    if (pair.pairs > 0 && (worstDelta == nullptr || pair.error.maxNs > worstDelta->error.maxNs)) worstDelta = &pair;
  }
  const ErrorSummary delta = summarise(pooledDelta);

  std::printf("== summary\n");
  std::printf(
      "   period error, %zu intervals of %zu cyclic streams: p50 %.1f us, p99 %.1f us, max %.1f us; "
      "gaps > 1.5 cycles %llu, missed slots %llu\n",
      overall.count, cyclic, toUs(overall.p50Ns), toUs(overall.p99Ns), toUs(overall.maxNs),
      static_cast<unsigned long long>(gaps), static_cast<unsigned long long>(missed));
  if (worstP99 != nullptr) {
    std::printf("   worst stream p99 %.1f us (%s), worst stream max %.1f us (%s)\n", toUs(worstP99->error.p99Ns),
                worstP99->name.c_str(), toUs(worstMax->error.maxNs), worstMax->name.c_str());
  }
  if (worstSampledP99 != nullptr) {
    std::printf("   worst p99 of the streams with at least %zu intervals %.1f us (%s)\n", P99_MIN_INTERVALS,
                toUs(worstSampledP99->error.p99Ns), worstSampledP99->name.c_str());
  }
  std::printf("   SHM->SDM delta error, %zu pairs of %zu configured: p50 %.1f us, p99 %.1f us, max %.1f us%s%s\n",
              delta.count, analysis.pairs.size(), toUs(delta.p50Ns), toUs(delta.p99Ns), toUs(delta.maxNs),
              worstDelta != nullptr ? ", worst pair " : "", worstDelta != nullptr ? worstDelta->name.c_str() : "");
  std::printf(
      "   pair faults %llu: order %llu, sequence %llu, CRC %llu, length %llu, SHM naming no configured SDM "
      "%llu\n",
      static_cast<unsigned long long>(pairFaults), static_cast<unsigned long long>(orderFaults),
      static_cast<unsigned long long>(sequenceErrors), static_cast<unsigned long long>(crcErrors),
      static_cast<unsigned long long>(lengthErrors), static_cast<unsigned long long>(analysis.unknownShm));
  std::printf("   listener CPU %.3f %% of one core over the window and tail\n",
              100.0 * static_cast<double>(recording.cpuNs) /
                  static_cast<double>(recording.endNs - recording.startNs + recording.tailNs));

  // Targets: per stream and per pair, so one bad message cannot hide in a pooled figure.
  double streamP99 = worstP99 != nullptr ? toUs(worstP99->error.p99Ns) : 0.0;
  const double sampledP99 = worstSampledP99 != nullptr ? toUs(worstSampledP99->error.p99Ns) : 0.0;
  double streamMax = worstMax != nullptr ? toUs(worstMax->error.maxNs) : 0.0;
  double pairP99 = 0.0, pairMax = 0.0;
  for (const PairResult& pair : analysis.pairs) {
    pairP99 = std::max(pairP99, toUs(pair.error.p99Ns));
    pairMax = std::max(pairMax, toUs(pair.error.maxNs));
  }
  const bool measured = analysis.windowFrames > 0 && cyclic > 0;
  const bool p99Met = measured && streamP99 <= targets.p99Us && pairP99 <= targets.p99Us;
  const bool maxMet = measured && streamMax <= targets.maxUs && pairMax <= targets.maxUs;
  const bool pairsMet = pairFaults == 0 && everyPairSeen;
  const bool complete = recording.queueLost == 0 && recording.overflow == 0 && missed == 0;
  auto verdict = [](bool met) { return met ? "met" : "BROKEN"; };
  std::printf("== targets\n");
  std::printf("   p99 <= %.0f us (every stream and pair): %s (stream %.1f us, pair delta %.1f us)\n", targets.p99Us,
              verdict(p99Met), streamP99, pairP99);
  std::printf("   max <= %.0f us (every stream and pair): %s (stream %.1f us, pair delta %.1f us)\n", targets.maxUs,
              verdict(maxMet), streamMax, pairMax);
  std::printf("   no pair fault, every configured pair seen: %s\n", verdict(pairsMet));
  std::printf("   no missed slot, no frame lost by the listener: %s\n", verdict(complete));
  const bool allMet = p99Met && maxMet && pairsMet && complete;
  std::printf(
      "bench_tx_listener: frames=%zu seconds=%.3f fps=%.1f period_p50_us=%.1f period_p99_us=%.1f "
      "period_max_us=%.1f worst_stream_p99_us=%.1f sampled_stream_p99_us=%.1f worst_stream_max_us=%.1f gaps=%llu "
      "missed=%llu pairs=%llu "
      "delta_p50_us=%.1f delta_p99_us=%.1f delta_max_us=%.1f pair_faults=%llu queue_lost=%llu verdict=%s\n",
      analysis.windowFrames, windowS, framesPerSecond, toUs(overall.p50Ns), toUs(overall.p99Ns), toUs(overall.maxNs),
      streamP99, sampledP99, streamMax, static_cast<unsigned long long>(gaps), static_cast<unsigned long long>(missed),
      static_cast<unsigned long long>(pairs), toUs(delta.p50Ns), toUs(delta.p99Ns), toUs(delta.maxNs),
      static_cast<unsigned long long>(pairFaults), static_cast<unsigned long long>(recording.queueLost),
      allMet ? "PASS" : "FAIL");
  std::fflush(stdout);
  return allMet ? 0 : 2;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Measuring end of the can-tx benchmark: records a sim bus and checks periods and J1939-76 pairs"};
  std::string configPath, busName, schedulePath;
  std::int64_t seconds = 60;
  std::int64_t maxRate = 5000;
  std::int64_t connectMs = 1000;
  std::int64_t pollMs = 5;
  std::int64_t tailMs = 50;
  Targets targets;
  app.add_option("--config", configPath, "vehicle configuration (vehicle.json): DBC, buses, schedule file")->required();
  app.add_option("--bus", busName, "bus name in the configuration (default: the first; its link must be sim:NAME)");
  app.add_option("--schedule", schedulePath, "schedule file (default: the configuration's \"schedule\")");
  app.add_option("--seconds", seconds, "recording window in seconds (default 60)")->check(CLI::Range(1, 3600));
  app.add_option("--max-rate", maxRate, "frames/s to reserve room for (default 5000)")->check(CLI::Range(1, 1'000'000));
  app.add_option("--connect-ms", connectMs, "wait after opening the link, before the window (default 1000)")
      ->check(CLI::Range(0, 60'000));
  app.add_option("--poll-ms", pollMs, "how often the link's queue is emptied (default 5)")->check(CLI::Range(1, 100));
  app.add_option("--tail-ms", tailMs, "kept after the window to complete safety pairs (default 50)")
      ->check(CLI::Range(0, 10'000));
  app.add_option("--target-p99-us", targets.p99Us, "p99 target, period and delta error (default 200)");
  app.add_option("--target-max-us", targets.maxUs, "max target, period and delta error (default 1000)");
  app.add_option("--late-events", targets.eventsShown, "late events listed, the worst first (default 10)");
  std::string dumpPath;
  app.add_option("--dump", dumpPath, "also write every recorded frame as CSV (after the window)");
  CLI11_PARSE(app, argc, argv);

  auto vehicleResult = config::loadVehicleConfig(configPath);
  if (!vehicleResult) {
    std::cerr << "bench_tx_listener: " << vehicleResult.error().toString() << '\n';
    return 1;
  }
  const config::VehicleConfig& vehicle = *vehicleResult;
  const config::BusConfig* bus =
      busName.empty() ? (vehicle.buses.empty() ? nullptr : &vehicle.buses.front()) : vehicle.findBus(busName);
  if (bus == nullptr) {
    std::cerr << "bench_tx_listener: " << configPath << ": no bus '" << busName << "'\n";
    return 1;
  }
  if (bus->link.kind != config::LinkKind::Sim) {
    std::cerr << "bench_tx_listener: bus '" << bus->name << "' is " << bus->link.toString() << ", not sim:NAME\n";
    return 1;
  }
  auto scheduleResult = readSchedule(schedulePath.empty() ? vehicle.scheduleFile : schedulePath);
  if (!scheduleResult) {
    std::cerr << "bench_tx_listener: " << scheduleResult.error().toString() << '\n';
    return 1;
  }

  const std::string runtimeName = "bench-tx-listener-" + std::to_string(::getpid());
  if (auto initResult = ipc::Runtime::init(runtimeName, std::chrono::seconds{5}); !initResult) {
    std::cerr << "bench_tx_listener: " << initResult.error().toString() << '\n';
    return 1;
  }
  auto linkResult = can::openLink(can::LinkKind::Sim, bus->link.target, bus->linkOptions());
  if (!linkResult) {
    std::cerr << "bench_tx_listener: " << linkResult.error().toString() << '\n';
    return 1;
  }
  can::Link& link = **linkResult;

  const Recording recording = record(link, seconds, maxRate, connectMs, pollMs, tailMs);
  if (!dumpPath.empty() && !dump(recording, dumpPath)) {
    std::cerr << "bench_tx_listener: cannot write " << dumpPath << '\n';
    return 1;
  }
  const Analysis analysis = analyse(recording, vehicle, *scheduleResult);
  return report(recording, analysis, targets, link.name());
}
