// The simulated chip: input lines are the keys "internal.gpio.sim.<line>" of the signal
// table (their electrical level: an override, else the command, else the bus plane, else the
// bias: pull-up 1, anything else 0); outputs are held in memory (vcu-gpio reports them).
// tableChanged() turns level changes into events behind an eventfd, so the caller waits for
// the sim chip exactly as for the kernel's line-event descriptors.

#include <sys/eventfd.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstring>
#include <mutex>

#include "chip.hpp"
#include "openvcu/core/clock.hpp"

namespace openvcu::gpio {
namespace {

class SimChip final : public Chip {
 public:
  SimChip(const config::GpioMap& map, signals::SignalTable& table, std::vector<std::optional<signals::SignalIndex>> keys,
          int eventFd)
      : m_map(map), m_table(table), m_keys(std::move(keys)), m_levels(map.lines.size(), false), m_eventFd(eventFd) {}
  ~SimChip() override { ::close(m_eventFd); }
  SimChip(const SimChip&) = delete;
  SimChip& operator=(const SimChip&) = delete;

  Status request(std::span<const bool> levels) override {
    std::lock_guard lock(m_mutex);
    for (std::size_t i = 0; i < m_map.lines.size(); ++i) {
      m_levels[i] = isInput(i) ? logicalInput(i) : (i < levels.size() && levels[i]);
    }
    m_requested = true;
    return {};
  }

  Status set(std::size_t line, bool level) override {
    if (line >= m_levels.size() || isInput(line)) return Error{"line " + std::to_string(line) + " is not an output"};
    std::lock_guard lock(m_mutex);
    m_levels[line] = level;
    return {};
  }

  Result<bool> get(std::size_t line) override {
    if (line >= m_levels.size()) return Error{"no line " + std::to_string(line)};
    std::lock_guard lock(m_mutex);
    return static_cast<bool>(m_levels[line]);
  }

  [[nodiscard]] std::vector<int> eventFds() const override { return {m_eventFd}; }

  std::size_t readEvents(int fd, std::span<LineEvent> out) override {
    if (fd != m_eventFd) return 0;
    std::uint64_t signalled = 0;
    (void)::read(m_eventFd, &signalled, sizeof signalled);  // non-blocking; resets the count
    std::lock_guard lock(m_mutex);
    std::size_t count = 0;
    while (count < out.size() && m_head != m_tail) {
      out[count++] = m_queue[m_tail % m_queue.size()];
      ++m_tail;
    }
    if (m_head != m_tail) signal();  // more than fitted: readable again
    return count;
  }

  void tableChanged() override {
    std::lock_guard lock(m_mutex);
    if (!m_requested) return;
    bool any = false;
    for (std::size_t i = 0; i < m_map.lines.size(); ++i) {
      if (!isInput(i)) continue;
      const bool level = logicalInput(i);
      if (level == static_cast<bool>(m_levels[i])) continue;
      m_levels[i] = level;
      if (m_head - m_tail == m_queue.size()) ++m_tail;  // full: the oldest edge goes (counted by the caller as a gap)
      m_queue[m_head % m_queue.size()] = LineEvent{i, level, clock::monotonicNs()};
      ++m_head;
      any = true;
    }
    if (any) signal();
  }

  void release() noexcept override {
    std::lock_guard lock(m_mutex);
    m_requested = false;
  }

  [[nodiscard]] std::string_view kind() const noexcept override { return "sim"; }

 private:
  [[nodiscard]] bool isInput(std::size_t line) const noexcept {
    return m_map.lines[line].direction == config::LineDirection::Input;
  }

  /// The electrical level of an input from its key, as logical level.
  [[nodiscard]] bool logicalInput(std::size_t line) const noexcept {
    const config::GpioLine& spec = m_map.lines[line];
    bool electrical = spec.bias == config::LineBias::PullUp;
    if (m_keys[line]) {
      if (const auto snapshot = m_table.read(*m_keys[line])) {
        if (const auto command = signals::effectiveCommand(*snapshot)) {
          electrical = command->value >= 0.5;
        } else if (snapshot->bus.updates > 0) {
          electrical = snapshot->bus.value >= 0.5;
        }
      }
    }
    return electrical != spec.activeLow;
  }

  void signal() noexcept {
    const std::uint64_t one = 1;
    (void)::write(m_eventFd, &one, sizeof one);
  }

  const config::GpioMap& m_map;
  signals::SignalTable& m_table;
  std::vector<std::optional<signals::SignalIndex>> m_keys;  // sim key per line (inputs)
  std::mutex m_mutex;
  std::vector<char> m_levels;  // logical level per line
  std::array<LineEvent, 256> m_queue{};
  std::size_t m_head{};
  std::size_t m_tail{};
  bool m_requested{false};
  int m_eventFd;
};

}  // namespace

Result<std::unique_ptr<Chip>> openSimChip(const config::GpioMap& map, signals::SignalTable& table,
                                          const signals::Catalog& catalog) {
  std::vector<std::optional<signals::SignalIndex>> keys(map.lines.size());
  for (std::size_t i = 0; i < map.lines.size(); ++i) {
    if (map.lines[i].direction != config::LineDirection::Input) continue;
    keys[i] = catalog.indexOf(map.lines[i].simKey());
    if (!keys[i]) return Error{"the catalog has no key " + map.lines[i].simKey() + " (configuration mismatch)"};
  }
  const int fd = ::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
  if (fd < 0) return Error{std::string("eventfd: ") + std::strerror(errno)};
  return std::unique_ptr<Chip>(new SimChip(map, table, std::move(keys), fd));
}

Result<std::unique_ptr<Chip>> openChip(const config::GpioMap& map, signals::SignalTable& table,
                                       const signals::Catalog& catalog) {
  if (map.backend == config::GpioBackend::Sim) return openSimChip(map, table, catalog);
  return openGpiodChip(map);
}

}  // namespace openvcu::gpio
