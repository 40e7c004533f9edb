// Writes an HTML trace report of synthetic but plausible data (two buses, the thesis'
// nodes, cyclic messages with some jitter, 60 000-sample signals, DTCs, FSM events,
// findings) for the browser test (report_browser_test.sh) until `vcu trace report` writes
// one from a real log. The same run always writes the same bytes.
//
//   make_sample_report OUT.html [--signal-name NAME]
//   make_sample_report /tmp/report.html   ->  report.html with 9 charts
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <string>

#include "openvcu/trace/html_report.hpp"

using namespace openvcu::trace;

namespace {

constexpr double DURATION_S = 600.0;
constexpr double LOG_START_S = 1'700'000'000.0;
constexpr std::int64_t NS = 1'000'000'000;

/// A small deterministic generator (same numbers on every machine).
class Lcg {
 public:
  /// Uniform in [0, 1).
  double next() {
    m_state = m_state * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<double>(m_state >> 11) / 9007199254740992.0;
  }

 private:
  std::uint64_t m_state{21};
};

std::int64_t logNs(double s) { return static_cast<std::int64_t>((LOG_START_S + s) * 1e9); }

void addBuses(StatsReport& stats, Lcg& random) {
  for (const auto& [name, bitrate, base] : {std::tuple{"vehicle", 500'000u, 46.0}, std::tuple{"can1", 250'000u, 18.0}}) {
    BusStats bus;
    bus.bus = name;
    bus.bitrate = bitrate;
    bus.durationS = DURATION_S;
    bus.loadBucketS = DURATION_S / static_cast<double>(LOAD_SERIES_POINTS);
    double sum = 0;
    for (std::size_t i = 0; i < LOAD_SERIES_POINTS; ++i) {
      const double s = static_cast<double>(i) * bus.loadBucketS;
      double pct = base + 6 * std::sin(s / 40) + 3 * random.next();
      if (s > 300 && s < 320) pct += 25;  // a burst (BAM transfers)
      bus.loadSeries.emplace_back(s, pct);
      sum += pct;
      bus.loadMaxPct = std::max(bus.loadMaxPct, pct);
    }
    bus.loadMeanPct = sum / static_cast<double>(LOAD_SERIES_POINTS);
    bus.frames = static_cast<std::uint64_t>(bus.loadMeanPct / 100 * bitrate / 130 * DURATION_S);
    stats.frames += bus.frames;
    stats.buses.push_back(std::move(bus));
  }
}

void addNodes(StatsReport& stats) {
  // The thesis' Fig. 7.1 nodes, with its proportions (VCU over 40 %, VIG about 20 %).
  const struct {
    const char* name;
    std::uint8_t sa;
    double share;
  } nodes[] = {{"VCU", 0x27, 41.5}, {"VIG", 0x21, 19.8}, {"Editron", 0xEF, 11.2}, {"PDU", 0x4A, 9.3},
               {"HVLP1", 0xF4, 7.1},  {"HVLP2", 0xF5, 6.4}, {"", 0x80, 4.7}};
  const BusStats& vehicle = stats.buses[0];
  const double bits = vehicle.loadMeanPct / 100 * vehicle.bitrate;
  for (const auto& node : nodes) {
    NodeStats stat;
    stat.bus = "vehicle";
    stat.sa = node.sa;
    stat.name = node.name;
    stat.sharePct = node.share;
    stat.bitsPerS = bits * node.share / 100;
    stat.frames = static_cast<std::uint64_t>(stat.bitsPerS / 130 * DURATION_S);
    stats.nodes.push_back(stat);
  }
  NodeStats standard;
  standard.bus = "can1";
  standard.standard = true;
  standard.sharePct = 100;
  standard.bitsPerS = stats.buses[1].loadMeanPct / 100 * stats.buses[1].bitrate;
  standard.frames = stats.buses[1].frames;
  stats.nodes.push_back(standard);
}

void addMessages(StatsReport& stats, Lcg& random) {
  const double cycles[] = {10, 20, 50, 100, 100, 200, 500, 1000, 5000};
  const char* names[] = {"EEC1", "TSC1", "VCU_Status", "BMS_Limits", "PDU_Relays", "HVLP_Temp", "VIG_Cmd",
                         "DM1",  "Editron_Torque", "CCVS", "ET1", "VEP1"};
  for (std::uint32_t i = 0; i < 34; ++i) {
    MessageStats message;
    message.bus = i < 30 ? "vehicle" : "can1";
    message.extended = i < 30;
    message.sa = static_cast<std::uint8_t>(0x20 + i % 6);
    message.id = message.extended ? 0x0CF00000u + (i << 8) + message.sa : 0x100u + i;
    message.name = i % 3 == 2 ? std::string() : std::string(names[i % 12]) + (i >= 12 ? std::to_string(i) : "");
    message.expectedMs = i % 7 == 6 ? 0 : cycles[i % 9];
    message.cycleSource = message.expectedMs == 0 ? CycleSource::None
                          : i % 2 == 0            ? CycleSource::Schedule
                                                  : CycleSource::Attribute;
    const double nominal = message.expectedMs > 0 ? message.expectedMs : 250;
    message.meanMs = nominal + (random.next() - 0.3) * (i % 5 == 0 ? 17 : 3);
    message.p50Ms = std::round(message.meanMs * 10) / 10;
    message.p99Ms = message.meanMs + 2 + 5 * random.next();
    message.maxMs = message.p99Ms + 10 * random.next();
    message.minMs = message.meanMs - 1;
    message.deviationMs = message.expectedMs > 0 ? message.meanMs - message.expectedMs : 0;
    message.count = static_cast<std::uint64_t>(DURATION_S * 1000 / message.meanMs);
    if (i == 4) {
      message.gaps = 3;
      message.missing = 7;
    }
    stats.messages.push_back(std::move(message));
  }
}

void addSignals(ReportInput& input, const std::string& extraName) {
  SignalSeries speed{"VehicleSpeed", "km/h", {}};
  SignalSeries torque{"MotorTorque", "Nm", {}};
  SignalSeries torqueRequest{"TorqueRequest", "Nm", {}};
  SignalSeries soc{"BatterySoC", "%", {}};
  constexpr int SAMPLES = 60'000;  // 100 Hz for 10 min: decimated when drawn
  for (int i = 0; i < SAMPLES; ++i) {
    const double s = i * DURATION_S / SAMPLES;
    const double drive = s < 30 ? 0 : std::max(0.0, std::sin((s - 30) / 90));
    speed.samples.emplace_back(s, 42 * drive + (i % 97 == 0 ? 0.8 : 0));
    torque.samples.emplace_back(s, 180 * std::cos((s - 30) / 90) * (s > 30) + 8 * std::sin(s * 7));
    torqueRequest.samples.emplace_back(s, 180 * std::cos((s - 30) / 90) * (s > 30));
    if (i % 100 == 0) soc.samples.emplace_back(s, 92 - s / DURATION_S * 11);
  }
  input.signals = {speed, torque, torqueRequest, soc};
  if (!extraName.empty()) input.signals.push_back({extraName, "V", {{0, 1}, {DURATION_S, 2}}});
}

void addEvents(ReportInput& input) {
  EventLane state{"FSM state", {}};
  const struct {
    double s;
    const char* to;
  } transitions[] = {{2, "Standby"}, {12, "PreCharge"}, {18, "Ready"}, {30, "Driving"}, {305, "Fault"},
                     {318, "Standby"}, {330, "Ready"}, {340, "Driving"}, {580, "Ready"}, {595, "Standby"}};
  for (const auto& transition : transitions) {
    state.events.push_back({transition.s, transition.to,
                            std::strcmp(transition.to, "Fault") == 0 ? Severity::Fault : Severity::Info});
  }
  EventLane faults{"FSM faults", {{305, "HV isolation low", Severity::Fault}, {306.5, "Inverter derate", Severity::Warning}}};
  input.eventLanes = {state, faults};
}

void addDtcsAndFindings(ReportInput& input) {
  input.dtcs.push_back({.bus = 0, .source = 0xEF, .spn = 523, .fmi = 3, .occurrenceCount = 1,
                        .raisedNs = logNs(120), .clearedNs = logNs(160)});
  input.dtcs.push_back({.bus = 0, .source = 0xEF, .spn = 523, .fmi = 3, .occurrenceCount = 2,
                        .raisedNs = logNs(410), .clearedNs = logNs(440)});
  input.dtcs.push_back({.bus = 0, .source = 0x4A, .spn = 168, .fmi = 1, .occurrenceCount = 1,
                        .raisedNs = logNs(304), .clearedNs = std::nullopt});
  input.dtcs.push_back({.bus = 0, .source = 0x4A, .previouslyActive = true, .spn = 3509, .fmi = 4,
                        .occurrenceCount = 5, .raisedNs = logNs(200), .clearedNs = logNs(250)});
  ReportFindings sink;
  for (int i = 0; i < 40; ++i) {
    sink.finding({logNs(10 + i * 14.5), 0, Severity::Info, Check::Transport,
                  "BAM PGN 0xFECA from 0xEF completed (" + std::to_string(14 + i % 5) + " bytes)"});
  }
  sink.finding({logNs(120), 0, Severity::Warning, Check::Dtc, "DTC raised: SA 0xEF SPN 523 FMI 3 OC 1"});
  sink.finding({logNs(305.2), 0, Severity::Fault, Check::Safety,
                "S1_ES (0x0CEFF321): CrcMismatch: SHM CRC 0x8100EFA3, SDM data CRC 0x12345678"});
  sink.finding({logNs(306), 0, Severity::Fault, Check::Transport, "RTS/CTS 0x27 -> 0xEF PGN 0xEF00 timed out (T3)"});
  sink.finding({logNs(311), 0, Severity::Warning, Check::Cycle, "BMS_Limits 0x0CF00424: gap of 412 ms (3 cycles missing)"});
  sink.finding({logNs(450), 0, Severity::Fault, Check::Request, "request PGN 0xFEDA from 0x27 to 0x4A unanswered"});
  input.findings = sink.list();
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || std::strcmp(argv[1], "--help") == 0) {
    std::cerr << "usage: make_sample_report OUT.html [--signal-name NAME]\n"
                 "Writes an HTML trace report of synthetic data (tests/tools/report).\n";
    return argc < 2 ? 2 : 0;
  }
  std::string extraName;
  if (argc >= 4 && std::strcmp(argv[2], "--signal-name") == 0) extraName = argv[3];
  Lcg random;
  ReportInput input;
  input.title = "Sample trace report (synthetic data)";
  input.source = "synthetic data of tests/tools/report/make_sample_report.cpp: 2 buses, 10 min";
  input.stats.startS = LOG_START_S;
  input.stats.durationS = DURATION_S;
  input.buses = {"vehicle", "can1"};
  addBuses(input.stats, random);
  addNodes(input.stats);
  addMessages(input.stats, random);
  addSignals(input, extraName);
  addEvents(input);
  addDtcsAndFindings(input);
  const std::string html = renderHtmlReport(input);
  std::ofstream file(argv[1], std::ios::binary);
  file << html;
  file.close();
  if (!file) {
    std::cerr << "make_sample_report: cannot write " << argv[1] << ": " << std::strerror(errno) << "\n";
    return 1;
  }
  std::cout << argv[1] << ": " << html.size() << " bytes\n";
  return 0;
}
