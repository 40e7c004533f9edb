// `vcu send` and `vcu dump`. Each command's description and footer are its manual
// (`vcu send --help`); README.md explains the decisions behind them.
#include "bus_commands.hpp"

#include <signal.h>
#include <unistd.h>

#include <CLI/CLI.hpp>

#include "cli_checks.hpp"
#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <csignal>
#include <memory>
#include <optional>
#include <string_view>
#include <thread>

#include "cansend_syntax.hpp"
#include "decode_output.hpp"
#include "diagnostics.hpp"
#include "stop_signal.hpp"
#include "openvcu/can/log_writer.hpp"
#include "openvcu/can_links/open_link.hpp"
#include "openvcu/core/text.hpp"
#include "openvcu/dbc/codec.hpp"
#include "openvcu/dbc/matcher.hpp"
#include "openvcu/ipc/frame_stream.hpp"
#include "openvcu/ipc/request_stream.hpp"
#include "openvcu/ipc/runtime.hpp"
#include "openvcu/ipc/waiter.hpp"

namespace openvcu::cli {
namespace {

using namespace std::chrono_literals;

/// How long `vcu send` waits for a subscriber of can-tx's send stream (why: RouDi
/// connects new ports in one pass every 100 ms; 0.5 s leaves room for a loaded machine).
constexpr auto CAN_TX_CONNECT_TIMEOUT = 500ms;
/// A frame refused as Busy (transmit queue or mempool full) is retried this long.
constexpr auto BUSY_RETRY_TIME = 100ms;
constexpr auto BUSY_RETRY_STEP = 1ms;
/// The longest `vcu dump` waits between looks at its stop flag (SIGINT, SIGTERM).
constexpr auto DUMP_TICK = 200ms;

constexpr const char* CONFIG_NOTE =
    "The stack: --config FILE or $OPENVCU_CONFIG (required: there is no default), and\n"
    "--instance for a stack started with another instance name.\n";

constexpr const char* SEND_DESCRIPTION = "Send CAN frames (cansend syntax) on a bus of the configuration";
constexpr const char* SEND_FOOTER =
    "Sends each FRAME, in order, on bus BUS (its logical name in the configuration,\n"
    "e.g. 'vehicle'). FRAME is cansend's syntax:\n"
    "  123#DEADBEEF      standard (11-bit) ID: exactly 3 hex digits, 0..8 data bytes\n"
    "  18FEF121#0102     extended (29-bit) ID: exactly 8 hex digits\n"
    "  123#R  123#R4     remote request, optional length digit 0..8\n"
    "  123##1DEADBEEF    CAN FD: '##', one flags digit (1 BRS, 2 ESI), 0..64 bytes; a\n"
    "                    length between FD sizes is padded with zeros (9 -> 12)\n"
    "  123#11.22.33      a '.' may separate bytes\n"
    "Stricter than cansend: text after the data, a standard ID above 7FF, the raw DLC\n"
    "'_' and CAN XL IDs are errors. All frames are checked before anything is sent.\n"
    "\n"
    "Default: through vcu-can-tx. The frames are published on the bus's send stream\n"
    "(openvcu/<instance>.<bus>/send) once a subscriber is connected (up to 0.5 s), and\n"
    "can-tx writes them onto the bus. Without one, nothing is sent and the error\n"
    "suggests --direct.\n"
    "--direct: write onto the bus's link itself (socketcan:IFACE or sim:NAME; a replay:\n"
    "link cannot be sent to), bypassing can-tx. On a sim: link it first waits until\n"
    "RouDi has connected the new link to the other nodes (normally < 0.1 s): a frame\n"
    "sent before would reach nobody.\n"
    "--repeat N sends the list N times; --interval MS pauses between two frames. A frame\n"
    "refused as busy (full transmit queue) is retried for 0.1 s.\n"
    "Needs iox-roudi (frame streams and sim links); registers as vcu-send-<pid>.\n"
    "\n"
    "Examples:\n"
    "  vcu send vehicle 18FEF121#0102030405060708\n"
    "  vcu send --direct vehicle 123#DEADBEEF 123#R --repeat 10 --interval 100\n"
    "Exit: 0 every frame handed over (published to a connected can-tx, or accepted by\n"
    "the link), 1 unknown bus, configuration error, nobody listening, a link error or a\n"
    "refused frame, 2 usage error or a malformed FRAME.\n";

constexpr const char* DUMP_DESCRIPTION = "Print the frames of a bus as candump -L lines, optionally decoded";
constexpr const char* DUMP_FOOTER =
    "Prints each frame of a stream of bus BUS as a candump -L line (what candump -L\n"
    "writes and canplayer, python-can and 'vcu dbc decode' read), the bus name as the\n"
    "interface:\n"
    "  (1700000000.123456) vehicle 18FEF121#0102030405060708\n"
    "--stream: rx (default) frames vcu-can-rx received; tx frames vcu-can-tx sent;\n"
    "send requests to can-tx (vcu send, the HMI); req J1939 requests for this node\n"
    "(can-rx -> can-tx); net J1939 address claims and TP answers to this node's\n"
    "transfers (can-rx -> can-tx); wire a simulated bus itself (sim: buses only: every frame any\n"
    "node sends, no service needed); all of them (wire on sim: buses), each line\n"
    "prefixed with its stream ('rx  ', 'tx  ', 'send', 'req ', 'net ', 'wire'), in arrival\n"
    "order per stream.\n"
    "The time (UTC seconds) is the frame's kernel/hardware stamp when it has one, else\n"
    "its publication time (CLOCK_MONOTONIC, converted with the current clock offset).\n"
    "--decode appends the matched DBC message (J1939 PGN rule, as 'vcu dbc decode') and\n"
    "its signals with unit or value text; unmatched frames stay plain:\n"
    "  (...) vehicle 18FEF221#0102030405060708  Status: SOC=0.5 %, Mode=2 \"Fault\"\n"
    "A line 'listening on ...' on stderr says the subscriptions are in place. Runs until\n"
    "Ctrl-C (SIGINT) or SIGTERM, --count N frames, or --timeout SECONDS without a frame.\n"
    "Needs iox-roudi; registers as vcu-dump-<pid>.\n"
    "\n"
    "Examples:\n"
    "  vcu dump vehicle\n"
    "  vcu dump vehicle --stream wire --decode\n"
    "  vcu dump vehicle --count 1000 > drive.log\n"
    "Exit: 0 stopped by a signal or --count reached, or --timeout after at least one frame\n"
    "without --count; 1 --timeout before any frame or before --count frames, unknown bus,\n"
    "configuration error, no iox-roudi, write error; 2 usage error.\n";

// ---- shared -----------------------------------------------------------------------------

std::string join(const std::vector<std::string>& items, std::string_view separator) {
  std::string text;
  for (const std::string& item : items) {
    if (!text.empty()) text += separator;
    text += item;
  }
  return text;
}

/// The bus named `name`, or nullptr after reporting it with a "did you mean".
const config::BusConfig* findBus(const config::VehicleConfig& config, const std::string& name, Sink& err) {
  if (const config::BusConfig* bus = config.findBus(name)) return bus;
  std::vector<std::string> names;
  names.reserve(config.buses.size());
  for (const config::BusConfig& bus : config.buses) names.push_back(bus.name);
  std::string message = "unknown bus '" + name + "'";
  if (const auto maybeSuggestion = text::didYouMean(name, names)) {
    message += " (did you mean '" + *maybeSuggestion + "'?)";
  } else {
    message += " (the buses of " + config.path + ": " + join(names, ", ") + ")";
  }
  reportError(err, message);
  return nullptr;
}

std::size_t busIndex(const config::VehicleConfig& config, const config::BusConfig& bus) noexcept {
  return static_cast<std::size_t>(&bus - config.buses.data());
}

/// Registers with iox-roudi as "vcu-<command>-<pid>": unique per invocation, so two vcu
/// processes never cut each other off.
bool initRuntime(std::string_view command, Sink& err) {
  const std::string name = "vcu-" + std::string(command) + "-" + std::to_string(::getpid());
  if (const Status initResult = ipc::Runtime::init(name); !initResult) {
    reportError(err, initResult.error().message);
    return false;
  }
  return true;
}

std::string plural(std::uint64_t count, std::string_view noun) {
  return std::to_string(count) + " " + std::string(noun) + (count == 1 ? "" : "s");
}

// ---- send -------------------------------------------------------------------------------

struct ParsedFrame {
  std::string text;  ///< as given
  can::Frame frame;
};

/// Every FRAME parsed; each malformed one reported. Empty optional when any was malformed.
std::optional<std::vector<ParsedFrame>> parseFrames(const std::vector<std::string>& texts, Sink& err) {
  std::vector<ParsedFrame> frames;
  bool allGood = true;
  for (const std::string& text : texts) {
    Result<can::Frame> parseResult = parseCansendFrame(text);
    if (!parseResult) {
      reportError(err, "'" + text + "': " + parseResult.error().message);
      allGood = false;
      continue;
    }
    frames.push_back(ParsedFrame{text, *parseResult});
  }
  if (!allGood) return std::nullopt;
  return frames;
}

std::string refusalText(can::SendStatus status) {
  switch (status) {
    case can::SendStatus::Busy:
      return "still busy after " + std::to_string(BUSY_RETRY_TIME.count()) + " ms (transmit queue full)";
    case can::SendStatus::Down:
      return "the link is down";
    case can::SendStatus::Invalid:
      return "the link refused it as invalid on this bus";
    case can::SendStatus::NotSupported:
      return "the link cannot send";
    case can::SendStatus::Sent:
      break;
  }
  return std::string(can::sendStatusName(status));
}

/// Hands every frame, `repeat` times, to `sendOne` (returns a can::SendStatus), pausing
/// `intervalMs` between two frames and retrying Busy for BUSY_RETRY_TIME. Stops at the
/// first refusal and reports it. Returns the number handed over.
template <typename SendOne>
std::uint64_t sendAll(const SendOptions& options, const std::vector<ParsedFrame>& frames, SendOne&& sendOne,
                      Sink& err) {
  const auto interval = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double, std::milli>(options.intervalMs));
  auto nextSend = std::chrono::steady_clock::now();
  std::uint64_t handedOver = 0;
  for (std::uint32_t round = 0; round < options.repeat; ++round) {
    for (const ParsedFrame& parsed : frames) {
      if (handedOver > 0 && interval.count() > 0) {
        nextSend += interval;  // a fixed schedule: the pauses do not add up the send times
        std::this_thread::sleep_until(nextSend);
      }
      can::SendStatus status = sendOne(parsed.frame);
      const auto busyDeadline = std::chrono::steady_clock::now() + BUSY_RETRY_TIME;
      while (status == can::SendStatus::Busy && std::chrono::steady_clock::now() < busyDeadline) {
        std::this_thread::sleep_for(BUSY_RETRY_STEP);
        status = sendOne(parsed.frame);
      }
      if (status != can::SendStatus::Sent) {
        reportError(err, "'" + parsed.text + "': not sent: " + refusalText(status) + " (" +
                             plural(handedOver, "frame") + " sent before)");
        return handedOver;
      }
      ++handedOver;
    }
  }
  return handedOver;
}

ExitCode sendDirect(const SendOptions& options, const config::BusConfig& bus, const std::vector<ParsedFrame>& frames,
                    Streams streams) {
  const std::string linkName = bus.link.toString();
  if (bus.link.kind == config::LinkKind::Replay) {
    reportError(streams.err, "bus '" + bus.name + "' is " + linkName + ": a log cannot be sent to");
    return ExitCode::Failure;
  }
  if (bus.link.kind == config::LinkKind::Sim && !initRuntime("send", streams.err)) return ExitCode::Failure;
  can::LinkOptions linkOptions = bus.linkOptions();
  linkOptions.errorFrames = false;
  auto linkResult = can::openLink(bus.link.kind, bus.link.target, linkOptions);
  if (!linkResult) {
    reportError(streams.err, linkResult.error().message);
    return ExitCode::Failure;
  }
  can::Link& link = **linkResult;
  if (bus.link.kind == config::LinkKind::Sim) {
    if (const Status connected = waitUntilSimLinkConnected(bus.link.target); !connected) {
      reportError(streams.err, connected.error().message);
      return ExitCode::Failure;
    }
  }
  const std::uint64_t expected = static_cast<std::uint64_t>(frames.size()) * options.repeat;
  const std::uint64_t sent = sendAll(
      options, frames, [&link](const can::Frame& frame) { return link.send(frame); }, streams.err);
  if (sent != expected) return ExitCode::Failure;
  streams.out.write("sent " + plural(sent, "frame") + " on " + link.name() + "\n");
  return ExitCode::Ok;
}

ExitCode sendThroughCanTx(const SendOptions& options, const config::VehicleConfig& config, const config::BusConfig& bus,
                          const std::vector<ParsedFrame>& frames, Streams streams) {
  if (!initRuntime("send", streams.err)) return ExitCode::Failure;
  const ipc::FrameTopic topic{config.instance, bus.name, ipc::FrameStream::SendRequest};
  auto publisherResult = ipc::FramePublisher::create(topic);
  if (!publisherResult) {
    reportError(streams.err, publisherResult.error().message);
    return ExitCode::Failure;
  }
  ipc::FramePublisher& publisher = *publisherResult;
  if (!publisher.waitForSubscribers(CAN_TX_CONNECT_TIMEOUT)) {
    reportError(streams.err, "nothing sent: nobody listens on " + topic.toString() + " (is vcu-can-tx running?); " +
                                 "--direct writes onto " + bus.link.toString() + " without can-tx");
    return ExitCode::Failure;
  }
  const auto index = static_cast<std::uint16_t>(busIndex(config, bus));
  const std::uint64_t expected = static_cast<std::uint64_t>(frames.size()) * options.repeat;
  const std::uint64_t sent = sendAll(
      options, frames,
      [&publisher, index](const can::Frame& frame) {
        ipc::FrameSample sample{};
        sample.busIndex = index;
        sample.frame = frame;
        return publisher.publish(sample) ? can::SendStatus::Sent : can::SendStatus::Busy;  // false: mempool full
      },
      streams.err);
  if (sent != expected) return ExitCode::Failure;
  streams.out.write("sent " + plural(sent, "frame") + " to can-tx on " + topic.toString() + "\n");
  return ExitCode::Ok;
}

// ---- dump -------------------------------------------------------------------------------

/// The topics `--stream` names, or empty after reporting why not.
std::vector<ipc::FrameTopic> dumpTopics(const std::string& stream, const config::VehicleConfig& config,
                                        const config::BusConfig& bus, Sink& err) {
  const bool simulated = bus.link.kind == config::LinkKind::Sim;
  const ipc::FrameTopic wire{"sim", bus.link.target, ipc::FrameStream::SimWire};
  std::vector<ipc::FrameTopic> topics;
  for (const ipc::FrameStream candidate :
       {ipc::FrameStream::Received, ipc::FrameStream::Sent, ipc::FrameStream::SendRequest, ipc::FrameStream::Request,
        ipc::FrameStream::Network}) {
    if (stream == "all" || stream == ipc::eventName(candidate)) {
      topics.push_back(ipc::FrameTopic{config.instance, bus.name, candidate});
    }
  }
  if (stream == "wire" && !simulated) {
    reportError(err, "--stream wire: bus '" + bus.name + "' is " + bus.link.toString() +
                         "; 'wire' exists for sim: buses only (use rx)");
    return {};
  }
  if ((stream == "wire" || stream == "all") && simulated) topics.push_back(wire);
  return topics;
}

/// "rx  ", "send", ...: the --stream all prefix, one width for every stream.
std::string streamLabel(ipc::FrameStream stream) {
  std::string label(ipc::eventName(stream));
  label.resize(4, ' ');
  return label;
}

/// Who publishes a stream, for the "no frame" message.
std::string_view publisherHint(ipc::FrameStream stream) noexcept {
  switch (stream) {
    case ipc::FrameStream::Received:
    case ipc::FrameStream::Request:
    case ipc::FrameStream::Network:
      return " (is vcu-can-rx running?)";
    case ipc::FrameStream::Sent:
      return " (is vcu-can-tx running?)";
    case ipc::FrameStream::SendRequest:
    case ipc::FrameStream::SimWire:
      return "";
  }
  return "";
}

/// The frame's time as CLOCK_REALTIME ns: the kernel/hardware stamp when the producer had
/// one, else the publication time (CLOCK_MONOTONIC, stamped by every publisher).
std::int64_t realtimeNs(const ipc::FrameSample& sample) noexcept {
  if (sample.hardwareNs != 0) return sample.hardwareNs;
  return monotonicToRealtimeNs(sample.monotonicNs);
}

/// A J1939 request can-rx handed to can-tx, as candump's time and channel then the request:
/// "(1700000000.123456) vehicle request PGN 0x0FEE6 (65254) from 0x21, global".
std::string requestLine(const ipc::RequestSample& request, const std::string& bus) {
  const std::int64_t ns = monotonicToRealtimeNs(request.monotonicNs);
  std::array<char, 160> text{};
  std::snprintf(text.data(), text.size(), "(%lld.%06lld) %s request PGN 0x%05X (%u) from 0x%02X, %s\n",
                static_cast<long long>(ns / 1'000'000'000), static_cast<long long>((ns % 1'000'000'000) / 1000),
                bus.c_str(), static_cast<unsigned>(request.pgn), static_cast<unsigned>(request.pgn),
                static_cast<unsigned>(request.requester), request.global ? "global" : "to this node");
  return text.data();
}

/// --decode: the matched message and its signals, appended to a candump line.
class SignalAppender {
 public:
  explicit SignalAppender(const dbc::Database& database)
      : m_database(database), m_matcher(database, dbc::MatchMode::J1939), m_codecs(database) {
    std::size_t most = 1;
    for (const dbc::Message& message : database.messages) most = std::max(most, message.signals.size());
    m_values.resize(most);  // the codec visits each signal at most once
  }

  /// "  Status: SOC=0.5 %, Mode=2 \"Fault\"", or nothing when no message matches.
  void append(std::string& out, const can::Frame& frame) {
    if ((frame.flags & can::FLAG_ERROR) != 0) return;
    const std::int32_t match = m_matcher.match(frame.id, frame.extended());
    if (match == dbc::MessageMatcher::NO_MATCH) return;
    const auto messageIndex = static_cast<std::size_t>(match);
    const dbc::Message& message = m_database.messages[messageIndex];
    out += "  ";
    out += message.displayName;
    out += ':';
    if ((frame.flags & can::FLAG_RTR) != 0) {
      out += " remote request";
      return;
    }
    std::size_t decoded = 0;
    m_codecs[messageIndex].decode(frame.payload(), [&](std::uint32_t signalIndex, const dbc::DecodedValue& value) {
      m_values[decoded++] = SignalValue{signalIndex, value};
    });
    if (decoded == 0) out += " no signal in the received bytes";
    for (std::size_t i = 0; i < decoded; ++i) {
      const dbc::Signal& signal = message.signals[m_values[i].signalIndex];
      const dbc::DecodedValue& value = m_values[i].value;
      out += i == 0 ? " " : ", ";
      out += signal.displayName;
      out += '=';
      appendNumber(out, value.physical, false);
      const std::string* valueText = nullptr;
      if (value.kind == dbc::RawKind::Unsigned) {
        valueText = signal.describe(static_cast<std::int64_t>(value.rawUnsigned));
      } else if (value.kind == dbc::RawKind::Signed) {
        valueText = signal.describe(value.rawSigned);
      }
      if (valueText != nullptr) {
        out += " \"" + *valueText + "\"";
      } else if (!signal.unit.empty()) {
        out += ' ';
        out += signal.unit;
      }
    }
  }

 private:
  const dbc::Database& m_database;
  dbc::MessageMatcher m_matcher;
  dbc::DatabaseCodec m_codecs;
  std::vector<SignalValue> m_values;
};

}  // namespace

ExitCode runSend(const SendOptions& options, Streams streams) {
  const auto maybeFrames = parseFrames(options.frames, streams.err);
  if (!maybeFrames) return ExitCode::Usage;
  ExitCode exitCode = ExitCode::Ok;
  const auto maybeStack = loadStack(options.stack, streams.err, &exitCode);
  if (!maybeStack) return exitCode;
  const config::VehicleConfig& config = maybeStack->config;
  const config::BusConfig* bus = findBus(config, options.bus, streams.err);
  if (bus == nullptr) return ExitCode::Failure;
  for (const ParsedFrame& parsed : *maybeFrames) {
    if (parsed.frame.fd() && !bus->fd) {
      reportError(streams.err, "'" + parsed.text + "': bus '" + bus->name +
                                   "' is classic CAN (its configuration does not set \"fd\"): no CAN FD frames");
      return ExitCode::Failure;
    }
  }
  if (options.direct) return sendDirect(options, *bus, *maybeFrames, streams);
  return sendThroughCanTx(options, config, *bus, *maybeFrames, streams);
}

ExitCode runDump(const DumpOptions& options, Streams streams) {
  ExitCode exitCode = ExitCode::Ok;
  const auto maybeStack = loadStack(options.stack, streams.err, &exitCode);
  if (!maybeStack) return exitCode;
  const config::VehicleConfig& config = maybeStack->config;
  const config::BusConfig* bus = findBus(config, options.bus, streams.err);
  if (bus == nullptr) return ExitCode::Failure;
  const std::vector<ipc::FrameTopic> topics = dumpTopics(options.stream, config, *bus, streams.err);
  if (topics.empty()) return ExitCode::Failure;
  if (!initRuntime("dump", streams.err)) return ExitCode::Failure;

  // Frames on every stream but "req", which carries typed J1939 requests (RequestSample).
  std::vector<ipc::FrameSubscriber> subscribers;
  std::optional<ipc::RequestSubscriber> requests;
  std::vector<ipc::FrameTopic> frameTopics;
  subscribers.reserve(topics.size());  // attached below by address: no reallocation after
  for (const ipc::FrameTopic& topic : topics) {
    if (topic.stream == ipc::FrameStream::Request) {
      auto requestResult = ipc::RequestSubscriber::create(topic.instance, topic.bus);
      if (!requestResult) {
        reportError(streams.err, requestResult.error().message);
        return ExitCode::Failure;
      }
      requests.emplace(std::move(*requestResult));
      continue;
    }
    auto subscriberResult = ipc::FrameSubscriber::create(topic);
    if (!subscriberResult) {
      reportError(streams.err, subscriberResult.error().message);
      return ExitCode::Failure;
    }
    subscribers.push_back(std::move(*subscriberResult));
    frameTopics.push_back(topic);
  }
  auto waiterResult = ipc::Waiter::create();
  if (!waiterResult) {
    reportError(streams.err, waiterResult.error().message);
    return ExitCode::Failure;
  }
  ipc::Waiter& waiter = *waiterResult;
  std::vector<std::string> names;
  for (std::size_t i = 0; i < subscribers.size(); ++i) {
    if (const Status attached = waiter.attach(subscribers[i], i); !attached) {
      reportError(streams.err, attached.error().message);
      return ExitCode::Failure;
    }
    names.push_back(frameTopics[i].toString());
  }
  const std::uint64_t requestsId = subscribers.size();
  if (requests) {
    if (const Status attached = waiter.attach(*requests, requestsId); !attached) {
      reportError(streams.err, attached.error().message);
      return ExitCode::Failure;
    }
    names.push_back(ipc::FrameTopic{config.instance, bus->name, ipc::FrameStream::Request}.toString());
  }
  std::optional<SignalAppender> maybeSignals;
  if (options.decode) maybeSignals.emplace(config.database);
  const bool prefixed = topics.size() > 1;

  const StopSignalScope stopSignals;
  streams.err.write("listening on " + join(names, ", ") + " (Ctrl-C to stop)\n");
  streams.err.flush();

  const auto timeout = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(options.timeoutSeconds));
  auto lastFrame = std::chrono::steady_clock::now();
  std::uint64_t printed = 0;
  std::string out;
  bool timedOut = false;
  while (!stopRequested()) {
    std::chrono::nanoseconds wait = DUMP_TICK;
    if (options.timeoutSeconds > 0) {
      const auto left = lastFrame + timeout - std::chrono::steady_clock::now();
      if (left <= std::chrono::steady_clock::duration::zero()) {
        timedOut = true;
        break;
      }
      wait = std::min(wait, std::chrono::duration_cast<std::chrono::nanoseconds>(left));
    }
    out.clear();
    for (const std::uint64_t id : waiter.waitFor(wait)) {
      if (id == requestsId) {
        while (options.count == 0 || printed < options.count) {
          const std::optional<ipc::RequestSample> maybeRequest = requests->take();
          if (!maybeRequest) break;
          if (prefixed) out += streamLabel(ipc::FrameStream::Request) + ' ';
          out += requestLine(*maybeRequest, bus->name);
          ++printed;
        }
        continue;
      }
      ipc::FrameSubscriber& subscriber = subscribers[id];
      if (subscriber.hasLostFrames()) {
        streams.err.write("vcu: warning: frames lost on " + names[id] + ": the dump fell behind\n");
      }
      while (options.count == 0 || printed < options.count) {
        const std::optional<ipc::FrameSample> maybeSample = subscriber.take();
        if (!maybeSample) break;
        can::Frame frame = maybeSample->frame;
        frame.timestampNs = realtimeNs(*maybeSample);
        if (prefixed) out += streamLabel(frameTopics[id].stream) + ' ';
        out += can::formatCandumpL(frame, bus->name);
        if (maybeSignals) maybeSignals->append(out, frame);
        out += '\n';
        ++printed;
      }
    }
    if (!out.empty()) {
      streams.out.write(out);
      if (!streams.out.flush()) return ExitCode::Failure;  // e.g. `| head` went away; run() says why
      lastFrame = std::chrono::steady_clock::now();
    }
    if (options.count > 0 && printed >= options.count) return ExitCode::Ok;
  }
  if (!timedOut) return ExitCode::Ok;  // SIGINT or SIGTERM
  if (printed > 0 && options.count == 0) return ExitCode::Ok;
  std::string message = "no frame on " + join(names, ", ") + " for " + formatNumber(options.timeoutSeconds) + " s";
  if (options.count > 0) {
    message += ": " + std::to_string(printed) + " of " + plural(options.count, "frame") + " printed";
  }
  if (printed == 0 && topics.size() == 1) message += publisherHint(topics.front().stream);
  reportError(streams.err, message);
  return ExitCode::Failure;
}

void registerBusCommands(CLI::App& app, CommandContext& context) {
  auto sendOptions = std::make_shared<SendOptions>();
  CLI::App* send = app.add_subcommand("send", SEND_DESCRIPTION);
  send->footer(std::string(SEND_FOOTER) + CONFIG_NOTE);
  send->add_option("BUS", sendOptions->bus, "bus name in the configuration, e.g. vehicle")->required()->type_name("");
  send->add_option("FRAME", sendOptions->frames, "frames in cansend syntax, e.g. 123#DEADBEEF")
      ->required()
      ->type_name("");
  send->add_flag("--direct", sendOptions->direct, "write onto the bus's link instead of through vcu-can-tx");
  send->add_option("--repeat", sendOptions->repeat, "send the list N times (default 1)")
      ->check(CLI::Range(1u, 1'000'000'000u))
      ->option_text("N");
  send->add_option("--interval", sendOptions->intervalMs, "milliseconds between two frames (default 0)")
      ->check(nonNegativeNumber())
      ->option_text("MS");
  addStackOptions(*send, sendOptions->stack);
  send->callback([sendOptions, &context] { context.exitCode = runSend(*sendOptions, context.streams); });

  auto dumpOptions = std::make_shared<DumpOptions>();
  CLI::App* dump = app.add_subcommand("dump", DUMP_DESCRIPTION);
  dump->footer(std::string(DUMP_FOOTER) + CONFIG_NOTE);
  dump->add_option("BUS", dumpOptions->bus, "bus name in the configuration, e.g. vehicle")->required()->type_name("");
  dump->add_option("-s,--stream", dumpOptions->stream, "which frames (default rx)")
      ->check(CLI::IsMember({"rx", "tx", "send", "req", "net", "wire", "all"}))
      ->option_text("rx|tx|send|req|net|wire|all");
  dump->add_flag("-d,--decode", dumpOptions->decode, "append the DBC message and its signal values");
  dump->add_option("-n,--count", dumpOptions->count, "stop after N frames")->option_text("N");
  dump->add_option("--timeout", dumpOptions->timeoutSeconds, "stop after this many seconds without a frame")
      ->check(CLI::PositiveNumber)
      ->option_text("SECONDS");
  addStackOptions(*dump, dumpOptions->stack);
  dump->callback([dumpOptions, &context] { context.exitCode = runDump(*dumpOptions, context.streams); });
}

}  // namespace openvcu::cli
