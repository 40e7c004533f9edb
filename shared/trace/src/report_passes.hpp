#pragma once
// The parts of makeReport() (report_job.cpp) beside the first pass: the frame budget every
// pass keeps (ReportJob::maxFrames, ReportJob::cancel), the chosen signals' second pass and
// the event lanes of an events.lcmlog.

#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

#include "openvcu/core/error.hpp"
#include "openvcu/trace/html_report.hpp"
#include "openvcu/trace/log.hpp"
#include "openvcu/trace/report_job.hpp"

namespace openvcu::trace::detail {

/// Counts the frames of one pass against ReportJob::maxFrames and looks at
/// ReportJob::cancel every CANCEL_POLL_FRAMES frames.
class FrameBudget {
 public:
  explicit FrameBudget(const ReportJob& job) noexcept : m_maxFrames(job.maxFrames), m_cancel(job.cancel) {}

  /// True when one more frame may be read; false once the limit is reached or cancel was seen.
  [[nodiscard]] bool allowsAnother() noexcept {
    if (m_maxFrames != 0 && m_frames >= m_maxFrames) return false;
    if (m_cancel != nullptr && m_frames % CANCEL_POLL_FRAMES == 0 && m_cancel->load(std::memory_order_relaxed)) {
      m_cancelled = true;
      return false;
    }
    ++m_frames;
    return true;
  }
  [[nodiscard]] bool cancelled() const noexcept { return m_cancelled; }
  [[nodiscard]] bool limitReached() const noexcept { return m_maxFrames != 0 && m_frames >= m_maxFrames; }

 private:
  std::uint64_t m_maxFrames;
  const std::atomic<bool>* m_cancel;
  std::uint64_t m_frames{};
  bool m_cancelled{};
};

/// The Error a cancelled job returns.
[[nodiscard]] Error cancelledError();

/// The signals of `names` in `database`: "MESSAGE.SIGNAL" or the table key
/// "NODE.MESSAGE.SIGNAL". An unknown name becomes an Error in `errors` and is left out.
[[nodiscard]] std::vector<SignalRef> resolveSignals(const dbc::Database& database,
                                                    const std::vector<std::string>& names, std::vector<Error>& errors);

/// The second pass over `logs`: every signal of `refs` as min/max buckets (SIGNAL_BUCKETS)
/// over [0, durationS] seconds from `startNs`. Fails when a log cannot be opened again or
/// the job was cancelled.
[[nodiscard]] Result<std::vector<SignalSeries>> extractSignalSeries(const ReportJob& job,
                                                                    const std::vector<std::string>& logs,
                                                                    const std::vector<SignalRef>& refs,
                                                                    std::int64_t startNs, double durationS);

/// The "FSM state" and "Faults" lanes of the events log at `path`, seconds from `startNs`.
/// A log that cannot be read gives no lane and an Error in `errors`; events that did not
/// decode or were over the limit give a Warning.
[[nodiscard]] std::vector<EventLane> recordedEventLanes(const std::string& path, std::int64_t startNs,
                                                        std::vector<Error>& errors);

}  // namespace openvcu::trace::detail
