// STUB (drop at merge): TransportAnalysis is implemented in branch wt-tp
// (shared/trace/src/transport_analysis.cpp). This stand-in follows no session and reports
// nothing, only so that TraceChecker links in branch wt-check until the merge.
#include "openvcu/trace/transport_analysis.hpp"

namespace openvcu::trace {

struct TransportAnalysis::Impl {
  TransportCounts counts;
  std::vector<DtcInterval> dtcIntervals;
};

TransportAnalysis::TransportAnalysis(const AnalysisSetup&, OnMessage) : m_impl(std::make_unique<Impl>()) {}
TransportAnalysis::TransportAnalysis(TransportAnalysis&&) noexcept = default;
TransportAnalysis& TransportAnalysis::operator=(TransportAnalysis&&) noexcept = default;
TransportAnalysis::~TransportAnalysis() = default;
void TransportAnalysis::add(const TraceFrame&, FindingSink&) {}
void TransportAnalysis::finish(std::int64_t, FindingSink&) {}
const TransportCounts& TransportAnalysis::counts() const noexcept { return m_impl->counts; }
const std::vector<DtcInterval>& TransportAnalysis::dtcIntervals() const noexcept { return m_impl->dtcIntervals; }

}  // namespace openvcu::trace
