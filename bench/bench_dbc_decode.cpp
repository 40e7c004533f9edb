// bench_dbc_decode: frames per second of openvcu's J1939 match + full decode, from memory,
// on one core, next to a deliberately naive reference decoder, plus a correctness check
// against the log generator's truth file.
//
//   /usr/bin/python3 ../shared/tools/gen-j1939-log.py --frames 1000000 --seed 1939
//       --out-dir /tmp/j1939 --truth 20000
//   bench_dbc_decode --dbc /tmp/j1939/synthetic_j1939.dbc --log /tmp/j1939/synthetic_j1939.log
//       --truth /tmp/j1939/synthetic_j1939.truth.jsonl
// (bench/run_decode_bench.sh does both.)
//
// The whole log is parsed into memory first (own candump -L parser: "(t) can0 18FEF100#0102.."),
// then each measured pass runs over all frames: MessageMatcher (MatchMode::J1939) finds the
// message, MessageCodec::decode visits every active signal and the physical values are summed
// into a sink that is printed, so nothing can be optimised away. Passes are repeated and the
// best (min) and median times are reported. See docs/benchmarks.md.

#include <sched.h>
#include <time.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <chrono>
#include <cinttypes>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <span>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "openvcu/dbc/codec.hpp"
#include "openvcu/dbc/matcher.hpp"
#include "openvcu/dbc/parser.hpp"

namespace {

namespace dbc = openvcu::dbc;
using Clock = std::chrono::steady_clock;

constexpr std::size_t MAX_PAYLOAD = 64;

/// One logged frame, as plain data in memory.
struct LogFrame {
  std::uint32_t id{};
  bool extended{};
  std::uint8_t length{};
  std::array<std::uint8_t, MAX_PAYLOAD> data{};

  [[nodiscard]] std::span<const std::uint8_t> payload() const noexcept { return {data.data(), length}; }
};

// ------------------------------------------------------------------ candump -L reader

int hexDigit(char c) noexcept {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

/// "(1700000000.001626) can0 0CF00447#F888D8084E2CF849" -> frame; CAN FD "ID##<flags><data>".
/// Remote and error frames and anything malformed -> false.
bool parseCandumpLine(std::string_view line, LogFrame& frame) noexcept {
  const std::size_t close = line.find(") ");
  if (line.empty() || line.front() != '(' || close == std::string_view::npos) return false;
  std::string_view rest = line.substr(close + 2);
  const std::size_t space = rest.find(' ');
  if (space == std::string_view::npos) return false;
  rest = rest.substr(space + 1);  // after the interface name
  const std::size_t hash = rest.find('#');
  if (hash == std::string_view::npos || hash == 0 || hash > 8) return false;
  std::uint32_t id = 0;
  for (std::size_t i = 0; i < hash; ++i) {
    const int digit = hexDigit(rest[i]);
    if (digit < 0) return false;
    id = (id << 4) | static_cast<std::uint32_t>(digit);
  }
  frame.extended = hash > 3;
  if ((id & 0x20000000u) != 0) return false;  // error frame (CAN_ERR_FLAG)
  frame.id = id;
  std::string_view hex = rest.substr(hash + 1);
  if (!hex.empty() && hex.front() == '#') hex = hex.substr(2);  // CAN FD: skip '#' and the flags nibble
  if (!hex.empty() && (hex.front() == 'R' || hex.front() == 'r')) return false;  // remote frame
  while (!hex.empty() && (hex.back() == '\r' || hex.back() == ' ' || hex.back() == 'T' || hex.back() == 'R')) {
    hex.remove_suffix(1);  // optional " T"/" R" direction
  }
  std::size_t length = 0;
  for (std::size_t i = 0; i < hex.size();) {
    if (hex[i] == '.') {
      ++i;
      continue;
    }
    if (i + 1 >= hex.size() || length >= MAX_PAYLOAD) return false;
    const int high = hexDigit(hex[i]);
    const int low = hexDigit(hex[i + 1]);
    if (high < 0 || low < 0) return false;
    frame.data[length++] = static_cast<std::uint8_t>((high << 4) | low);
    i += 2;
  }
  frame.length = static_cast<std::uint8_t>(length);
  return true;
}

std::vector<LogFrame> readCandumpLog(const std::string& path, std::size_t& skippedLines) {
  std::ifstream file(path, std::ios::binary | std::ios::ate);
  std::string text(static_cast<std::size_t>(std::max<std::streamoff>(0, file.tellg())), '\0');
  file.seekg(0);
  file.read(text.data(), static_cast<std::streamsize>(text.size()));
  std::vector<LogFrame> frames;
  frames.reserve(text.size() / 48);
  std::size_t begin = 0;
  while (begin < text.size()) {
    std::size_t end = text.find('\n', begin);
    if (end == std::string::npos) end = text.size();
    LogFrame frame;
    if (parseCandumpLine(std::string_view(text).substr(begin, end - begin), frame)) {
      frames.push_back(frame);
    } else if (end > begin) {
      ++skippedLines;
    }
    begin = end + 1;
  }
  return frames;
}

// ------------------------------------------------------------------ naive reference decoder

/// The decoder a first attempt would write: messages found through std::map by name, every
/// signal extracted bit by bit from its DBC start bit, multiplexors re-read by name.
/// Slow on purpose; shares nothing with MessageCodec but the parsed model.
class NaiveDecoder {
 public:
  using Visit = std::function<void(const dbc::Signal&, const dbc::DecodedValue&)>;

  explicit NaiveDecoder(const dbc::Database& db) {
    for (const dbc::Message& msg : db.messages) {
      if (msg.pseudo) continue;
      m_byName.emplace(msg.name, &msg);
      m_nameByExactId.emplace((std::uint64_t{msg.extended} << 32) | msg.id, msg.name);
      if (msg.extended) m_nameByPgn.emplace(pgnKey(msg.id), msg.name);  // first in file order wins
    }
  }

  /// J1939 rules of docs/design/j1939-matching.md: exact ID, then PGN (PDU1: own destination,
  /// then global). Returns the number of signals visited, or -1 when no message matches.
  int decode(const LogFrame& frame, const Visit& visit) const {
    const std::string* name = nullptr;
    if (auto exact = m_nameByExactId.find((std::uint64_t{frame.extended} << 32) | frame.id);
        exact != m_nameByExactId.end()) {
      name = &exact->second;
    } else if (frame.extended) {
      if (auto byPgn = m_nameByPgn.find(pgnKey(frame.id)); byPgn != m_nameByPgn.end()) {
        name = &byPgn->second;
      } else if (isPdu1(frame.id)) {
        const std::uint32_t global = (frame.id & ~0xFF00u) | 0xFF00u;
        if (auto toAll = m_nameByPgn.find(pgnKey(global)); toAll != m_nameByPgn.end()) name = &toAll->second;
      }
    }
    if (name == nullptr) return -1;
    const dbc::Message& msg = *m_byName.at(*name);
    int visited = 0;
    for (const dbc::Signal& sig : msg.signals) {
      if (!active(msg, sig, frame, 0)) continue;
      dbc::DecodedValue value;
      if (!extract(sig, frame, value)) continue;
      ++visited;
      visit(sig, value);
    }
    return visited;
  }

 private:
  static bool isPdu1(std::uint32_t id) { return ((id >> 16) & 0xFFu) < 0xF0u; }
  /// (EDP, DP, PF, PS-or-destination): PDU2 PS is part of the PGN, PDU1 PS the destination.
  static std::uint32_t pgnKey(std::uint32_t id) { return (id >> 8) & 0x3FFFFu; }

  /// The bits of a signal as an unsigned number, bit by bit; false if it does not fit.
  static bool rawBits(const dbc::Signal& sig, const LogFrame& frame, std::uint64_t& bits) {
    if (sig.size == 0 || sig.size > 64) return false;
    bits = 0;
    std::uint32_t position = sig.startBit;
    for (std::uint32_t k = 0; k < sig.size; ++k) {
      // Intel: bit k of the value is DBC bit start+k. Motorola: the start bit is the MSB,
      // then the sawtooth goes down within a byte and on to bit 7 of the next byte.
      const std::uint32_t valueBit = sig.byteOrder == dbc::ByteOrder::LittleEndian ? k : sig.size - 1 - k;
      if (position / 8 >= frame.length) return false;
      const std::uint64_t bit = (frame.data[position / 8] >> (position % 8)) & 1u;
      bits |= bit << valueBit;
      if (sig.byteOrder == dbc::ByteOrder::LittleEndian) {
        ++position;
      } else {
        position = position % 8 == 0 ? position + 15 : position - 1;
      }
    }
    return true;
  }

  static bool extract(const dbc::Signal& sig, const LogFrame& frame, dbc::DecodedValue& value) {
    std::uint64_t bits = 0;
    if (!rawBits(sig, frame, bits)) return false;
    if (sig.valueType == dbc::ValueType::Float32) {
      if (sig.size != 32) return false;
      float f;
      const auto narrow = static_cast<std::uint32_t>(bits);
      std::memcpy(&f, &narrow, sizeof f);
      value.kind = dbc::RawKind::Float32;
      value.rawFloat = static_cast<double>(f);
      value.physical = value.rawFloat * sig.factor + sig.offset;
    } else if (sig.valueType == dbc::ValueType::Float64) {
      if (sig.size != 64) return false;
      value.kind = dbc::RawKind::Float64;
      std::memcpy(&value.rawFloat, &bits, sizeof bits);
      value.physical = value.rawFloat * sig.factor + sig.offset;
    } else if (sig.isSigned) {
      value.kind = dbc::RawKind::Signed;
      std::int64_t signedValue = static_cast<std::int64_t>(bits);
      if (sig.size < 64 && ((bits >> (sig.size - 1)) & 1u) != 0) {
        signedValue = static_cast<std::int64_t>(bits | (~std::uint64_t{0} << sig.size));
      }
      value.rawSigned = signedValue;
      value.physical = static_cast<double>(signedValue) * sig.factor + sig.offset;
    } else {
      value.kind = dbc::RawKind::Unsigned;
      value.rawUnsigned = bits;
      value.physical = static_cast<double>(bits) * sig.factor + sig.offset;
    }
    return true;
  }

  /// Whether a signal is selected, following its multiplexor chain by name.
  static bool active(const dbc::Message& msg, const dbc::Signal& sig, const LogFrame& frame, int depth) {
    if (sig.muxSwitch.empty()) {  // a root; a multiplexed signal without multiplexor is never selected
      return sig.muxRole != dbc::MuxRole::Multiplexed && sig.muxRole != dbc::MuxRole::MultiplexedMultiplexor;
    }
    const dbc::Signal* switchSignal = msg.findSignal(sig.muxSwitch);
    std::uint64_t selector = 0;
    if (switchSignal == nullptr || depth > 16 || !active(msg, *switchSignal, frame, depth + 1) ||
        !rawBits(*switchSignal, frame, selector)) {
      return false;
    }
    if (sig.muxRanges.empty()) return selector == sig.muxValue;
    return std::any_of(sig.muxRanges.begin(), sig.muxRanges.end(),
                       [&](const dbc::MuxRange& range) { return selector >= range.low && selector <= range.high; });
  }

  std::map<std::string, const dbc::Message*> m_byName;
  std::map<std::uint64_t, std::string> m_nameByExactId;
  std::map<std::uint32_t, std::string> m_nameByPgn;
};

// ------------------------------------------------------------------ measuring

struct Timing {
  std::vector<double> seconds;     ///< wall clock (steady_clock) per pass
  std::vector<double> cpuSeconds;  ///< this thread's CPU time per pass (immune to being descheduled)
  double sink{};                   ///< sum of all physical values of the last pass
  std::uint64_t signals{};         ///< signals visited in the last pass
  std::uint64_t unmatched{};
};

/// CPU time of the calling thread: on a shared machine the wall clock also counts the time
/// other processes had the core.
double threadCpuSeconds() {
  timespec now{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  return static_cast<double>(now.tv_sec) + static_cast<double>(now.tv_nsec) * 1e-9;
}

template <typename Pass>
Timing measure(int repeat, Pass&& pass) {
  Timing timing;
  for (int r = 0; r < repeat; ++r) {
    timing.sink = 0.0;
    timing.signals = 0;
    timing.unmatched = 0;
    const double cpuStart = threadCpuSeconds();
    const auto start = Clock::now();
    pass(timing);
    const auto stop = Clock::now();
    timing.cpuSeconds.push_back(threadCpuSeconds() - cpuStart);
    timing.seconds.push_back(std::chrono::duration<double>(stop - start).count());
  }
  return timing;
}

/// best (min) and median of a series of pass times, as Mframes/s and ns/frame.
std::string rates(std::vector<double> seconds, std::size_t frames) {
  std::sort(seconds.begin(), seconds.end());
  const double best = seconds.front();
  const double median = seconds[seconds.size() / 2];
  const auto count = static_cast<double>(frames);
  char text[160];
  std::snprintf(text, sizeof text, "best %6.2f Mframes/s %6.1f ns/frame, median %6.2f Mframes/s %6.1f ns/frame",
                count / best / 1e6, best / count * 1e9, count / median / 1e6, median / count * 1e9);
  return text;
}

/// CPU ns/frame of the best (min) or the median pass.
double cpuNsPerFrame(std::vector<double> seconds, std::size_t frames, bool median) {
  std::sort(seconds.begin(), seconds.end());
  const double pass = median ? seconds[seconds.size() / 2] : seconds.front();
  return pass / static_cast<double>(frames) * 1e9;
}

void report(const char* label, const Timing& timing, std::size_t frames) {
  std::printf("%s\n  cpu  %s\n  wall %s\n  %" PRIu64 " signals decoded, %" PRIu64 " frames unmatched, sink %.9e\n",
              label, rates(timing.cpuSeconds, frames).c_str(), rates(timing.seconds, frames).c_str(), timing.signals,
              timing.unmatched, timing.sink);
}

bool pinToCpu(int cpu) {
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(cpu, &set);
  return sched_setaffinity(0, sizeof set, &set) == 0;
}

// ------------------------------------------------------------------ correctness vs truth

/// Whether a truth raw value (JSON number) equals a decoded one, exactly.
bool sameRaw(const nlohmann::json& truth, const dbc::DecodedValue& value) {
  switch (value.kind) {
    case dbc::RawKind::Unsigned:
      return truth.is_number_unsigned() && truth.get<std::uint64_t>() == value.rawUnsigned;
    case dbc::RawKind::Signed:
      return truth.is_number_integer() && truth.get<std::int64_t>() == value.rawSigned;
    default:
      return truth.is_number() && truth.get<double>() == value.rawFloat;
  }
}

struct Agreement {
  std::uint64_t frames{}, values{}, agree{}, differ{};
  std::string firstDifference;
};

std::string hexOf(const LogFrame& frame) {
  static constexpr char DIGITS[] = "0123456789ABCDEF";
  std::string text;
  for (const std::uint8_t byte : frame.payload()) {
    text += DIGITS[byte >> 4];
    text += DIGITS[byte & 0xF];
  }
  return text;
}

/// Decodes the first frames of the log with `decode` (name -> value per frame) and compares
/// with the generator's packed raw values: same signal names, same raw values.
template <typename DecodeFrame>
Agreement checkTruth(const std::string& truthPath, const std::vector<LogFrame>& frames, DecodeFrame&& decode) {
  Agreement result;
  std::ifstream truth(truthPath);
  std::string line;
  std::size_t index = 0;
  while (std::getline(truth, line) && index < frames.size()) {
    const nlohmann::json expected = nlohmann::json::parse(line);
    const LogFrame& frame = frames[index++];
    ++result.frames;
    if (expected.at("id").get<std::uint32_t>() != frame.id || expected.at("data").get<std::string>() != hexOf(frame)) {
      ++result.differ;  // the truth file does not describe this log
      if (result.firstDifference.empty())
        result.firstDifference = "frame " + std::to_string(index) + " is not in the log";
      continue;
    }
    std::map<std::string, dbc::DecodedValue> decoded;
    decode(frame, decoded);
    std::map<std::string, bool> seen;
    for (const auto& [name, raw] : expected.at("raw").items()) {
      ++result.values;
      const auto it = decoded.find(name);
      if (it != decoded.end() && sameRaw(raw, it->second)) {
        ++result.agree;
      } else {
        ++result.differ;
        if (result.firstDifference.empty()) result.firstDifference = "frame " + std::to_string(index) + " " + name;
      }
      seen[name] = true;
    }
    for (const auto& [name, value] : decoded) {
      if (seen.count(name) != 0) continue;
      ++result.values;
      ++result.differ;  // decoded a signal the generator did not pack
      if (result.firstDifference.empty()) result.firstDifference = "frame " + std::to_string(index) + " extra " + name;
    }
  }
  return result;
}

void printAgreement(const char* label, const Agreement& agreement) {
  std::printf("truth %-10s %" PRIu64 " frames, %" PRIu64 " raw values: %" PRIu64 " agree, %" PRIu64 " differ%s%s\n",
              label, agreement.frames, agreement.values, agreement.agree, agreement.differ,
              agreement.firstDifference.empty() ? "" : "; first: ", agreement.firstDifference.c_str());
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Decode throughput of openvcu::dbc (J1939 match + all signals) from memory, one core"};
  std::string dbcPath, logPath, truthPath;
  int repeat = 7;
  int cpu = 0;
  bool onlyOpenvcu = false;
  app.add_option("--dbc", dbcPath, "DBC file (synthetic_j1939.dbc)")->required();
  app.add_option("--log", logPath, "candump -L log (synthetic_j1939.log)")->required();
  app.add_option("--truth", truthPath, "generator truth file (synthetic_j1939.truth.jsonl)");
  app.add_option("--repeat", repeat, "measured passes per decoder (default 7)")->check(CLI::Range(1, 1000));
  app.add_option("--cpu", cpu, "pin to this CPU (-1: do not pin; default 0)");
  app.add_flag("--only-openvcu", onlyOpenvcu, "measure only openvcu's match + decode (for profilers)");
  CLI11_PARSE(app, argc, argv);

  std::vector<openvcu::Error> warnings;
  auto loadResult = dbc::loadFile(dbcPath, &warnings);
  if (!loadResult) {
    std::cerr << loadResult.error().toString() << '\n';
    return 1;
  }
  const dbc::Database& db = *loadResult;

  std::size_t skippedLines = 0;
  const auto readStart = Clock::now();
  const std::vector<LogFrame> frames = readCandumpLog(logPath, skippedLines);
  const double readSeconds = std::chrono::duration<double>(Clock::now() - readStart).count();
  if (frames.empty()) {
    std::cerr << logPath << ": no frames\n";
    return 1;
  }
  if (cpu >= 0 && !pinToCpu(cpu)) std::cerr << "warning: cannot pin to CPU " << cpu << '\n';

  std::printf("dbc %s: %zu messages (%zu warnings); log %s: %zu frames read in %.2f s (%zu lines skipped)\n",
              dbcPath.c_str(), db.messages.size(), warnings.size(), logPath.c_str(), frames.size(), readSeconds,
              skippedLines);
  std::printf("%d passes per decoder, %s\n", repeat,
              cpu >= 0 ? ("pinned to CPU " + std::to_string(cpu)).c_str() : "not pinned");

  const dbc::MessageMatcher matcher(db, dbc::MatchMode::J1939);
  const dbc::DatabaseCodec codecs(db);

  // 1. what the brief asks for: match (J1939 PGN mode) + decode of every signal.
  const Timing fast = measure(repeat, [&](Timing& t) {
    double sink = 0.0;
    std::uint64_t signals = 0;
    std::uint64_t unmatched = 0;
    for (const LogFrame& frame : frames) {
      const std::int32_t index = matcher.match(frame.id, frame.extended);
      if (index < 0) {
        ++unmatched;
        continue;
      }
      const auto summary = codecs[static_cast<std::size_t>(index)].decode(
          frame.payload(), [&sink](std::uint32_t, const dbc::DecodedValue& value) { sink += value.physical; });
      signals += summary.decoded;
    }
    t.sink = sink;
    t.signals = signals;
    t.unmatched = unmatched;
  });

  report("openvcu match(J1939) + decode", fast, frames.size());
  if (onlyOpenvcu) {
    std::printf("RESULT ns_per_frame=%.2f ns_per_frame_median=%.2f\n", cpuNsPerFrame(fast.cpuSeconds, frames.size(), false),
                cpuNsPerFrame(fast.cpuSeconds, frames.size(), true));
    return 0;
  }

  // 2. and 3. the two halves on their own, to see where the time goes.
  const Timing matchOnly = measure(repeat, [&](Timing& t) {
    std::int64_t sum = 0;
    for (const LogFrame& frame : frames) sum += matcher.match(frame.id, frame.extended);
    t.sink = static_cast<double>(sum);
  });
  std::vector<std::int32_t> matched(frames.size());
  for (std::size_t i = 0; i < frames.size(); ++i) matched[i] = matcher.match(frames[i].id, frames[i].extended);
  const Timing decodeOnly = measure(repeat, [&](Timing& t) {
    double sink = 0.0;
    std::uint64_t signals = 0;
    for (std::size_t i = 0; i < frames.size(); ++i) {
      if (matched[i] < 0) continue;
      const auto summary = codecs[static_cast<std::size_t>(matched[i])].decode(
          frames[i].payload(), [&sink](std::uint32_t, const dbc::DecodedValue& value) { sink += value.physical; });
      signals += summary.decoded;
    }
    t.sink = sink;
    t.signals = signals;
  });

  // 4. the naive reference, same work.
  const NaiveDecoder naive(db);
  const Timing reference = measure(repeat, [&](Timing& t) {
    double sink = 0.0;
    std::uint64_t signals = 0;
    std::uint64_t unmatched = 0;
    const NaiveDecoder::Visit visit = [&sink](const dbc::Signal&, const dbc::DecodedValue& value) {
      sink += value.physical;
    };
    for (const LogFrame& frame : frames) {
      const int visited = naive.decode(frame, visit);
      if (visited < 0) {
        ++unmatched;
      } else {
        signals += static_cast<std::uint64_t>(visited);
      }
    }
    t.sink = sink;
    t.signals = signals;
    t.unmatched = unmatched;
  });

  report("  match only", matchOnly, frames.size());
  report("  decode only (index precomputed)", decodeOnly, frames.size());
  report("naive reference (std::map, bit loop)", reference, frames.size());
  const bool sameWork = fast.signals == reference.signals && fast.unmatched == reference.unmatched &&
                        std::fabs(fast.sink - reference.sink) <= 1e-9 * std::max(1.0, std::fabs(fast.sink));
  std::printf("openvcu vs naive on all %zu frames: %s (signals %" PRIu64 " / %" PRIu64 ", sink %.9e / %.9e)\n",
              frames.size(), sameWork ? "same" : "DIFFERENT", fast.signals, reference.signals, fast.sink,
              reference.sink);
  std::printf("speed-up over naive: %.1fx (best passes, cpu time)\n",
              *std::min_element(reference.cpuSeconds.begin(), reference.cpuSeconds.end()) /
                  *std::min_element(fast.cpuSeconds.begin(), fast.cpuSeconds.end()));

  bool truthAgrees = true;
  if (!truthPath.empty()) {
    const Agreement ours = checkTruth(truthPath, frames, [&](const LogFrame& frame, auto& decoded) {
      const std::int32_t index = matcher.match(frame.id, frame.extended);
      if (index < 0) return;
      const dbc::Message& msg = db.messages[static_cast<std::size_t>(index)];
      codecs[static_cast<std::size_t>(index)].decode(frame.payload(),
                                                     [&](std::uint32_t signalIndex, const dbc::DecodedValue& value) {
                                                       decoded[msg.signals[signalIndex].name] = value;
                                                     });
    });
    const Agreement theirs = checkTruth(truthPath, frames, [&](const LogFrame& frame, auto& decoded) {
      (void)naive.decode(frame,
                         [&](const dbc::Signal& sig, const dbc::DecodedValue& value) { decoded[sig.name] = value; });
    });
    printAgreement("openvcu", ours);
    printAgreement("naive", theirs);
    truthAgrees = ours.differ == 0 && theirs.differ == 0 && ours.frames > 0;
  }
  // One machine-readable line, CPU time of the thread (best and median pass).
  std::printf("RESULT ns_per_frame=%.2f ns_per_frame_median=%.2f match_ns=%.2f decode_ns=%.2f naive_ns=%.2f "
              "same_as_naive=%d truth_agree=%d\n",
              cpuNsPerFrame(fast.cpuSeconds, frames.size(), false), cpuNsPerFrame(fast.cpuSeconds, frames.size(), true),
              cpuNsPerFrame(matchOnly.cpuSeconds, frames.size(), false),
              cpuNsPerFrame(decodeOnly.cpuSeconds, frames.size(), false),
              cpuNsPerFrame(reference.cpuSeconds, frames.size(), false), sameWork ? 1 : 0,
              truthAgrees && !truthPath.empty() ? 1 : 0);
  return sameWork && truthAgrees ? 0 : 2;
}
