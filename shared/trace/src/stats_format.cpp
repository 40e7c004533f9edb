// The text and JSON forms of a StatsReport (`vcu trace stats --format text|json`).
//
//   Buses
//     BUS   BIT RATE    FRAMES  ERROR FRAMES  DURATION s  LOAD MEAN %  LOAD PEAK %
//     can0  500 kbit/s   12000             0      60.000        23.10        24.02
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "openvcu/trace/frame_writer.hpp"
#include "openvcu/trace/stats.hpp"

namespace openvcu::trace {
namespace {

/// Columns padded to their widest cell; `rightAligned[i]` for numeric columns.
class Table {
 public:
  Table(std::vector<std::string> header, std::vector<bool> rightAligned)
      : m_rightAligned(std::move(rightAligned)) {
    m_rows.push_back(std::move(header));
  }
  void addRow(std::vector<std::string> cells) { m_rows.push_back(std::move(cells)); }

  void appendTo(std::string& out) const {
    std::vector<std::size_t> widths(m_rows.front().size(), 0);
    for (const auto& row : m_rows) {
      for (std::size_t c = 0; c < row.size() && c < widths.size(); ++c) widths[c] = std::max(widths[c], row[c].size());
    }
    for (const auto& row : m_rows) {
      std::string line = "  ";
      for (std::size_t c = 0; c < widths.size(); ++c) {
        const std::string& cell = c < row.size() ? row[c] : std::string();
        const std::string padding(widths[c] - cell.size(), ' ');
        if (c > 0) line += "  ";
        if (m_rightAligned[c]) {
          line += padding + cell;
        } else {
          line += cell + padding;
        }
      }
      while (!line.empty() && line.back() == ' ') line.pop_back();
      out += line;
      out += '\n';
    }
  }

 private:
  std::vector<std::vector<std::string>> m_rows;
  std::vector<bool> m_rightAligned;
};

std::string fixed(double value, int decimals) {
  char text[64];
  std::snprintf(text, sizeof text, "%.*f", decimals, value);
  return text;
}

std::string hexId(std::uint32_t id, bool extended) {
  char text[16];
  std::snprintf(text, sizeof text, extended ? "0x%08X" : "0x%03X", id);
  return text;
}

std::string hexByte(std::uint8_t value) {
  char text[8];
  std::snprintf(text, sizeof text, "0x%02X", value);
  return text;
}

std::string bitrateText(std::uint32_t bitrate) {
  if (bitrate % 1000 == 0) return std::to_string(bitrate / 1000) + " kbit/s";
  return std::to_string(bitrate) + " bit/s";
}

std::string_view cycleSourceName(CycleSource source) {
  switch (source) {
    case CycleSource::Schedule: return "schedule";
    case CycleSource::Attribute: return "GenMsgCycleTime";
    case CycleSource::None: break;
  }
  return "";
}

/// The value rounded to `decimals` places, in the shortest text that reads back.
void appendRounded(std::string& out, double value, int decimals) {
  const double scale = std::pow(10.0, decimals);
  appendNumber(out, std::round(value * scale) / scale, true);
}

void appendKey(std::string& out, std::string_view key) {
  out += '"';
  out += key;
  out += "\":";
}

void appendField(std::string& out, std::string_view key, double value, int decimals) {
  appendKey(out, key);
  appendRounded(out, value, decimals);
  out += ',';
}

void appendField(std::string& out, std::string_view key, std::uint64_t value) {
  appendKey(out, key);
  out += std::to_string(value);
  out += ',';
}

void appendField(std::string& out, std::string_view key, std::string_view text) {
  appendKey(out, key);
  appendJsonString(out, text);
  out += ',';
}

void appendNull(std::string& out, std::string_view key) {
  appendKey(out, key);
  out += "null,";
}

/// Replaces the trailing comma of an object's or array's last element by `close`.
void close(std::string& out, char close) {
  if (!out.empty() && out.back() == ',') {
    out.back() = close;
  } else {
    out += close;
  }
}

}  // namespace

void appendStatsText(std::string& out, const StatsReport& report) {
  out += "Trace: " + std::to_string(report.frames) + " frames over " + fixed(report.durationS, 3) + " s";
  if (report.skippedFrames > 0) {
    out += "; " + std::to_string(report.skippedFrames) + " frames of streams beyond the first " +
           std::to_string(MAX_STREAMS) + " not measured";
  }
  if (report.backwardSteps > 0) {
    out += "; " + std::to_string(report.backwardSteps) + " periods not measured (time went back)";
  }
  out += "\n\nBuses (load: wire time incl. stuff bits / time; peak over " + fixed(LOAD_WINDOW_NS / 1e9, 0) +
         " s windows)\n";
  Table buses({"BUS", "BIT RATE", "FRAMES", "ERROR FRAMES", "DURATION s", "LOAD MEAN %", "LOAD PEAK %"},
              {false, false, true, true, true, true, true});
  for (const BusStats& bus : report.buses) {
    buses.addRow({bus.bus, bitrateText(bus.bitrate), std::to_string(bus.frames), std::to_string(bus.errorFrames),
                  fixed(bus.durationS, 3), fixed(bus.loadMeanPct, 2), fixed(bus.loadMaxPct, 2)});
  }
  buses.appendTo(out);

  out += "\nNodes (J1939 source address; 11-bit frames as one node)\n";
  Table nodes({"BUS", "SA", "NAME", "FRAMES", "BIT/S", "SHARE %"}, {false, false, false, true, true, true});
  for (const NodeStats& node : report.nodes) {
    nodes.addRow({node.bus, node.standard ? "11-bit" : hexByte(node.sa), node.name.empty() ? "-" : node.name,
                  std::to_string(node.frames), fixed(node.bitsPerS, 0), fixed(node.sharePct, 2)});
  }
  nodes.appendTo(out);

  out += "\nMessages (periods in ms; p50/p99 rounded to 0.1 ms up to 200 ms, within 0.4 % above; gap: period > 1.5 x expected)\n";
  Table messages({"BUS", "ID", "NAME", "COUNT", "EXPECTED", "MEAN", "P50", "P99", "MAX", "DEVIATION", "GAPS", "MISSING"},
                 {false, false, false, true, true, true, true, true, true, true, true, true});
  for (const MessageStats& message : report.messages) {
    const bool expected = message.expectedMs > 0;
    const bool measured = message.periods > 0;
    auto ms = [measured](double value) { return measured ? fixed(value, 3) : std::string("-"); };
    messages.addRow({message.bus, hexId(message.id, message.extended), message.name.empty() ? "-" : message.name,
                     std::to_string(message.count), expected ? fixed(message.expectedMs, 3) : "-", ms(message.meanMs),
                     ms(message.p50Ms), ms(message.p99Ms), ms(message.maxMs),
                     expected && measured ? fixed(message.deviationMs, 3) : "-",
                     expected ? std::to_string(message.gaps) : "-", expected ? std::to_string(message.missing) : "-"});
  }
  messages.appendTo(out);
}

void appendStatsJson(std::string& out, const StatsReport& report) {
  constexpr int MS_DECIMALS = 3;
  constexpr int PCT_DECIMALS = 2;
  out += '{';
  appendField(out, "start_s", report.startS, 6);
  appendField(out, "duration_s", report.durationS, 6);
  appendField(out, "frames", report.frames);
  appendField(out, "skipped_frames", report.skippedFrames);
  appendField(out, "backward_steps", report.backwardSteps);
  appendKey(out, "period_resolution");
  out += '{';
  appendField(out, "bin_ms", PERIOD_BIN_NS / 1e6, MS_DECIMALS);
  appendField(out, "linear_up_to_ms", PERIOD_LINEAR_NS / 1e6, MS_DECIMALS);
  appendField(out, "octave_bins", static_cast<std::uint64_t>(PERIOD_OCTAVE_BINS));
  appendField(out, "range_ms", PERIOD_RANGE_NS / 1e6, MS_DECIMALS);
  close(out, '}');
  out += ',';

  appendKey(out, "buses");
  out += '[';
  for (const BusStats& bus : report.buses) {
    out += '{';
    appendField(out, "bus", bus.bus);
    appendField(out, "bitrate", std::uint64_t{bus.bitrate});
    appendField(out, "frames", bus.frames);
    appendField(out, "error_frames", bus.errorFrames);
    appendField(out, "duration_s", bus.durationS, 6);
    appendField(out, "load_mean_pct", bus.loadMeanPct, PCT_DECIMALS);
    appendField(out, "load_max_pct", bus.loadMaxPct, PCT_DECIMALS);
    appendField(out, "load_window_s", LOAD_WINDOW_NS / 1e9, 3);
    close(out, '}');
    out += ',';
  }
  close(out, ']');
  out += ',';

  appendKey(out, "nodes");
  out += '[';
  for (const NodeStats& node : report.nodes) {
    out += '{';
    appendField(out, "bus", node.bus);
    if (node.standard) {
      appendNull(out, "sa");
    } else {
      appendField(out, "sa", std::uint64_t{node.sa});
    }
    appendKey(out, "standard");
    out += node.standard ? "true," : "false,";
    if (node.name.empty()) {
      appendNull(out, "name");
    } else {
      appendField(out, "name", node.name);
    }
    appendField(out, "frames", node.frames);
    appendField(out, "bits_per_s", node.bitsPerS, 1);
    appendField(out, "share_pct", node.sharePct, PCT_DECIMALS);
    close(out, '}');
    out += ',';
  }
  close(out, ']');
  out += ',';

  appendKey(out, "messages");
  out += '[';
  for (const MessageStats& message : report.messages) {
    const bool expected = message.expectedMs > 0;
    const bool measured = message.periods > 0;
    out += '{';
    appendField(out, "bus", message.bus);
    appendField(out, "id", hexId(message.id, message.extended));
    appendKey(out, "extended");
    out += message.extended ? "true," : "false,";
    if (message.name.empty()) {
      appendNull(out, "name");
    } else {
      appendField(out, "name", message.name);
    }
    if (message.extended) {
      appendField(out, "sa", std::uint64_t{message.sa});
    } else {
      appendNull(out, "sa");
    }
    appendField(out, "count", message.count);
    appendField(out, "periods", message.periods);
    if (expected) {
      appendField(out, "expected_ms", message.expectedMs, MS_DECIMALS);
      appendField(out, "cycle_source", cycleSourceName(message.cycleSource));
    } else {
      appendNull(out, "expected_ms");
      appendNull(out, "cycle_source");
    }
    auto period = [&out, measured](std::string_view key, double value) {
      if (measured) {
        appendField(out, key, value, MS_DECIMALS);
      } else {
        appendNull(out, key);
      }
    };
    period("mean_ms", message.meanMs);
    period("p50_ms", message.p50Ms);
    period("p99_ms", message.p99Ms);
    period("max_ms", message.maxMs);
    period("min_ms", message.minMs);
    if (expected && measured) {
      appendField(out, "deviation_ms", message.deviationMs, MS_DECIMALS);
    } else {
      appendNull(out, "deviation_ms");
    }
    appendField(out, "gaps", message.gaps);
    appendField(out, "missing", message.missing);
    close(out, '}');
    out += ',';
  }
  close(out, ']');
  out += "}\n";
}

}  // namespace openvcu::trace
