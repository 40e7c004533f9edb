#include "tx_thread.hpp"

#include <linux/futex.h>
#include <pthread.h>
#include <sched.h>
#include <sys/prctl.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cstring>
#include <ctime>
#include <type_traits>
#include "openvcu/core/clock.hpp"

namespace openvcu::cantx {
namespace {

constexpr std::int64_t SERVICE_PERIOD_NS = 100'000'000;  ///< link housekeeping every 100 ms

/// Sleeps while *word == expected, at most until the absolute CLOCK_MONOTONIC `deadlineNs`.
void futexWaitUntil(std::atomic<std::uint32_t>& word, std::uint32_t expected, std::int64_t deadlineNs) noexcept {
  timespec deadline{};
  deadline.tv_sec = static_cast<time_t>(deadlineNs / 1'000'000'000);
  deadline.tv_nsec = static_cast<long>(deadlineNs % 1'000'000'000);
  // FUTEX_WAIT_BITSET takes an absolute timeout (CLOCK_MONOTONIC without FUTEX_CLOCK_REALTIME).
  ::syscall(SYS_futex, reinterpret_cast<std::uint32_t*>(&word), FUTEX_WAIT_BITSET_PRIVATE, expected,
            deadlineNs == INT64_MAX ? nullptr : &deadline, nullptr, FUTEX_BITSET_MATCH_ANY);
}

void futexWake(std::atomic<std::uint32_t>& word) noexcept {
  ::syscall(SYS_futex, reinterpret_cast<std::uint32_t*>(&word), FUTEX_WAKE_PRIVATE, 1, nullptr, nullptr, 0);
}

/// The CPU's spin-wait hint between two clock reads (less power, no memory-order stall).
inline void cpuRelax() noexcept {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#elif defined(__aarch64__) || defined(__arm__)
  asm volatile("yield" ::: "memory");
#endif
}

}  // namespace

WaitPlan planWait(std::int64_t nowNs, std::int64_t nextNs, std::int64_t sdmNs, std::int64_t spinNs) noexcept {
  if (nextNs <= nowNs) return {WaitPlan::Kind::None, nowNs};
  if (sdmNs == INT64_MAX || spinNs <= 0) return {WaitPlan::Kind::Sleep, nextNs};
  if (sdmNs - nowNs <= spinNs) return {WaitPlan::Kind::Spin, std::min(nextNs, sdmNs)};
  return {WaitPlan::Kind::Sleep, std::min(nextNs, sdmNs - spinNs)};
}

void WakeGuard::record(std::int64_t latenessNs) noexcept {
  if (m_capNs == 0) return;
  m_window[m_count++] = latenessNs < 0 ? 0 : latenessNs;
  if (m_count < WINDOW) return;
  m_count = 0;
  // nearest-rank p99 of 1,024: rank 1,014 (the eleventh largest)
  constexpr std::size_t RANK = (WINDOW * 99 + 99) / 100 - 1;
  std::nth_element(m_window.begin(), m_window.begin() + RANK, m_window.end());
  const std::int64_t p99 = m_window[RANK];
  m_guardNs = std::min(m_capNs, std::max(p99, m_previousNs) + MARGIN_NS);
  m_previousNs = p99;
}

bool TxInbox::push(TxCommand&& command) noexcept {
  const std::uint64_t tail = m_tail.load(std::memory_order_relaxed);
  if (tail - m_head.load(std::memory_order_acquire) >= CAPACITY) return false;
  m_ring[tail % CAPACITY] = std::move(command);
  m_tail.store(tail + 1, std::memory_order_release);
  return true;
}

bool TxInbox::pop(TxCommand& command) noexcept {
  const std::uint64_t head = m_head.load(std::memory_order_relaxed);
  if (head == m_tail.load(std::memory_order_acquire)) return false;
  command = std::move(m_ring[head % CAPACITY]);
  m_head.store(head + 1, std::memory_order_release);
  return true;
}

TxThread::TxThread(Scheduler& scheduler, std::vector<can::Link*> links,
                   std::function<void(std::size_t, const can::BusEvent&)> onBusEvent, Network* network)
    : m_scheduler(scheduler), m_network(network), m_links(std::move(links)), m_onBusEvent(std::move(onBusEvent)) {}

TxThread::~TxThread() { stop(); }

std::string TxThread::start(int realtimePriority, std::int64_t sdmSpinNs) {
  m_guard = WakeGuard(sdmSpinNs);
  m_guardNs.store(m_guard.guardNs(), std::memory_order_relaxed);
  m_thread = std::thread([this] { run(); });
  if (realtimePriority <= 0) return {};
  sched_param parameters{};
  parameters.sched_priority = realtimePriority;
  const int error = ::pthread_setschedparam(m_thread.native_handle(), SCHED_FIFO, &parameters);
  if (error == 0) {
    m_realtime.store(true, std::memory_order_relaxed);
    return {};
  }
  return "realtimePriority " + std::to_string(realtimePriority) + ": SCHED_FIFO refused (" + std::strerror(error) +
         "); the transmit thread runs with normal scheduling";
}

void TxThread::stop() noexcept {
  if (!m_thread.joinable()) return;
  m_stopping.store(true, std::memory_order_release);
  m_wake.fetch_add(1, std::memory_order_release);
  futexWake(m_wake);
  m_thread.join();
  TxCommand left;
  while (m_inbox.pop(left)) {
  }  // never applied: an AddMessage's entry is freed with `left`
}

bool TxThread::post(TxCommand&& command) noexcept {
  if (!m_inbox.push(std::move(command))) {
    m_refused.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  m_wake.fetch_add(1, std::memory_order_seq_cst);
  if (m_sleeping.load(std::memory_order_seq_cst)) futexWake(m_wake);
  return true;
}

void TxThread::apply(TxCommand& command, std::int64_t nowNs) noexcept {
  std::visit(
      [&](auto& change) noexcept {
        using Change = std::decay_t<decltype(change)>;
        if constexpr (std::is_same_v<Change, SendOnce>) {
          m_scheduler.sendOnce(change.bus, change.frame);
        } else if constexpr (std::is_same_v<Change, AnswerRequest>) {
          if (m_network == nullptr || !m_network->answerRequest(change.bus, change.request, nowNs)) {
            m_scheduler.answerRequest(change.bus, change.request);
          }
        } else if constexpr (std::is_same_v<Change, NetworkFrame>) {
          if (m_network != nullptr) m_network->onFrame(change.bus, change.frame, nowNs);
        } else if constexpr (std::is_same_v<Change, SetCycle>) {
          m_scheduler.setCycle(change.scheduled, change.cycleNs, nowNs);
        } else if constexpr (std::is_same_v<Change, SetEnabled>) {
          m_scheduler.setEnabled(change.scheduled, change.enabled);
        } else if constexpr (std::is_same_v<Change, SetDefault>) {
          m_scheduler.setDefault(change.scheduled, change.signal, change.value);
        } else {
          static_assert(std::is_same_v<Change, AddMessage>);
          // the poster checked the room (Scheduler::capacity); a refusal would leave its
          // heartbeat counters pointing at freed statistics, so the entry is then kept alive
          if (!m_scheduler.add(change.message, nowNs)) (void)change.message.release();
        }
      },
      command);
}

void TxThread::service(std::int64_t nowNs) noexcept {
  m_nextServiceNs = nowNs + SERVICE_PERIOD_NS;
  for (std::size_t bus = 0; bus < m_links.size(); ++bus) {
    while (m_links[bus]->receive(m_scratch) == m_scratch.size()) {
    }
    while (const auto maybeEvent = m_links[bus]->nextEvent()) {
      if (m_onBusEvent) m_onBusEvent(bus, *maybeEvent);
    }
  }
}

void TxThread::spinUntil(std::int64_t deadlineNs) noexcept {
  // Bounded by planWait: at most the wake guard (so at most sdmSpinNs) and the pair's delta.
  // Under SCHED_FIFO a sched_yield() between clock reads lets a thread of the same priority
  // on this core run (it would otherwise wait for the whole spin); else the CPU's pause hint.
  const std::int64_t beginNs = clock::monotonicNs();
  std::int64_t now = beginNs;
  const bool yield = m_realtime.load(std::memory_order_relaxed);
  while (now < deadlineNs && !m_stopping.load(std::memory_order_relaxed)) {
    if (yield) {
      ::sched_yield();
    } else {
      cpuRelax();
    }
    now = clock::monotonicNs();
  }
  m_spins.fetch_add(1, std::memory_order_relaxed);
  m_spinTotalNs.fetch_add(now - beginNs, std::memory_order_relaxed);
}

void TxThread::run() noexcept {
  // The timer slack of a normal thread (50 us) would land in every period: ask for 1 ns.
  ::prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL);
  m_nextServiceNs = clock::monotonicNs();
  if (m_network != nullptr) m_network->start(m_nextServiceNs);  // the claims before the first scheduled frame
  while (!m_stopping.load(std::memory_order_acquire)) {
    const std::uint32_t seen = m_wake.load(std::memory_order_acquire);
    std::int64_t now = clock::monotonicNs();
    if (m_network != nullptr) m_network->setNow(now);
    TxCommand command;
    while (m_inbox.pop(command)) apply(command, now);
    m_scheduler.run(now);
    if (m_network != nullptr) m_network->run(now);
    now = clock::monotonicNs();
    const std::int64_t sdmNs = m_scheduler.nextDataDeadlineNs();
    // the link housekeeping (draining the links' receive queues, their events) waits while an
    // SDM is due within the wake guard, so that it cannot delay that SDM; it runs right after it
    const std::int64_t guardNs = m_guard.guardNs();
    const bool sdmSoon = sdmNs != INT64_MAX && sdmNs - now <= guardNs;
    if (now >= m_nextServiceNs && !sdmSoon) service(now);
    const std::int64_t serviceNs = sdmSoon ? INT64_MAX : m_nextServiceNs;
    const std::int64_t networkNs = m_network != nullptr ? m_network->nextDeadlineNs() : INT64_MAX;
    const WaitPlan plan = planWait(clock::monotonicNs(), std::min({m_scheduler.nextDeadlineNs(), serviceNs, networkNs}),
                                   sdmNs, guardNs);
    if (plan.kind == WaitPlan::Kind::Sleep) {
      m_sleeping.store(true, std::memory_order_seq_cst);
      // a post between the load of `seen` and here changed the word: the wait returns at once
      futexWaitUntil(m_wake, seen, plan.untilNs);
      m_sleeping.store(false, std::memory_order_relaxed);
      m_wakeups.fetch_add(1, std::memory_order_relaxed);
      // how late a sleep that ran to its deadline woke (one woken early by a post says nothing)
      if (const std::int64_t woke = clock::monotonicNs(); woke >= plan.untilNs) {
        m_guard.record(woke - plan.untilNs);
        m_guardNs.store(m_guard.guardNs(), std::memory_order_relaxed);
      }
    } else if (plan.kind == WaitPlan::Kind::Spin) {
      spinUntil(plan.untilNs);
    }
  }
}

}  // namespace openvcu::cantx
