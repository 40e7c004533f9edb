// The libgpiod v1 back end (Debian 12: libgpiod 1.6.3). Chips open by name ("gpiochip0"),
// path ("/dev/gpiochip0") or label; lines by offset or by name. Each line is requested once
// with its direction, active-low and bias flags (outputs at their start level, inputs with
// both-edge events on a non-blocking descriptor) and held until release(). Built only when
// CMake finds libgpiod (OPENVCU_HAVE_GPIOD); otherwise openGpiodChip says so.

#include "chip.hpp"

#if OPENVCU_HAVE_GPIOD

#include <fcntl.h>
#include <gpiod.h>
#include <poll.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>
#include <ctime>
#include "openvcu/core/clock.hpp"

namespace openvcu::gpio {
namespace {

constexpr const char* CONSUMER = "vcu-gpio";
/// An event stamp further than this from CLOCK_MONOTONIC now is not trusted (kernels before
/// 5.7 stamped v1 line events with CLOCK_REALTIME): the read time is used instead.
constexpr std::int64_t STAMP_TRUST_NS = 1'000'000'000;

std::string lastError() { return std::strerror(errno); }

int requestFlags(const config::GpioLine& line) {
  int flags = line.activeLow ? GPIOD_LINE_REQUEST_FLAG_ACTIVE_LOW : 0;
  switch (line.bias) {
    case config::LineBias::AsIs: break;
    case config::LineBias::Disabled: flags |= GPIOD_LINE_REQUEST_FLAG_BIAS_DISABLE; break;
    case config::LineBias::PullUp: flags |= GPIOD_LINE_REQUEST_FLAG_BIAS_PULL_UP; break;
    case config::LineBias::PullDown: flags |= GPIOD_LINE_REQUEST_FLAG_BIAS_PULL_DOWN; break;
  }
  return flags;
}

class GpiodChip final : public Chip {
 public:
  GpiodChip(const config::GpioMap& map, std::vector<gpiod_chip*> chips)
      : m_map(map), m_chips(std::move(chips)), m_lines(map.lines.size(), nullptr) {}
  ~GpiodChip() override {
    release();
    for (gpiod_chip* chip : m_chips) gpiod_chip_close(chip);
  }
  GpiodChip(const GpiodChip&) = delete;
  GpiodChip& operator=(const GpiodChip&) = delete;

  Status request(std::span<const bool> levels) override {
    for (std::size_t i = 0; i < m_map.lines.size(); ++i) {
      const config::GpioLine& spec = m_map.lines[i];
      const config::GpioChip& chipSpec = m_map.chips[spec.chip];
      gpiod_chip* chip = m_chips[spec.chip];
      gpiod_line* line = spec.offset ? gpiod_chip_get_line(chip, *spec.offset)
                                     : gpiod_chip_find_line(chip, spec.lineName.c_str());
      const std::string where = "gpio line " + spec.name + " (" + chipSpec.describe() + " " + spec.describeLine() + ")";
      if (line == nullptr) {
        release();
        return Error{where + ": " + (errno == 0 || errno == ENOENT ? std::string("no such line") : lastError())};
      }
      gpiod_line_request_config config{};
      config.consumer = CONSUMER;
      config.flags = requestFlags(spec);
      const bool output = spec.direction == config::LineDirection::Output;
      config.request_type = output ? GPIOD_LINE_REQUEST_DIRECTION_OUTPUT : GPIOD_LINE_REQUEST_EVENT_BOTH_EDGES;
      const int start = output && i < levels.size() && levels[i] ? 1 : 0;
      if (gpiod_line_request(line, &config, start) != 0) {
        const std::string reason = errno == EBUSY ? "busy (another program holds it)" : lastError();
        release();
        return Error{where + ": request failed: " + reason};
      }
      m_lines[i] = line;
      if (!output) {
        const int fd = gpiod_line_event_get_fd(line);
        if (fd < 0 || ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) | O_NONBLOCK) != 0) {
          const std::string reason = lastError();
          release();
          return Error{where + ": event descriptor: " + reason};
        }
        m_fds.emplace_back(fd, i);
      }
    }
    return {};
  }

  Status set(std::size_t line, bool level) override {
    if (line >= m_lines.size() || m_lines[line] == nullptr) return Error{"line " + std::to_string(line) + " is not requested"};
    if (gpiod_line_set_value(m_lines[line], level ? 1 : 0) != 0) return Error{"set " + m_map.lines[line].name + ": " + lastError()};
    return {};
  }

  Result<bool> get(std::size_t line) override {
    if (line >= m_lines.size() || m_lines[line] == nullptr) return Error{"line " + std::to_string(line) + " is not requested"};
    const int value = gpiod_line_get_value(m_lines[line]);
    if (value < 0) return Error{"get " + m_map.lines[line].name + ": " + lastError()};
    return value == 1;
  }

  [[nodiscard]] std::vector<int> eventFds() const override {
    std::vector<int> fds;
    for (const auto& [fd, line] : m_fds) fds.push_back(fd);
    return fds;
  }

  std::size_t readEvents(int fd, std::span<LineEvent> out) override {
    std::size_t line = m_lines.size();
    for (const auto& [known, index] : m_fds) {
      if (known == fd) line = index;
    }
    if (line == m_lines.size() || out.empty()) return 0;
    std::array<gpiod_line_event, 16> events{};
    const unsigned int wanted = static_cast<unsigned int>(std::min(out.size(), events.size()));
    const int count = gpiod_line_event_read_fd_multiple(fd, events.data(), wanted);
    if (count <= 0) return 0;  // EAGAIN: nothing waiting
    const std::int64_t now = clock::monotonicNs();
    for (int i = 0; i < count; ++i) {
      const gpiod_line_event& event = events[static_cast<std::size_t>(i)];
      std::int64_t stamp = static_cast<std::int64_t>(event.ts.tv_sec) * 1'000'000'000 + event.ts.tv_nsec;
      if (stamp > now || now - stamp > STAMP_TRUST_NS) stamp = now;
      // v1 both-edge events report the logical level read at the interrupt as the edge type
      out[static_cast<std::size_t>(i)] = LineEvent{line, event.event_type == GPIOD_LINE_EVENT_RISING_EDGE, stamp};
    }
    return static_cast<std::size_t>(count);
  }

  void release() noexcept override {
    for (gpiod_line*& line : m_lines) {
      if (line != nullptr) gpiod_line_release(line);
      line = nullptr;
    }
    m_fds.clear();
  }

  [[nodiscard]] std::string_view kind() const noexcept override { return "gpiod"; }

 private:
  const config::GpioMap& m_map;
  std::vector<gpiod_chip*> m_chips;
  std::vector<gpiod_line*> m_lines;
  std::vector<std::pair<int, std::size_t>> m_fds;  // event descriptor -> line
};

}  // namespace

bool haveGpiod() noexcept { return true; }

Result<std::unique_ptr<Chip>> openGpiodChip(const config::GpioMap& map) {
  std::vector<gpiod_chip*> chips;
  for (const config::GpioChip& spec : map.chips) {
    errno = 0;
    gpiod_chip* chip = nullptr;
    if (!spec.label.empty()) {
      chip = gpiod_chip_open_by_label(spec.label.c_str());
    } else if (spec.device.starts_with('/')) {
      chip = gpiod_chip_open(spec.device.c_str());
    } else {
      chip = gpiod_chip_open_by_name(spec.device.c_str());
    }
    if (chip == nullptr) {
      const std::string reason = errno == 0 || errno == ENOENT ? "no such chip" : lastError();
      for (gpiod_chip* opened : chips) gpiod_chip_close(opened);
      return Error{"gpio chip '" + spec.id + "' (" + spec.describe() + "): " + reason};
    }
    chips.push_back(chip);
  }
  return std::unique_ptr<Chip>(new GpiodChip(map, std::move(chips)));
}

}  // namespace openvcu::gpio

#else

namespace openvcu::gpio {

bool haveGpiod() noexcept { return false; }

Result<std::unique_ptr<Chip>> openGpiodChip(const config::GpioMap&) {
  return Error{"this vcu-gpio was built without libgpiod (install libgpiod-dev and rebuild); use \"backend\": \"sim\""};
}

}  // namespace openvcu::gpio

#endif
