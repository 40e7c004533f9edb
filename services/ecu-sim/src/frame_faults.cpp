#include "frame_faults.hpp"

#include <algorithm>
#include <charconv>

#include "openvcu/can/wire_time.hpp"

namespace openvcu::ecusim {
namespace {

struct KindName {
  FrameFaultKind kind;
  std::string_view name;
};
constexpr std::array<KindName, 8> KINDS{{{FrameFaultKind::Silent, "silent"},
                                         {FrameFaultKind::Delay, "delay"},
                                         {FrameFaultKind::Corrupt, "corrupt"},
                                         {FrameFaultKind::Replay, "replay"},
                                         {FrameFaultKind::Spoof, "spoof"},
                                         {FrameFaultKind::Claim, "claim"},
                                         {FrameFaultKind::Babble, "babble"},
                                         {FrameFaultKind::BusOff, "busoff"}}};

constexpr std::int64_t MS = 1'000'000;
constexpr std::int64_t MAX_DELAY_MS = 10'000;

std::string_view kindName(FrameFaultKind kind) {
  for (const KindName& entry : KINDS) {
    if (entry.kind == kind) return entry.name;
  }
  return "?";
}

/// "300" -> 300; "0x21" -> 33; empty for anything else.
std::optional<std::int64_t> parseInteger(std::string_view text) {
  int base = 10;
  if (text.starts_with("0x") || text.starts_with("0X")) {
    text.remove_prefix(2);
    base = 16;
  }
  std::int64_t value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value, base);
  if (text.empty() || error != std::errc{} || end != text.data() + text.size()) return std::nullopt;
  return value;
}

std::optional<std::uint8_t> parseAddress(std::string_view text) {
  const auto value = parseInteger(text);
  if (!value || *value < 0 || *value > 253) return std::nullopt;  // SAE J1939-81: 254 null, 255 global
  return static_cast<std::uint8_t>(*value);
}

}  // namespace

std::string FrameFaultRequest::name() const {
  return std::string(kindName(kind)) + "." + target;
}

std::optional<Result<FrameFaultRequest>> parseFrameFault(std::string_view key, bool on) {
  const auto dot = key.find('.');
  if (dot == std::string_view::npos) return std::nullopt;
  const std::string_view kindText = key.substr(0, dot);
  const auto kind = std::find_if(KINDS.begin(), KINDS.end(), [&](const KindName& k) { return k.name == kindText; });
  if (kind == KINDS.end()) return std::nullopt;
  FrameFaultRequest request;
  request.kind = kind->kind;
  std::string_view rest = key.substr(dot + 1);
  if (const auto equals = rest.find('='); equals != std::string_view::npos) {
    request.parameter = std::string(rest.substr(equals + 1));
    rest = rest.substr(0, equals);
  }
  request.target = std::string(rest);
  const std::string what = std::string(key) + ": ";
  if (request.target.empty())
    return Result<FrameFaultRequest>(Error{what + "no target after '" + std::string(kindText) + ".'"});
  if (request.kind == FrameFaultKind::Claim) {
    const auto address = parseAddress(request.target);
    if (!address)
      return Result<FrameFaultRequest>(
          Error{what + "the address must be 0..253 (33 or 0x21), not '" + request.target + "'"});
    request.address = *address;
  }
  if (!on) return Result<FrameFaultRequest>(std::move(request));  // clearing needs no parameter
  const std::string& parameter = request.parameter;
  switch (request.kind) {
    case FrameFaultKind::Silent:
    case FrameFaultKind::Claim:
    case FrameFaultKind::BusOff:
      if (!parameter.empty()) return Result<FrameFaultRequest>(Error{what + "takes no parameter"});
      break;
    case FrameFaultKind::Delay:
    case FrameFaultKind::Replay: {
      const auto ms = parseInteger(parameter);
      if (!ms || *ms < 1 || *ms > MAX_DELAY_MS) {
        return Result<FrameFaultRequest>(Error{what + "the time must be 1..10000 ms, not '" + parameter + "'"});
      }
      request.delayNs = *ms * MS;
      break;
    }
    case FrameFaultKind::Corrupt: {
      if (parameter.empty()) {
        request.mask.fill(0xFF);
        request.maskLength = request.mask.size();
        break;
      }
      if (parameter.size() % 2 != 0 || parameter.size() > 2 * can::MAX_DATA_LENGTH) {
        return Result<FrameFaultRequest>(
            Error{what + "the XOR mask must be whole hex bytes (e.g. FF01), not '" + parameter + "'"});
      }
      for (std::size_t i = 0; i < parameter.size(); i += 2) {
        std::uint8_t byte = 0;
        const auto [end, error] = std::from_chars(parameter.data() + i, parameter.data() + i + 2, byte, 16);
        if (error != std::errc{} || end != parameter.data() + i + 2) {
          return Result<FrameFaultRequest>(
              Error{what + "the XOR mask must be hex (e.g. FF01), not '" + parameter + "'"});
        }
        request.mask[i / 2] = byte;
      }
      request.maskLength = parameter.size() / 2;
      break;
    }
    case FrameFaultKind::Spoof: {
      const auto address = parseAddress(parameter);
      if (!address)
        return Result<FrameFaultRequest>(Error{what + "the source address must be 0..253, not '" + parameter + "'"});
      request.address = *address;
      break;
    }
    case FrameFaultKind::Babble: {
      double percent = 0;
      const auto [end, error] = std::from_chars(parameter.data(), parameter.data() + parameter.size(), percent);
      if (parameter.empty() || error != std::errc{} || end != parameter.data() + parameter.size() || !(percent > 0) ||
          percent > 100) {
        return Result<FrameFaultRequest>(
            Error{what + "the load must be above 0 and at most 100 %, not '" + parameter + "'"});
      }
      request.load = percent / 100.0;
      break;
    }
  }
  return Result<FrameFaultRequest>(std::move(request));
}

FrameFaults::FrameFaults(std::vector<FaultBus> buses) : m_buses(std::move(buses)) {
  m_faults.reserve(MAX_FAULTS);
  m_history.resize(HISTORY);
  m_held.reserve(DELAY_LINE);
}

std::optional<std::size_t> FrameFaults::targetIndex(const Fault& fault, std::size_t bus,
                                                    const can::Frame& frame) noexcept {
  for (std::size_t i = 0; i < fault.targets.size(); ++i) {
    const FrameTarget& target = fault.targets[i];
    if (target.bus == bus && target.id == frame.id && target.extended == frame.extended()) return i;
  }
  return std::nullopt;
}

std::optional<std::string> FrameFaults::apply(const FrameFaultRequest& request, bool on,
                                              std::vector<FrameTarget> targets, std::int64_t nowNs) {
  const std::string name = request.name();
  const auto existing = std::find_if(m_faults.begin(), m_faults.end(), [&](const Fault& f) { return f.name == name; });
  if (!on) {
    if (existing != m_faults.end()) {
      if (existing->request.kind == FrameFaultKind::BusOff) --m_cutBuses;
      m_faults.erase(existing);
    }
    return std::nullopt;  // clearing what is not active changes nothing
  }
  Fault fault;
  fault.request = request;
  fault.name = name;
  switch (request.kind) {
    case FrameFaultKind::Claim: {
      if (std::none_of(m_buses.begin(), m_buses.end(), [](const FaultBus& b) { return b.vcuName.has_value(); })) {
        return "no bus has a \"j1939\" object: there is no VCU NAME to outrank";
      }
      for (const FaultBus& bus : m_buses) {
        if (bus.vcuName && bus.vcuName->toValue() == 0)
          return "the VCU's NAME on bus " + bus.name + " is 0: no NAME outranks it";
      }
      fault.claimPending = true;
      break;
    }
    case FrameFaultKind::Babble:
    case FrameFaultKind::BusOff: {
      const auto bus =
          std::find_if(m_buses.begin(), m_buses.end(), [&](const FaultBus& b) { return b.name == request.target; });
      if (bus == m_buses.end()) {
        std::string known;
        for (const FaultBus& b : m_buses) known += (known.empty() ? "" : ", ") + b.name;
        return "no bus '" + request.target + "' (buses: " + known + ")";
      }
      fault.bus = static_cast<std::size_t>(bus - m_buses.begin());
      if (request.kind == FrameFaultKind::BusOff) break;
      can::Frame sample;
      sample.id = BABBLE_CAN_ID;
      sample.flags = can::FLAG_EXTENDED;
      sample.length = 8;
      sample.data.fill(0x55);  // average stuffing
      const std::int64_t wireNs = can::wireTimeNs(sample, bus->bitrate, bus->dataBitrate);
      fault.periodNs = std::max<std::int64_t>(1, static_cast<std::int64_t>(static_cast<double>(wireNs) / request.load));
      fault.nextNs = nowNs;
      break;
    }
    case FrameFaultKind::Replay: {
      fault.replayFrames.resize(targets.size());
      const std::int64_t wanted = nowNs - request.delayNs;
      for (std::size_t t = 0; t < targets.size(); ++t) {
        bool found = false;
        for (std::size_t n = 0; n < m_historyCount && !found; ++n) {  // newest first
          const Recorded& r = m_history[(m_historyNext + HISTORY - 1 - n) % HISTORY];
          if (r.atNs > wanted || r.bus != targets[t].bus || r.id != targets[t].id) continue;
          fault.replayFrames[t] = r.frame;
          found = true;
        }
        if (!found) {
          return "no frame of " + request.target + " was sent " + std::to_string(request.delayNs / MS) +
                 " ms ago or earlier (the history holds the last " + std::to_string(HISTORY) + " frames)";
        }
      }
      break;
    }
    default:
      break;
  }
  fault.targets = std::move(targets);
  if (existing != m_faults.end()) {
    *existing = std::move(fault);  // the same fault again: its new parameter replaces the old
    return std::nullopt;
  }
  if (m_faults.size() == MAX_FAULTS) return "already " + std::to_string(MAX_FAULTS) + " frame faults active";
  if (request.kind == FrameFaultKind::BusOff) ++m_cutBuses;
  m_faults.push_back(std::move(fault));
  return std::nullopt;
}

std::int64_t FrameFaults::nextDueNs() const noexcept {
  std::int64_t next = NEVER;
  for (const Held& held : m_held) next = std::min(next, held.dueNs);
  for (const Fault& fault : m_faults) {
    if (fault.claimPending) return 0;
    if (fault.request.kind == FrameFaultKind::Babble) next = std::min(next, fault.nextNs);
  }
  return next;
}

}  // namespace openvcu::ecusim
