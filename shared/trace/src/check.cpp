// TraceChecker: the J1939-76 check (safety_check.cpp), the request check (here) and the
// transport/DTC analysis (TransportAnalysis) over one timeline, with the findings counted
// by severity on their way to the caller's sink.
#include "openvcu/trace/check.hpp"

#include <array>
#include <cstdio>
#include <optional>

#include "openvcu/j1939/acknowledgement.hpp"
#include "openvcu/j1939/id.hpp"
#include "openvcu/j1939/request.hpp"
#include "openvcu/j1939/transport.hpp"
#include "safety_check.hpp"

namespace openvcu::trace {
namespace {

std::string pgnText(std::uint32_t pgn) {
  char text[32];
  std::snprintf(text, sizeof text, "PGN %u (0x%04X)", static_cast<unsigned>(pgn), static_cast<unsigned>(pgn));
  return text;
}

std::string address(std::uint8_t value) {
  char text[8];
  std::snprintf(text, sizeof text, "0x%02X", value);
  return text;
}

/// Every address: the checker listens to all requests on the bus, not one node's.
constexpr j1939::AddressSet everyAddress() noexcept {
  j1939::AddressSet all{};
  for (bool& one : all) one = true;
  return all;
}
constexpr j1939::AddressSet EVERY_ADDRESS = everyAddress();

/// Counts findings by severity and hands them on.
class CountingSink final : public FindingSink {
 public:
  CountingSink(FindingSink& next, CheckCounts& counts) noexcept : m_next(next), m_counts(counts) {}
  void finding(const Finding& finding) override {
    switch (finding.severity) {
      case Severity::Info:
        ++m_counts.infos;
        break;
      case Severity::Warning:
        ++m_counts.warnings;
        break;
      case Severity::Fault:
        ++m_counts.faults;
        break;
    }
    m_next.finding(finding);
  }

 private:
  FindingSink& m_next;
  CheckCounts& m_counts;
};

/// J1939-21 requests (PGN 59904) and their answers: a table of at most MAX_OPEN_REQUESTS
/// open requests, scanned per frame only while it holds any.
class RequestCheck {
 public:
  void add(const TraceFrame& frame, FindingSink& sink, CheckCounts& counts) {
    if (m_open > 0) expire(frame.timeNs, sink, counts);
    const can::Frame& can = frame.frame;
    if (!can.extended() || (can.flags & (can::FLAG_ERROR | can::FLAG_RTR)) != 0) return;
    const j1939::Id id = j1939::Id::fromCanId(can.id);
    if (m_open > 0) answer(frame, id, sink);
    const std::optional<j1939::Request> request = j1939::parseRequest(can.id, true, can.payload(), EVERY_ADDRESS);
    if (!request) return;
    ++counts.requests;
    if (m_open == m_requests.size()) {
      if (counts.requestsSkipped++ == 0) {
        sink.finding(Finding{frame.timeNs, frame.bus, Severity::Warning, Check::Request,
                             "more than " + std::to_string(MAX_OPEN_REQUESTS) +
                                 " requests waiting for an answer: further ones are not checked (counted at the end)"});
      }
      return;
    }
    m_requests[m_open++] = Open{frame.timeNs, request->pgn, frame.bus, request->requester, id.destination()};
  }

  void finish(std::int64_t endNs, FindingSink& sink, CheckCounts& counts) {
    expire(endNs, sink, counts);
    for (std::size_t i = 0; i < m_open; ++i) {
      const Open& open = m_requests[i];
      sink.finding(Finding{open.timeNs, open.bus, Severity::Info, Check::Request,
                           describe(open) + ": the log ends before its answer was due"});
    }
    if (counts.requestsSkipped > 0) {
      sink.finding(Finding{endNs, 0, Severity::Warning, Check::Request,
                           std::to_string(counts.requestsSkipped) + " requests not checked (table full)"});
    }
  }

 private:
  struct Open {
    std::int64_t timeNs{};
    std::uint32_t pgn{};
    std::uint16_t bus{};
    std::uint8_t requester{};
    std::uint8_t destination{};  ///< 0xFF: global
  };

  static std::string describe(const Open& open) {
    return "request from " + address(open.requester) + " to " +
           (open.destination == j1939::GLOBAL_ADDRESS ? std::string("global") : address(open.destination)) + " for " +
           pgnText(open.pgn);
  }

  void expire(std::int64_t nowNs, FindingSink& sink, CheckCounts& counts) {
    for (std::size_t i = 0; i < m_open;) {
      const Open& open = m_requests[i];
      if (nowNs - open.timeNs <= REQUEST_TIMEOUT_NS) {
        ++i;
        continue;
      }
      ++counts.unanswered;
      // at the request's own frame, so that its time is found in the log
      sink.finding(
          Finding{open.timeNs, open.bus, Severity::Fault, Check::Request,
                  describe(open) + ": no answer within " + std::to_string(REQUEST_TIMEOUT_NS / 1'000'000) + " ms"});
      remove(i);
    }
  }

  /// Closes the open requests `frame` answers: the PGN itself, an ACK/NACK for it, or a
  /// TP.CM BAM/RTS announcing it, from the addressee (from anyone for a global request).
  void answer(const TraceFrame& frame, const j1939::Id& id, FindingSink& sink) {
    const std::span<const std::uint8_t> data = frame.frame.payload();
    std::uint32_t answered = id.pgn();
    std::optional<j1939::Acknowledgement> ack;
    if (answered == j1939::PGN_ACKNOWLEDGEMENT) {
      ack = j1939::decodeAcknowledgement(data);
      if (!ack) return;
      answered = ack->pgn;
    } else if (answered == j1939::PGN_TP_CM) {
      if (data.size() != j1939::TP_FRAME_LENGTH || (data[0] != j1939::TP_CM_BAM && data[0] != j1939::TP_CM_RTS)) return;
      answered = static_cast<std::uint32_t>(data[5]) | (static_cast<std::uint32_t>(data[6]) << 8) |
                 (static_cast<std::uint32_t>(data[7]) << 16);
    } else if (answered == j1939::PGN_REQUEST) {
      return;  // a request is no answer (a request for the Request PGN is not checked)
    }
    for (std::size_t i = 0; i < m_open;) {
      const Open& open = m_requests[i];
      const bool fromAddressee = open.destination == j1939::GLOBAL_ADDRESS || id.sourceAddress == open.destination;
      if (open.bus != frame.bus || open.pgn != answered || !fromAddressee) {
        ++i;
        continue;
      }
      if (ack && ack->control != j1939::AckControl::Positive) {
        static constexpr const char* NAMES[] = {"ACK", "NACK", "access denied", "cannot respond"};
        sink.finding(Finding{frame.timeNs, frame.bus, Severity::Info, Check::Request,
                             describe(open) + ": answered " + NAMES[static_cast<std::size_t>(ack->control)]});
      }
      remove(i);
    }
  }

  void remove(std::size_t index) noexcept { m_requests[index] = m_requests[--m_open]; }

  std::array<Open, MAX_OPEN_REQUESTS> m_requests{};
  std::size_t m_open{};
};

}  // namespace

struct TraceChecker::Impl {
  Impl(const AnalysisSetup& setup, TransportAnalysis::OnMessage onMessage)
      : safety(setup), transport(setup, std::move(onMessage)) {}
  detail::SafetyCheck safety;
  RequestCheck requests;
  TransportAnalysis transport;
  CheckCounts counts;
};

TraceChecker::TraceChecker(const AnalysisSetup& setup, TransportAnalysis::OnMessage onMessage)
    : m_impl(std::make_unique<Impl>(setup, std::move(onMessage))) {}
TraceChecker::TraceChecker(TraceChecker&&) noexcept = default;
TraceChecker& TraceChecker::operator=(TraceChecker&&) noexcept = default;
TraceChecker::~TraceChecker() = default;

void TraceChecker::add(const TraceFrame& frame, FindingSink& sink) {
  CountingSink counting(sink, m_impl->counts);
  m_impl->safety.add(frame, counting);
  m_impl->requests.add(frame, counting, m_impl->counts);
  m_impl->transport.add(frame, counting);
}

void TraceChecker::finish(std::int64_t endNs, FindingSink& sink) {
  CountingSink counting(sink, m_impl->counts);
  m_impl->safety.finish(endNs, counting);
  m_impl->requests.finish(endNs, counting, m_impl->counts);
  m_impl->transport.finish(endNs, counting);
  m_impl->counts.safetyPairs = m_impl->safety.pairsChecked();
  m_impl->counts.safetyFaults = m_impl->safety.faults();
  m_impl->counts.safetyPairsSkipped = m_impl->safety.skipped();
}

const CheckCounts& TraceChecker::counts() const noexcept {
  m_impl->counts.safetyPairs = m_impl->safety.pairsChecked();
  m_impl->counts.safetyFaults = m_impl->safety.faults();
  m_impl->counts.safetyPairsSkipped = m_impl->safety.skipped();
  return m_impl->counts;
}

const TransportAnalysis& TraceChecker::transport() const noexcept {
  return m_impl->transport;
}

std::vector<SafetyPairStats> TraceChecker::safetyPairs() const {
  return m_impl->safety.stats();
}

}  // namespace openvcu::trace
