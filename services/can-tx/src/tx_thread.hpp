#pragma once
// The transmit thread of vcu-can-tx: the only thread that touches the Scheduler and the
// links. It sleeps on a futex with an absolute CLOCK_MONOTONIC deadline (the scheduler's
// next one), so it wakes exactly when a frame is due, or at once when the service's loop
// thread posts something (a one-shot frame, a request to answer, a schedule change).
// The one exception (issue 27): when a J1939-76 SDM is due within the wake guard it does
// not sleep again but stays on the CPU until that deadline (planWait below), so a short
// SHM -> SDM delta does not pay a second wake-up latency. The guard (WakeGuard below) is
// how late this thread's recent timed sleeps woke (p99 + 20 us), at most `sdmSpinNs`.
//
//   cantx::TxThread thread(scheduler, links, onBusEvent);
//   thread.start(priority, sdmSpinNs);                  // SCHED_FIFO when priority > 0
//   thread.post(cantx::SendOnce{bus, frame});           // from the loop thread
//   thread.stop();
//
// The inbox is a single-producer single-consumer ring of TxCommand variants (the loop
// thread produces): no lock, no allocation per command; a full ring refuses the post
// (counted). Commands move through the ring: an AddMessage's PreparedMessage (a unique_ptr)
// is moved into the slot and out again, so the transmit thread neither allocates nor frees
// (Scheduler::add takes the entry; the emptied slot holds a null pointer).

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <thread>
#include <variant>
#include <vector>

#include "openvcu/can/frame.hpp"
#include "openvcu/can/link.hpp"
#include "openvcu/j1939/request.hpp"
#include "network.hpp"
#include "scheduler.hpp"

namespace openvcu::cantx {

/// A frame other processes asked for ("send" stream): Scheduler::sendOnce.
struct SendOnce {
  std::size_t bus{};
  can::Frame frame{};
};
/// A J1939 request for this node ("req" stream): Scheduler::answerRequest.
struct AnswerRequest {
  std::size_t bus{};
  j1939::Request request{};
};
/// A frame of the "net" stream (J1939 claims, TP answers to us): Network::onFrame.
struct NetworkFrame {
  std::size_t bus{};
  can::Frame frame{};
};
/// ScheduleCycle: Scheduler::setCycle (index into Schedule::messages).
struct SetCycle {
  std::size_t scheduled{};
  std::int64_t cycleNs{};
};
/// ScheduleEnable: Scheduler::setEnabled.
struct SetEnabled {
  std::size_t scheduled{};
  bool enabled{};
};
/// ScheduleDefault: Scheduler::setDefault.
struct SetDefault {
  std::size_t scheduled{};
  std::uint32_t signal{};
  double value{};
};
/// ScheduleAdd: a Scheduler::prepare()d message for Scheduler::add.
struct AddMessage {
  PreparedMessage message;
};

using TxCommand = std::variant<SendOnce, AnswerRequest, SetCycle, SetEnabled, SetDefault, AddMessage, NetworkFrame>;
static_assert(std::is_nothrow_move_assignable_v<TxCommand>);

/// How the transmit thread waits for its next deadline (planWait).
struct WaitPlan {
  enum class Kind : std::uint8_t {
    None,   ///< something is due now: run at once
    Sleep,  ///< futex sleep until untilNs (or a post)
    Spin,   ///< stay on the CPU, reading CLOCK_MONOTONIC, until untilNs
  };
  Kind kind{Kind::None};
  std::int64_t untilNs{};
};

/// The transmit thread's choice, free of clocks for tests. `nextNs`: the earliest deadline
/// (Scheduler::nextDeadlineNs, link service); `sdmNs`: the earliest pending SDM's
/// (Scheduler::nextDataDeadlineNs; INT64_MAX none); `spinNs`: the schedule's sdmSpinUs.
///   - nextNs <= nowNs: None;
///   - an SDM due within spinNs of nowNs: Spin until nextNs (which is <= sdmNs), so the
///     spin never lasts longer than spinNs nor than the pair's delta;
///   - else Sleep until nextNs, or until spinNs before the SDM when that is earlier (a pair
///     whose delta is longer than spinNs sleeps once, then spins the last spinNs).
/// @note noexcept, pure.
[[nodiscard]] WaitPlan planWait(std::int64_t nowNs, std::int64_t nextNs, std::int64_t sdmNs,
                                std::int64_t spinNs) noexcept;

/// The wake guard: how long before an SDM the transmit thread stops sleeping and waits on
/// the CPU. A fixed guard has to cover the worst platform the schedule may run on and
/// spends that long on the CPU for every pair; this one follows how late the thread's own
/// timed sleeps woke. Per window of WINDOW sleeps that ended at their deadline: the p99
/// lateness (nearest rank: the eleventh largest of 1,024); the guard is the larger of the
/// last two windows' figures plus MARGIN_NS, at most the cap (sdmSpinUs). So about 99 % of
/// SDMs are waited for on the CPU from before the thread wakes, the rest are late by the
/// platform's tail beyond the guard (the issue 27 target is a delta error p99 <= 50 us).
/// It rises within one window (about 5 s on HHEA) and falls after two. Before the first window it is the
/// cap; a cap of 0 keeps it 0 (never wait on the CPU). Fixed storage, no allocation.
/// @note record() and guardNs() on one thread.
class WakeGuard {
 public:
  static constexpr std::size_t WINDOW = 1024;
  static constexpr std::int64_t MARGIN_NS = 20'000;
  explicit WakeGuard(std::int64_t capNs = 0) noexcept : m_capNs(capNs < 0 ? 0 : capNs), m_guardNs(m_capNs) {}
  /// A timed sleep ended `latenessNs` after its deadline.
  void record(std::int64_t latenessNs) noexcept;
  [[nodiscard]] std::int64_t guardNs() const noexcept { return m_guardNs; }

 private:
  std::int64_t m_capNs;
  std::int64_t m_guardNs;
  std::int64_t m_previousNs{-1};  ///< the previous window's p99; -1 before the first
  std::size_t m_count{};
  std::array<std::int64_t, WINDOW> m_window{};
};

/// Single-producer single-consumer ring of TxCommands.
class TxInbox {
 public:
  static constexpr std::size_t CAPACITY = 1024;
  /// Producer side: moves `command` in. false when full (`command` is left as it was).
  bool push(TxCommand&& command) noexcept;
  /// Consumer side: moves the oldest command into `command`. false when empty.
  bool pop(TxCommand& command) noexcept;

 private:
  std::array<TxCommand, CAPACITY> m_ring{};
  alignas(64) std::atomic<std::uint64_t> m_head{};  ///< next to pop (consumer)
  alignas(64) std::atomic<std::uint64_t> m_tail{};  ///< next to push (producer)
};

/// @note post() from one thread (the service loop); everything else on the owner's thread.
class TxThread {
 public:
  /// `links[bus]` send the scheduler's frames (the caller's port forwards to them); the
  /// thread also services them every 100 ms (reopening, bus events), which it reports
  /// through `onBusEvent` (called on the transmit thread).
  /// `network` (may be null): the J1939 network citizen (network.hpp), started on the
  /// thread; it answers the requests it owns, the scheduler the rest.
  TxThread(Scheduler& scheduler, std::vector<can::Link*> links,
           std::function<void(std::size_t bus, const can::BusEvent&)> onBusEvent, Network* network = nullptr);
  ~TxThread();
  TxThread(const TxThread&) = delete;
  TxThread& operator=(const TxThread&) = delete;

  /// Starts the thread; `realtimePriority` > 0 asks for SCHED_FIFO. `sdmSpinNs` (>= 0): the
  /// wake guard's cap; an SDM due within the guard is waited for on the CPU (planWait). Returns a warning text when
  /// SCHED_FIFO was refused (the thread then runs with normal scheduling), else empty.
  std::string start(int realtimePriority, std::int64_t sdmSpinNs = 0);
  /// Stops and joins the thread (idempotent).
  void stop() noexcept;

  /// Queues a command (moved in) and wakes the thread. false when the inbox is full
  /// (counted; `command` is left with the caller).
  bool post(TxCommand&& command) noexcept;
  [[nodiscard]] std::uint64_t refusedPosts() const noexcept { return m_refused.load(std::memory_order_relaxed); }
  /// Wake-ups of the thread from its futex sleep (deadlines and posts), for the heartbeat.
  [[nodiscard]] std::uint64_t wakeups() const noexcept { return m_wakeups.load(std::memory_order_relaxed); }
  /// Waits on the CPU for an SDM (planWait's Spin) and their total time, for the heartbeat.
  [[nodiscard]] std::uint64_t spins() const noexcept { return m_spins.load(std::memory_order_relaxed); }
  [[nodiscard]] std::int64_t spinNs() const noexcept { return m_spinTotalNs.load(std::memory_order_relaxed); }
  /// The wake guard now (WakeGuard), for the heartbeat.
  [[nodiscard]] std::int64_t guardNs() const noexcept { return m_guardNs.load(std::memory_order_relaxed); }

 private:
  void run() noexcept;
  void apply(TxCommand& command, std::int64_t nowNs) noexcept;
  void service(std::int64_t nowNs) noexcept;
  void spinUntil(std::int64_t deadlineNs) noexcept;

  Scheduler& m_scheduler;
  Network* m_network{};
  std::vector<can::Link*> m_links;
  std::function<void(std::size_t, const can::BusEvent&)> m_onBusEvent;
  TxInbox m_inbox;
  std::atomic<std::uint32_t> m_wake{};   ///< the futex word: bumped by every post and by stop()
  std::atomic<bool> m_sleeping{};
  std::atomic<bool> m_stopping{};
  std::atomic<std::uint64_t> m_refused{};
  std::atomic<std::uint64_t> m_wakeups{};
  std::atomic<std::uint64_t> m_spins{};
  std::atomic<std::int64_t> m_spinTotalNs{};
  WakeGuard m_guard;                     ///< set before the thread starts; then the thread's own
  std::atomic<std::int64_t> m_guardNs{};  ///< m_guard's figure for other threads
  std::atomic<bool> m_realtime{};        ///< SCHED_FIFO granted: the spin yields to its peers
  std::int64_t m_nextServiceNs{};
  std::array<can::ReceivedFrame, 16> m_scratch{};
  std::thread m_thread;
};

}  // namespace openvcu::cantx
