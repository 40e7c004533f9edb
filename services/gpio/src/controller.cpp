#include "controller.hpp"

#include <algorithm>
#include <cstdio>

namespace openvcu::gpio {

std::string formatDelay(std::int64_t ns) {
  char text[32];
  if (ns % 1'000'000'000 == 0) {
    std::snprintf(text, sizeof text, "%lld s", static_cast<long long>(ns / 1'000'000'000));
  } else if (ns % 1'000'000 == 0) {
    std::snprintf(text, sizeof text, "%lld ms", static_cast<long long>(ns / 1'000'000));
  } else {
    std::snprintf(text, sizeof text, "%.3f ms", static_cast<double>(ns) / 1e6);
  }
  return text;
}

namespace {
const char* onOff(bool level) {
  return level ? "on" : "off";
}
}  // namespace

Result<std::unique_ptr<Controller>> Controller::create(const config::GpioMap& map, const signals::Catalog& catalog,
                                                       signals::SignalTable& table, Chip& chip, LogSink log,
                                                       std::vector<schedule::WatchedWriter> writers,
                                                       WriterSink onWriter) {
  std::vector<LineState> lines(map.lines.size());
  for (std::size_t i = 0; i < map.lines.size(); ++i) {
    const config::GpioLine& spec = map.lines[i];
    const auto status = catalog.indexOf(spec.statusKey());
    const auto bound = catalog.indexOf(spec.signal);
    if (!status || !bound) {
      return Error{"line " + spec.name + ": the catalog lacks " + (status ? spec.signal : spec.statusKey()) +
                   " (configuration mismatch)"};
    }
    lines[i].status = *status;
    lines[i].bound = *bound;
  }
  return std::unique_ptr<Controller>(
      new Controller(map, table, chip, std::move(log), std::move(lines), std::move(writers), std::move(onWriter)));
}

Controller::Controller(const config::GpioMap& map, signals::SignalTable& table, Chip& chip, LogSink log,
                       std::vector<LineState> lines, std::vector<schedule::WatchedWriter> writers,
                       WriterSink onWriter) noexcept
    : m_map(&map),
      m_table(&table),
      m_chip(&chip),
      m_log(std::move(log)),
      m_lines(std::move(lines)),
      m_levels(new std::atomic<bool>[m_lines.size()]),
      m_writers(std::move(writers)),
      m_onWriter(std::move(onWriter)) {
  for (std::size_t i = 0; i < m_lines.size(); ++i) m_levels[i].store(false);
}

bool Controller::output(std::size_t line) const noexcept {
  return m_map->lines[line].direction == config::LineDirection::Output;
}

Status Controller::start(std::int64_t nowNs) {
  const std::size_t count = m_lines.size();
  std::unique_ptr<bool[]> levels(new bool[count + 1]());
  std::vector<char> resumed(count, 0);
  for (std::size_t i = 0; i < count; ++i) {
    if (!output(i)) continue;
    levels[i] = m_map->lines[i].initial;
    const auto previous = m_table->readBus(m_lines[i].status);
    if (previous && previous->updates > 0 && previous->source == GPIO_WRITER) {
      levels[i] = previous->value >= 0.5;
      resumed[i] = 1;
    }
  }
  if (Status requested = m_chip->request(std::span<const bool>(levels.get(), count)); !requested) return requested;
  m_startNs = nowNs;
  m_watches.clear();
  m_confirmed.assign(m_writers.size(), 0);
  const std::uint64_t damage = m_table->damageCount();
  for (std::size_t w = 0; w < m_writers.size(); ++w) {
    const schedule::WatchedWriter& writer = m_writers[w];
    m_watches.emplace_back(writer.timeoutNs, nowNs, damage);
    const auto beat = m_table->readBus(writer.heartbeat);
    const bool fresh = beat && beat->updates > 0 && beat->quality != signals::Quality::NeverReceived &&
                       nowNs - beat->timestampNs <= writer.timeoutNs;
    m_confirmed[w] = fresh ? 1 : 0;
    m_log(false, "watching writer " + writer.service + " (timeout " + formatDelay(writer.timeoutNs) + ")" +
                     (fresh ? "" : ": outputs hold their levels until it beats"));
  }
  m_following.store(std::all_of(m_confirmed.begin(), m_confirmed.end(), [](char c) { return c != 0; }),
                    std::memory_order_relaxed);
  for (std::size_t i = 0; i < count; ++i) {
    LineState& state = m_lines[i];
    bool level = levels[i];
    if (!output(i)) {
      auto read = m_chip->get(i);
      if (!read) return Error{"line " + m_map->lines[i].name + ": " + read.error().message};
      level = *read;
      state.raw = level;
      state.rawSinceNs = nowNs;
      m_table->writeBus(state.bound, level ? 1.0 : 0.0, nowNs, GPIO_WRITER, signals::Quality::Valid);
    }
    state.target = level;
    state.targetSinceNs = nowNs;
    m_levels[i].store(level, std::memory_order_relaxed);
    writeStatus(i, nowNs);
    const config::GpioLine& spec = m_map->lines[i];
    m_log(false, spec.name + ": " + std::string(config::lineDirectionName(spec.direction)) + " " +
                     std::string(m_chip->kind()) + " " + spec.describeLine() + " requested, " + onOff(level) +
                     (resumed[i] != 0 ? " (resumed: the level driven before the restart)" : ""));
  }
  return {};
}

std::int64_t Controller::dueNs(std::size_t line) const noexcept {
  const LineState& state = m_lines[line];
  const config::GpioLine& spec = m_map->lines[line];
  const std::int64_t delay = state.target ? spec.onDelayNs : spec.offDelayNs;
  return std::max(state.targetSinceNs + delay, state.retryAtNs);
}

void Controller::watchWriters(std::int64_t nowNs) {
  bool following = true;
  const std::string* released = nullptr;  // the writer whose beat may release the outputs
  for (std::size_t w = 0; w < m_writers.size(); ++w) {
    const schedule::WatchedWriter& writer = m_writers[w];
    const auto beat = m_table->readBus(writer.heartbeat);
    // The damage count after the read: a read that met the damage counts it.
    const signals::WriterChange change = m_watches[w].update(beat, m_table->damageCount(), nowNs);
    if (m_confirmed[w] == 0 && beat && beat->updates > 0 && beat->quality != signals::Quality::NeverReceived &&
        beat->timestampNs > m_startNs) {
      m_confirmed[w] = 1;
      released = &writer.service;
    }
    if (change == signals::WriterChange::Lost) {
      m_writersLost.fetch_add(1, std::memory_order_relaxed);
      m_confirmed[w] = 1;  // from now on its return is what counts
      m_lostReason = "writer " + writer.service + " lost";
      m_log(true, "writer " + writer.service + " lost: no heartbeat for " + formatDelay(writer.timeoutNs) +
                      "; every output to its safe level");
      if (m_onWriter) m_onWriter(writer, true);
    } else if (change == signals::WriterChange::Back) {
      released = &writer.service;
      if (m_onWriter) m_onWriter(writer, false);
    }
    following = following && m_confirmed[w] != 0 && !m_watches[w].lost();
  }
  if (following && !m_following.load(std::memory_order_relaxed)) {
    m_releasedNs = nowNs;
    m_log(false, "writer " + (released != nullptr ? *released : std::string("?")) +
                     " back: outputs follow their commands, their delays counted from now");
  }
  m_following.store(following, std::memory_order_relaxed);
}

void Controller::driveSafe(std::int64_t nowNs) {
  for (std::size_t i = 0; i < m_lines.size(); ++i) {
    if (!output(i)) continue;
    LineState& state = m_lines[i];
    const bool safe = m_map->lines[i].safe;
    state.target = safe;
    state.targetSinceNs = nowNs;
    if (m_levels[i].load(std::memory_order_relaxed) == safe || nowNs < state.retryAtNs) continue;
    drive(i, safe, nowNs, "safe level: " + m_lostReason);
  }
}

void Controller::updateOutputs(std::int64_t nowNs) {
  if (!m_writers.empty()) {
    watchWriters(nowNs);
    if (!m_following.load(std::memory_order_relaxed)) {
      // a lost writer: safe levels; a writer awaited since the start: levels held
      if (std::any_of(m_watches.begin(), m_watches.end(), [](const signals::WriterWatch& w) { return w.lost(); })) {
        driveSafe(nowNs);
      }
      return;
    }
  }
  for (std::size_t i = 0; i < m_lines.size(); ++i) {
    if (!output(i)) continue;
    LineState& state = m_lines[i];
    const auto snapshot = m_table->read(state.bound);
    if (!snapshot) continue;  // a write in progress: read again at the next wake
    const auto command = signals::effectiveCommand(*snapshot);
    if (!command) continue;  // never commanded: hold
    const bool commanded = command->value >= 0.5;
    if (commanded != state.target) {
      state.target = commanded;
      // A command older than the writer's return counts from the return.
      state.targetSinceNs = std::min(std::max<std::int64_t>(command->timestampNs, m_releasedNs), nowNs);
      state.retryAtNs = 0;
    }
    const bool level = m_levels[i].load(std::memory_order_relaxed);
    if (state.target == level || nowNs < dueNs(i)) continue;
    const config::GpioLine& spec = m_map->lines[i];
    const std::int64_t delay = state.target ? spec.onDelayNs : spec.offDelayNs;
    drive(i, state.target, nowNs,
          "commanded " + std::string(onOff(state.target)) + (command->overridden ? " (override)" : "") +
              (delay > 0 ? ", " + std::string(state.target ? "on" : "off") + "-delay " + formatDelay(delay) : ""));
  }
}

std::int64_t Controller::nextOutputDeadlineNs() const noexcept {
  std::int64_t next = NO_DEADLINE;
  for (const signals::WriterWatch& watch : m_watches) {
    if (!watch.lost()) next = std::min(next, watch.lostAtNs());
  }
  const bool anyLost =
      std::any_of(m_watches.begin(), m_watches.end(), [](const signals::WriterWatch& w) { return w.lost(); });
  if (anyLost) {
    for (std::size_t i = 0; i < m_lines.size(); ++i) {  // a safe drive that failed: its retry
      if (output(i) && m_levels[i].load(std::memory_order_relaxed) != m_map->lines[i].safe) {
        next = std::min(next, m_lines[i].retryAtNs);
      }
    }
    return next;
  }
  if (!m_following.load(std::memory_order_relaxed)) return next;  // held until the writer beats
  for (std::size_t i = 0; i < m_lines.size(); ++i) {
    if (output(i) && m_lines[i].target != m_levels[i].load(std::memory_order_relaxed)) next = std::min(next, dueNs(i));
  }
  return next;
}

void Controller::drive(std::size_t line, bool level, std::int64_t nowNs, const std::string& why) {
  const config::GpioLine& spec = m_map->lines[line];
  if (Status set = m_chip->set(line, level); !set) {
    m_counters.setFailures.fetch_add(1, std::memory_order_relaxed);
    m_lines[line].retryAtNs = nowNs + RETRY_NS;
    m_log(true, spec.name + ": output " + onOff(level) + " failed: " + set.error().message + "; retrying in " +
                    formatDelay(RETRY_NS));
    return;
  }
  m_levels[line].store(level, std::memory_order_relaxed);
  m_counters.outputSwitches.fetch_add(1, std::memory_order_relaxed);
  writeStatus(line, nowNs);
  m_log(false, spec.name + ": output " + onOff(level) + " (" + why + ")");
}

void Controller::onEvent(const LineEvent& event) {
  if (event.line >= m_lines.size() || output(event.line)) return;
  m_counters.inputEdges.fetch_add(1, std::memory_order_relaxed);
  LineState& state = m_lines[event.line];
  if (event.level == state.raw) return;
  const bool accepted = m_levels[event.line].load(std::memory_order_relaxed);
  if (event.level == accepted) m_counters.inputBounces.fetch_add(1, std::memory_order_relaxed);
  state.raw = event.level;
  state.rawSinceNs = event.monotonicNs;
}

void Controller::updateInputs(std::int64_t nowNs) {
  for (std::size_t i = 0; i < m_lines.size(); ++i) {
    if (output(i)) continue;
    LineState& state = m_lines[i];
    const config::GpioLine& spec = m_map->lines[i];
    if (state.raw == m_levels[i].load(std::memory_order_relaxed) || nowNs < state.rawSinceNs + spec.debounceNs)
      continue;
    m_levels[i].store(state.raw, std::memory_order_relaxed);
    m_table->writeBus(state.bound, state.raw ? 1.0 : 0.0, nowNs, GPIO_WRITER, signals::Quality::Valid);
    writeStatus(i, nowNs);
    m_counters.inputChanges.fetch_add(1, std::memory_order_relaxed);
    m_log(false, spec.name + ": input " + onOff(state.raw) + " -> " + spec.signal + " = " + (state.raw ? "1" : "0") +
                     (spec.debounceNs > 0 ? " (stable for " + formatDelay(spec.debounceNs) + ")" : ""));
  }
}

std::int64_t Controller::nextInputDeadlineNs() const noexcept {
  std::int64_t next = NO_DEADLINE;
  for (std::size_t i = 0; i < m_lines.size(); ++i) {
    if (!output(i) && m_lines[i].raw != m_levels[i].load(std::memory_order_relaxed)) {
      next = std::min(next, m_lines[i].rawSinceNs + m_map->lines[i].debounceNs);
    }
  }
  return next;
}

void Controller::safeState(std::int64_t nowNs) {
  for (std::size_t i = 0; i < m_lines.size(); ++i) {
    if (!output(i)) continue;
    const bool safe = m_map->lines[i].safe;
    if (m_levels[i].load(std::memory_order_relaxed) == safe) continue;
    m_lines[i].retryAtNs = 0;
    drive(i, safe, nowNs, "safe state");
  }
}

void Controller::republish(std::int64_t nowNs) noexcept {
  for (std::size_t i = 0; i < m_lines.size(); ++i) {
    if (!output(i)) {
      m_table->writeBus(m_lines[i].bound, m_levels[i].load(std::memory_order_relaxed) ? 1.0 : 0.0, nowNs, GPIO_WRITER,
                        signals::Quality::Valid);
    }
    writeStatus(i, nowNs);
  }
}

void Controller::writeStatus(std::size_t line, std::int64_t nowNs) noexcept {
  m_table->writeBus(m_lines[line].status, m_levels[line].load(std::memory_order_relaxed) ? 1.0 : 0.0, nowNs,
                    GPIO_WRITER, signals::Quality::Valid);
}

}  // namespace openvcu::gpio
