#include "gpio_app.hpp"

#include <poll.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <thread>
#include <vector>

#include "controller.hpp"
#include "openvcu/config/faults.hpp"
#include "openvcu/core/clock.hpp"
#include "openvcu/schedule/schedule_config.hpp"
#include "openvcu/service/app_impl.hpp"

namespace openvcu::gpio {
namespace {

/// The longest the output thread sleeps without a table change or a deadline: it also
/// bounds how long stopping waits for it.
constexpr std::int64_t LONGEST_SLEEP_NS = 250'000'000;

}  // namespace

service::CommandPolicy gpioCommandPolicy(const signals::Catalog& catalog, const config::GpioMap& map) {
  service::CommandPolicy policy = service::CommandPolicy::byOwner(catalog, GPIO_WRITER);
  policy.veto = [&map](const ipc::CommandRequest& request,
                       const signals::SignalInfo& info) -> std::optional<std::string> {
    const bool setting =
        request.kind == ipc::CommandKind::SetSignal || request.kind == ipc::CommandKind::OperatorSwitch;
    if (const config::GpioLine* line = map.inputBoundTo(info.key)) {
      if (setting) {
        return "'" + info.key + "' is read from input line " + line->name + "; force it with an override";
      }
      return std::nullopt;
    }
    if (info.reported) {
      return "'" + info.key + "' is the level vcu-gpio reports for its line; command the bound signal instead";
    }
    // The rest of vcu-gpio's keys: the simulated input levels "internal.gpio.sim.<line>".
    if (map.backend != config::GpioBackend::Sim) {
      return "the GPIO back end is " + std::string(config::gpioBackendName(map.backend)) +
             ": the real line sets this input";
    }
    return std::nullopt;
  };
  return policy;
}

struct GpioAppImpl {
  service::Service& runtime;
  std::unique_ptr<Chip> chip;
  std::unique_ptr<Controller> controller;
  std::vector<schedule::WatchedWriter> writers;
  std::thread outputThread;
  std::thread inputThread;
  std::atomic<bool> stopping{false};
  int stopFd{-1};

  explicit GpioAppImpl(service::Service& service) : runtime(service) {}

  ~GpioAppImpl() {
    stopping.store(true);
    if (stopFd >= 0) {
      const std::uint64_t one = 1;
      (void)::write(stopFd, &one, sizeof one);
    }
    if (inputThread.joinable()) inputThread.join();
    if (outputThread.joinable()) outputThread.join();  // within LONGEST_SLEEP_NS
    if (controller) controller->safeState(clock::monotonicNs());
    if (chip) chip->release();
    if (stopFd >= 0) ::close(stopFd);
  }

  Status open() {
    const config::GpioMap& map = runtime.config().gpio;
    if (map.empty()) {
      return Error{"the configuration has no GPIO lines (\"gpio\" in " + runtime.config().path + ")"};
    }
    stopFd = ::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
    if (stopFd < 0) return Error{std::string("eventfd: ") + std::strerror(errno)};
    auto chipResult = openChip(map, runtime.table(), runtime.catalog());
    if (!chipResult) return chipResult.error();
    chip = std::move(*chipResult);
    // The writers whose heartbeats the outputs depend on, with their timeouts: the list
    // vcu-can-tx watches (schedule.json "writers"), one definition for both dead-man switches.
    auto scheduleResult = schedule::loadSchedule(runtime.config(), runtime.catalog());
    if (!scheduleResult) return scheduleResult.error();
    writers = scheduleResult->writers;
    if (writers.empty()) {
      runtime.log().warning(
          "no writers to watch (schedule \"writers\"): the outputs follow their commands even "
          "when their writer stops");
    }
    auto controllerResult = Controller::create(
        map, runtime.catalog(), runtime.table(), *chip,
        [this](bool error, const std::string& line) {
          if (error) {
            runtime.log().error(line);
          } else {
            runtime.log().info(line);
          }
        },
        writers, [this](const schedule::WatchedWriter& writer, bool lost) { writerChanged(writer, lost); });
    if (!controllerResult) return controllerResult.error();
    controller = std::move(*controllerResult);
    if (Status started = controller->start(clock::monotonicNs()); !started) return started;
    controller->updateOutputs(clock::monotonicNs());
    if (Status answering = runtime.answerCommands(gpioCommandPolicy(runtime.catalog(), map)); !answering)
      return answering.error();
    registerCounters(map);
    runtime.setStatus(std::to_string(map.lines.size()) + " lines on the " + std::string(chip->kind()) + " back end");
    outputThread = std::thread([this] { runOutputs(); });
    inputThread = std::thread([this] { runInputs(); });
    return {};
  }

  /// Output thread: the fault event (EventBus::publish is thread-safe), as vcu-can-tx names it.
  void writerChanged(const schedule::WatchedWriter& writer, bool lost) {
    const std::string text = lost ? "no heartbeat from " + writer.service + " for " +
                                        std::to_string(writer.timeoutNs / 1'000'000) +
                                        " ms: every GPIO output at its safe level"
                                  : writer.service + " is back; the GPIO outputs follow its commands again";
    runtime.events().publish(ipc::FaultEvent{0, faults::writerLost(writer.service), runtime.program(),
                                             ipc::FaultSeverity::Critical, lost, text});
  }

  void registerCounters(const config::GpioMap& map) {
    GpioCounters& counters = controller->counters();
    const auto add = [this](const char* name, std::atomic<std::int64_t>& value) {
      runtime.heartbeat().addCounterSource(name, [&value] { return value.load(std::memory_order_relaxed); });
    };
    add("output_switches", counters.outputSwitches);
    add("input_changes", counters.inputChanges);
    add("input_edges", counters.inputEdges);
    add("input_bounces", counters.inputBounces);
    add("set_failures", counters.setFailures);
    runtime.heartbeat().addCounterSource("writers_lost", [this] { return controller->writersLost(); });
    runtime.heartbeat().addStatSource("following_commands", [this] { return controller->followingCommands() ? 1 : 0; });
    for (std::size_t i = 0; i < map.lines.size(); ++i) {
      runtime.heartbeat().addStatSource("line." + map.lines[i].name,
                                        [this, i] { return controller->level(i) ? 1 : 0; });
    }
  }

  /// Outputs (and the sim chip's inputs): woken by table changes and output deadlines.
  void runOutputs() {
    // Woken only by the lines' bound signals and the sim chip's input keys, not by every
    // write of the table.
    std::vector<signals::SignalIndex> indexes;
    for (const config::GpioLine& line : runtime.config().gpio.lines) {
      for (const std::string& key : {line.signal, line.simKey()}) {
        if (const auto index = runtime.catalog().indexOf(key)) indexes.push_back(*index);
      }
    }
    // A lost writer's next beat wakes the thread at once; a live one's loss is a deadline.
    for (const schedule::WatchedWriter& writer : writers) indexes.push_back(writer.heartbeat);
    signals::SignalWatch watch = runtime.table().watch(indexes);
    if (!watch.dedicated())
      runtime.log().warning("no free watch entry in the signal table: woken by every table write");
    std::uint64_t seenDamage = runtime.table().damageCount();
    while (!stopping.load(std::memory_order_relaxed)) {
      // The table lost its values: the watch bits are gone, and the statuses must be written
      // again (the simulated VIC wakes on internal.gpio.Cl15, written on change only).
      if (const std::uint64_t damage = runtime.table().damageCount(); damage != seenDamage) {
        seenDamage = damage;
        watch = {};
        watch = runtime.table().watch(indexes);
        controller->republish(clock::monotonicNs());
      }
      const std::uint32_t epoch = watch.epoch();
      chip->tableChanged();
      const std::int64_t now = clock::monotonicNs();
      controller->updateOutputs(now);
      const std::int64_t deadline = controller->nextOutputDeadlineNs();
      std::int64_t timeout = LONGEST_SLEEP_NS;
      if (deadline != NO_DEADLINE) timeout = std::clamp<std::int64_t>(deadline - now, 0, LONGEST_SLEEP_NS);
      if (timeout > 0) (void)watch.wait(epoch, std::chrono::nanoseconds(timeout));
    }
  }

  /// Inputs: woken by line events and debounce deadlines.
  void runInputs() {
    const std::vector<int> fds = chip->eventFds();
    std::vector<pollfd> watched;
    for (const int fd : fds) watched.push_back(pollfd{fd, POLLIN, 0});
    watched.push_back(pollfd{stopFd, POLLIN, 0});
    std::array<LineEvent, 32> batch{};
    while (!stopping.load(std::memory_order_relaxed)) {
      const std::int64_t now = clock::monotonicNs();
      controller->updateInputs(now);
      const std::int64_t deadline = controller->nextInputDeadlineNs();
      int timeoutMs = -1;
      if (deadline != NO_DEADLINE)
        timeoutMs = static_cast<int>(std::max<std::int64_t>((deadline - now + 999'999) / 1'000'000, 0));
      const int ready = ::poll(watched.data(), watched.size(), timeoutMs);
      if (ready < 0 && errno != EINTR) {
        runtime.log().error(std::string("poll on the line events: ") + std::strerror(errno));
        return;
      }
      for (std::size_t i = 0; i + 1 < watched.size(); ++i) {
        if ((watched[i].revents & POLLIN) == 0) continue;
        const std::size_t count = chip->readEvents(watched[i].fd, batch);
        for (std::size_t e = 0; e < count; ++e) controller->onEvent(batch[e]);
      }
    }
  }
};

}  // namespace openvcu::gpio

template class openvcu::service::App<openvcu::gpio::GpioAppImpl>;
