#include "fault_guard.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <new>

#include "layout.hpp"
#include "openvcu/signals/catalog.hpp"

namespace openvcu::signals::detail {

namespace {

constexpr int GENERATION_ATTEMPTS = 8;
constexpr std::uint64_t NS_PER_SECOND = 1'000'000'000;

std::array<GuardEntry, MAX_GUARDED_MAPPINGS> g_entries;
std::atomic<bool> g_installing{false};
struct sigaction g_previous {};
std::uintptr_t g_pageBytes = 4096;  // set before the handler is installed
std::atomic<std::uint64_t> g_generationCounter{0};

TableHeader* headerOf(const GuardEntry& entry) noexcept {
  return std::launder(reinterpret_cast<TableHeader*>(entry.begin.load(std::memory_order_acquire)));
}

template <typename T>
T loadField(T& field) noexcept {
  return std::atomic_ref<T>(field).load(std::memory_order_relaxed);
}

template <typename T>
void storeField(T& field, T value) noexcept {
  std::atomic_ref<T>(field).store(value, std::memory_order_relaxed);
}

bool headerIntact(const GuardEntry& entry, TableHeader& header) noexcept {
  return header.magic.load(std::memory_order_acquire) == TABLE_MAGIC &&
         loadField(header.formatVersion) == SIGNAL_TABLE_FORMAT_VERSION &&
         loadField(header.headerBytes) == sizeof(TableHeader) &&
         loadField(header.layoutHash) == entry.layoutHash.load(std::memory_order_relaxed) &&
         loadField(header.slotCount) == entry.slotCount.load(std::memory_order_relaxed) &&
         loadField(header.slotBytes) == sizeof(Slot);
}

/// Writes the creator's fields again (the same values every attached process holds).
void rewriteHeaderFields(const GuardEntry& entry, TableHeader& header) noexcept {
  timespec now{};
  clock_gettime(CLOCK_REALTIME, &now);
  storeField(header.formatVersion, SIGNAL_TABLE_FORMAT_VERSION);
  storeField(header.headerBytes, static_cast<std::uint32_t>(sizeof(TableHeader)));
  storeField(header.layoutHash, entry.layoutHash.load(std::memory_order_relaxed));
  storeField(header.slotCount, entry.slotCount.load(std::memory_order_relaxed));
  storeField(header.slotBytes, static_cast<std::uint32_t>(sizeof(Slot)));
  storeField(header.createdRealtimeNs, static_cast<std::int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec);
  storeField(header.creatorPid, static_cast<std::int32_t>(getpid()));
}

/// Gives the table a new generation unless another process already did since this process
/// last accepted one; either way this process accepts the result.
void renewGeneration(GuardEntry& entry, TableHeader& header) noexcept {
  std::atomic_ref<std::uint64_t> generation(header.generation);
  const std::uint64_t accepted = entry.generation.load(std::memory_order_relaxed);
  for (int attempt = 0; attempt < GENERATION_ATTEMPTS; ++attempt) {
    std::uint64_t seen = generation.load(std::memory_order_acquire);
    if (seen != 0 && seen != accepted) {  // renewed by another process already
      entry.generation.store(seen, std::memory_order_relaxed);
      return;
    }
    const std::uint64_t fresh = freshGeneration();
    if (generation.compare_exchange_strong(seen, fresh, std::memory_order_acq_rel)) {
      entry.generation.store(fresh, std::memory_order_relaxed);
      return;
    }
  }
}

/// Restores a table's header after its pages were lost or overwritten. True when it wrote.
bool restoreHeader(GuardEntry& entry, TableHeader& header, bool renew) noexcept {
  const bool lost = !headerIntact(entry, header);
  if (lost) rewriteHeaderFields(entry, header);
  if (lost || renew) renewGeneration(entry, header);
  if (lost) {
    header.magic.store(TABLE_MAGIC, std::memory_order_release);
    entry.events.fetch_or(EVENT_HEADER_RESTORED, std::memory_order_relaxed);
  }
  return lost;
}

GuardEntry* entryFor(std::uintptr_t address) noexcept {
  for (GuardEntry& entry : g_entries) {
    const std::uintptr_t begin = entry.begin.load(std::memory_order_acquire);
    if (begin != 0 && address >= begin && address - begin < entry.bytes.load(std::memory_order_relaxed)) {
      return &entry;
    }
  }
  return nullptr;
}

/// The handler's decision for a fault in `entry`: true when the access may be retried.
bool absorbFault(GuardEntry& entry, std::uintptr_t address) noexcept {
  const std::uintptr_t page = address & ~(g_pageBytes - 1);
  entry.faults.fetch_add(1, std::memory_order_relaxed);
  entry.damage.fetch_add(1, std::memory_order_relaxed);
  if (restoreSize(entry)) {
    entry.lastFaultPage.store(page, std::memory_order_relaxed);
    return true;
  }
  // The size is right: another process restored it a moment ago (the retry succeeds), or the
  // page cannot be had (tmpfs full). Retry once; the same page again gets a private zero page.
  if (entry.lastFaultPage.exchange(page, std::memory_order_relaxed) != page) return true;
  void* mapped = mmap(reinterpret_cast<void*>(page), g_pageBytes, PROT_READ | PROT_WRITE,
                      MAP_PRIVATE | MAP_ANONYMOUS | MAP_FIXED, -1, 0);
  if (mapped == MAP_FAILED) return false;
  entry.detached.store(true, std::memory_order_release);
  entry.events.fetch_or(EVENT_PRIVATE_PAGES, std::memory_order_relaxed);
  entry.lastFaultPage.store(0, std::memory_order_relaxed);
  return true;
}

void onSigbus(int signal, siginfo_t* info, void* context) {
  const int savedErrno = errno;
  GuardEntry* entry = info != nullptr ? entryFor(reinterpret_cast<std::uintptr_t>(info->si_addr)) : nullptr;
  if (entry != nullptr && absorbFault(*entry, reinterpret_cast<std::uintptr_t>(info->si_addr))) {
    errno = savedErrno;
    return;  // the faulting access runs again and now succeeds
  }
  errno = savedErrno;
  // Not ours (or not recoverable): what would have happened without us.
  if ((g_previous.sa_flags & SA_SIGINFO) != 0 && g_previous.sa_sigaction != nullptr) {
    g_previous.sa_sigaction(signal, info, context);
    return;
  }
  if (g_previous.sa_handler != SIG_DFL && g_previous.sa_handler != SIG_IGN) {
    g_previous.sa_handler(signal);
    return;
  }
  // Default action: restore it and return; the access faults again and the kernel ends the
  // process with SIGBUS as it would have without this handler.
  struct sigaction fallback {};
  fallback.sa_handler = SIG_DFL;
  sigemptyset(&fallback.sa_mask);
  sigaction(SIGBUS, &fallback, nullptr);
}

/// Installs onSigbus unless it is the current SIGBUS action. Checked at every guardMapping()
/// (start-up only), not once per process: a library that installed its own SIGBUS action
/// since (test frameworks do, per test case) is then chained behind ours again.
bool installHandler() noexcept {
  bool expected = false;
  while (!g_installing.compare_exchange_weak(expected, true, std::memory_order_acquire)) {
    expected = false;
    sched_yield();  // another thread is installing it right now (two system calls)
  }
  struct sigaction current {};
  bool installed = sigaction(SIGBUS, nullptr, &current) == 0;
  if (installed && !((current.sa_flags & SA_SIGINFO) != 0 && current.sa_sigaction == onSigbus)) {
    const long pageBytes = sysconf(_SC_PAGESIZE);
    if (pageBytes > 0) g_pageBytes = static_cast<std::uintptr_t>(pageBytes);
    struct sigaction action {};
    action.sa_sigaction = onSigbus;
    sigemptyset(&action.sa_mask);
    // SA_NODEFER: a fault inside the handler (the segment truncated again meanwhile) is
    // handled too instead of killing the process.
    action.sa_flags = SA_SIGINFO | SA_NODEFER | SA_ONSTACK | SA_RESTART;
    installed = sigaction(SIGBUS, &action, &g_previous) == 0;
  }
  g_installing.store(false, std::memory_order_release);
  return installed;
}

}  // namespace

std::uint64_t freshGeneration() noexcept {
  timespec now{};
  clock_gettime(CLOCK_REALTIME, &now);
  const std::uint64_t time = static_cast<std::uint64_t>(now.tv_sec) * NS_PER_SECOND + static_cast<std::uint64_t>(now.tv_nsec);
  const auto pid = static_cast<std::uint64_t>(getpid());
  const std::uint64_t count = g_generationCounter.fetch_add(1, std::memory_order_relaxed);
  return (time ^ (pid << 40) ^ (count << 20)) | 1u;  // never 0 (0: "tables of older builds")
}

GuardEntry* guardMapping(void* base, std::size_t bytes, int fd, const GuardedHeader* header) noexcept {
  if (!installHandler()) return nullptr;
  for (GuardEntry& entry : g_entries) {
    std::uintptr_t expected = 0;
    // Claim with a non-zero placeholder so the handler ignores the entry until it is filled.
    if (!entry.begin.compare_exchange_strong(expected, 1, std::memory_order_acq_rel)) continue;
    entry.bytes.store(bytes, std::memory_order_relaxed);
    entry.fd.store(fd, std::memory_order_relaxed);
    entry.table.store(header != nullptr, std::memory_order_relaxed);
    entry.layoutHash.store(header != nullptr ? header->layoutHash : 0, std::memory_order_relaxed);
    entry.slotCount.store(header != nullptr ? header->slotCount : 0, std::memory_order_relaxed);
    entry.generation.store(header != nullptr ? header->generation : 0, std::memory_order_relaxed);
    entry.damage.store(0, std::memory_order_relaxed);
    entry.reported.store(0, std::memory_order_relaxed);
    entry.faults.store(0, std::memory_order_relaxed);
    entry.foundBytes.store(-1, std::memory_order_relaxed);
    entry.events.store(0, std::memory_order_relaxed);
    entry.detached.store(false, std::memory_order_relaxed);
    entry.lastFaultPage.store(0, std::memory_order_relaxed);
    entry.begin.store(reinterpret_cast<std::uintptr_t>(base), std::memory_order_release);
    return &entry;
  }
  return nullptr;
}

void unguardMapping(GuardEntry* entry) noexcept {
  if (entry == nullptr) return;
  entry->fd.store(-1, std::memory_order_relaxed);
  entry->begin.store(0, std::memory_order_release);
}

bool checkHeader(GuardEntry& entry) noexcept {
  if (!entry.table.load(std::memory_order_relaxed)) return false;
  TableHeader& header = *headerOf(entry);
  if (restoreHeader(entry, header, false)) {
    entry.damage.fetch_add(1, std::memory_order_relaxed);
    return true;
  }
  const std::uint64_t seen = std::atomic_ref<std::uint64_t>(header.generation).load(std::memory_order_acquire);
  if (seen == entry.generation.load(std::memory_order_relaxed)) return false;
  entry.generation.store(seen, std::memory_order_relaxed);
  entry.events.fetch_or(EVENT_RESTORED_ELSEWHERE, std::memory_order_relaxed);
  entry.damage.fetch_add(1, std::memory_order_relaxed);
  return true;
}

bool restoreSize(GuardEntry& entry) noexcept {
  const int fd = entry.fd.load(std::memory_order_relaxed);
  const std::size_t bytes = entry.bytes.load(std::memory_order_relaxed);
  struct stat status {};
  if (fd < 0 || fstat(fd, &status) != 0 || static_cast<std::size_t>(status.st_size) >= bytes) return false;
  if (ftruncate(fd, static_cast<off_t>(bytes)) != 0) return false;
  // Reserve the pages again (as creation does); without them a later access could still fault.
  (void)fallocate(fd, 0, 0, static_cast<off_t>(bytes));
  entry.foundBytes.store(status.st_size, std::memory_order_relaxed);
  entry.events.fetch_or(EVENT_SIZE_RESTORED, std::memory_order_relaxed);
  entry.damage.fetch_add(1, std::memory_order_relaxed);
  // The header page may be among the lost ones; the values certainly are.
  if (entry.table.load(std::memory_order_relaxed)) (void)restoreHeader(entry, *headerOf(entry), true);
  return true;
}

bool reattach(GuardEntry& entry) noexcept {
  if (!entry.detached.exchange(false, std::memory_order_acq_rel)) return false;
  const int fd = entry.fd.load(std::memory_order_relaxed);
  void* base = reinterpret_cast<void*>(entry.begin.load(std::memory_order_acquire));
  const std::size_t bytes = entry.bytes.load(std::memory_order_relaxed);
  if (fd < 0 || mmap(base, bytes, PROT_READ | PROT_WRITE, MAP_SHARED | MAP_FIXED, fd, 0) == MAP_FAILED) {
    entry.detached.store(true, std::memory_order_release);  // try again at the next check
    return false;
  }
  return true;
}

}  // namespace openvcu::signals::detail
