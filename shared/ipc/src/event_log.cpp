// readEventLog: LCM's C event-log reader, and the generated types' decoders via event_bus.cpp.
#include "openvcu/ipc/event_log.hpp"

#include <lcm/eventlog.h>

#include <memory>
#include <optional>
#include <string_view>
#include <system_error>
#include <cerrno>

#include "openvcu/ipc/event_bus.hpp"

namespace openvcu::ipc {
namespace {

bool endsWith(std::string_view text, std::string_view suffix) {
  return text.size() >= suffix.size() && text.substr(text.size() - suffix.size()) == suffix;
}

}  // namespace

Result<LoggedEvents> readEventLog(const std::string& path, std::size_t maxEvents) {
  const Location where{path, 0, 0, {}};
  std::unique_ptr<lcm_eventlog_t, void (*)(lcm_eventlog_t*)> log(lcm_eventlog_create(path.c_str(), "r"),
                                                                  lcm_eventlog_destroy);
  if (!log) return Error{std::string("cannot open: ") + std::generic_category().message(errno), where};
  LoggedEvents events;
  std::string fsmSuffix(1, '_');
  fsmSuffix += channelSuffix(EventKind::Fsm);
  std::string faultSuffix(1, '_');
  faultSuffix += channelSuffix(EventKind::Fault);
  while (lcm_eventlog_event_t* raw = lcm_eventlog_read_next_event(log.get())) {
    std::unique_ptr<lcm_eventlog_event_t, void (*)(lcm_eventlog_event_t*)> event(raw, lcm_eventlog_free_event);
    ++events.events;
    const std::string_view channel(event->channel, static_cast<std::size_t>(event->channellen));
    const auto size = static_cast<std::size_t>(event->datalen);
    if (endsWith(channel, fsmSuffix)) {
      std::optional<FsmTransition> transition = decodeFsmTransition(event->data, size);
      if (!transition) {
        ++events.undecodable;
      } else if (events.transitions.size() < maxEvents) {
        events.transitions.push_back(std::move(*transition));
      } else {
        ++events.dropped;
      }
    } else if (endsWith(channel, faultSuffix)) {
      std::optional<FaultEvent> fault = decodeFaultEvent(event->data, size);
      if (!fault) {
        ++events.undecodable;
      } else if (events.faults.size() < maxEvents) {
        events.faults.push_back(std::move(*fault));
      } else {
        ++events.dropped;
      }
    }
  }
  if (events.events == 0) return Error{"not an LCM event log, or empty", where};
  return events;
}

}  // namespace openvcu::ipc
