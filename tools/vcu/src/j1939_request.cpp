// `vcu j1939 request PGN --to ADDR`: a J1939 Request through vcu-can-tx, the answer from
// vcu-can-rx's received frames. The description and footer are its manual.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <initializer_list>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "decode_output.hpp"
#include "diagnostics.hpp"
#include "j1939_commands.hpp"
#include "openvcu/config/catalog.hpp"
#include "openvcu/config/receive.hpp"
#include "openvcu/dbc/codec.hpp"
#include "openvcu/dbc/matcher.hpp"
#include "openvcu/ipc/event_bus.hpp"
#include "openvcu/ipc/frame_stream.hpp"
#include "openvcu/ipc/runtime.hpp"
#include "openvcu/ipc/waiter.hpp"
#include "openvcu/j1939/acknowledgement.hpp"
#include "openvcu/j1939/dm1.hpp"
#include "openvcu/j1939/request.hpp"
#include "openvcu/j1939/transport.hpp"

namespace openvcu::cli {
namespace {

using namespace std::chrono_literals;

/// How long the request waits for a subscriber of can-tx's send stream (as `vcu send`:
/// RouDi connects new ports in one pass every 100 ms).
constexpr auto CAN_TX_CONNECT_TIMEOUT = 500ms;
/// How long the request listens for can-tx's J1939 view to learn the VCU's address when
/// --from is not given (the view comes once a second).
constexpr auto VIEW_WAIT = 1200ms;

constexpr std::uint32_t PGN_SOFTWARE_ID = 0xFEDA;   ///< SAE J1939-71 PGN 65242 Software Identification
constexpr std::uint32_t PGN_ECU_ID = 0xFDC5;        ///< SAE J1939-71 PGN 64965 ECU Identification Information
constexpr std::uint32_t PGN_COMPONENT_ID = 0xFEEB;  ///< SAE J1939-71 PGN 65259 Component Identification
constexpr char IDENTIFICATION_DELIMITER = '*';      ///< J1939-71: ends each identification field, 0x2a (42)

constexpr const char* REQUEST_DESCRIPTION = "Send a J1939 Request for a PGN and show the answer";
constexpr const char* REQUEST_FOOTER =
    "Sends a J1939 Request (PGN 59904, 0xEA00; 3 bytes, the PGN least significant byte\n"
    "first) for PGN to address ADDR (--to; 255 = global) on bus --bus (default: the\n"
    "configuration's only bus) through vcu-can-tx (the bus's send stream, as 'vcu send'),\n"
    "from the VCU's address: --from, else the claimed address in vcu-can-tx's J1939 view\n"
    "of the bus (listened to for up to 1.2 s), else the bus's j1939.preferredAddress, else\n"
    "the NmStationAddress of the configuration's node in the DBC. PGN and addresses:\n"
    "decimal or 0x hex.\n"
    "It then listens to the frames vcu-can-rx received on that bus (rx stream, subscribed\n"
    "before the request goes out) for --timeout seconds (default 2) and prints:\n"
    "- a frame of that PGN from ADDR, or a transport-protocol transfer of it (BAM, or\n"
    "  RTS/CTS to the VCU: vcu-can-rx does the handshake, the tool reassembles passively),\n"
    "  as hex bytes, then decoded: DM1/DM2 (lamps, DTCs), the identification PGNs 65242,\n"
    "  64965 and 65259 (fields split at '*'), else the DBC message of that PGN;\n"
    "- an Acknowledgement (PGN 59392, 0xE800) from ADDR naming the PGN: ACK, NACK, access\n"
    "  denied or cannot respond.\n"
    "A request to ADDR ends at the first answer; a global request prints every answer\n"
    "that arrives within --timeout.\n"
    "Needs iox-roudi, vcu-can-tx and vcu-can-rx; registers as vcu-j1939-<pid>.\n"
    "\n"
    "Examples:\n"
    "  vcu j1939 request 65242 --to 0x21\n"
    "  vcu j1939 request 0xFECA --to 255 --bus vehicle --timeout 1\n"
    "Exit: 0 data or an ACK arrived, 1 no answer within --timeout, a NACK (or access\n"
    "denied, cannot respond), nobody listening on the send stream, configuration error;\n"
    "2 usage error (a bad PGN or address).\n";

std::string pgnText(std::uint32_t pgn) {
  std::array<char, 32> text{};
  std::snprintf(text.data(), text.size(), "PGN 0x%05X (%u)", static_cast<unsigned>(pgn), static_cast<unsigned>(pgn));
  return text.data();
}

std::string hexBytes(std::span<const std::uint8_t> data) {
  std::string text;
  text.reserve(data.size() * 3);
  std::array<char, 4> byte{};
  for (const std::uint8_t value : data) {
    std::snprintf(byte.data(), byte.size(), "%02X", static_cast<unsigned>(value));
    if (!text.empty()) text += ' ';
    text += byte.data();
  }
  return text;
}

/// "0x21 (33) BMS" or "0x21 (33)".
std::string addressText(const config::VehicleConfig& config, std::uint8_t address) {
  const std::string node = dbcNodeAt(config, address);
  return formatJ1939Address(address) + (node.empty() ? "" : " " + node);
}

/// The identification fields of `data` split at '*' as quoted text (non-printable bytes as
/// \xNN); text after the last '*' is a field too when not empty.
std::vector<std::string> identificationFields(std::span<const std::uint8_t> data) {
  std::vector<std::string> fields;
  std::string field = "\"";
  bool open = false;
  for (const std::uint8_t byte : data) {
    if (byte == static_cast<std::uint8_t>(IDENTIFICATION_DELIMITER)) {
      fields.push_back(field + "\"");
      field = "\"";
      open = false;
      continue;
    }
    open = true;
    if (byte >= 0x20 && byte < 0x7F && byte != '"' && byte != '\\') {
      field += static_cast<char>(byte);
    } else {
      std::array<char, 8> escaped{};
      std::snprintf(escaped.data(), escaped.size(), "\\x%02X", static_cast<unsigned>(byte));
      field += escaped.data();
    }
  }
  if (open) fields.push_back(field + "\"");
  return fields;
}

void appendNamedFields(std::string& out, const std::vector<std::string>& fields,
                       std::initializer_list<const char*> names) {
  std::size_t i = 0;
  for (const char* name : names) {
    if (i >= fields.size()) break;
    out += (i == 0 ? " " : ", ") + std::string(name) + " " + fields[i];
    ++i;
  }
  for (; i < fields.size(); ++i) out += ", field " + std::to_string(i + 1) + " " + fields[i];
}

/// Decodes answers: DM1/DM2, identification, else the DBC message of the PGN.
class AnswerDecoder {
 public:
  explicit AnswerDecoder(const dbc::Database& database)
      : m_database(database), m_matcher(database, dbc::MatchMode::J1939), m_codecs(database) {}

  /// The decoded lines (each starting with two spaces and ending with '\n'); empty when
  /// the PGN is none of those.
  std::string decode(std::uint32_t canId, std::uint32_t pgn, std::span<const std::uint8_t> data) const {
    std::string out;
    if (pgn == j1939::PGN_DM1 || pgn == j1939::PGN_DM2) {
      appendDm(out, pgn, data);
    } else if (pgn == PGN_SOFTWARE_ID && !data.empty()) {
      const auto fields = identificationFields(data.subspan(1));
      out += "  software identification (" + std::to_string(data[0]) + " field" + (data[0] == 1 ? "" : "s") + "):";
      for (std::size_t i = 0; i < fields.size(); ++i) out += (i == 0 ? " " : ", ") + fields[i];
      out += '\n';
    } else if (pgn == PGN_ECU_ID) {
      out += "  ECU identification:";
      appendNamedFields(out, identificationFields(data),
                        {"part number", "serial number", "location", "type", "manufacturer", "hardware ID"});
      out += '\n';
    } else if (pgn == PGN_COMPONENT_ID) {
      out += "  component identification:";
      appendNamedFields(out, identificationFields(data), {"make", "model", "serial number", "unit number"});
      out += '\n';
    } else {
      appendDbc(out, canId, data);
    }
    return out;
  }

 private:
  static void appendDm(std::string& out, std::uint32_t pgn, std::span<const std::uint8_t> data) {
    const char* which = pgn == j1939::PGN_DM1 ? "DM1" : "DM2";
    const std::optional<j1939::Dm1> maybeDm = j1939::decodeDm1(data);
    if (!maybeDm) {
      out += std::string("  ") + which + ": not a valid message (" + std::to_string(data.size()) + " bytes)\n";
      return;
    }
    const j1939::LampStates& lamps = maybeDm->lamps;
    out += std::string("  ") + which + ": lamps protect " + std::string(j1939::lampStatusName(lamps.protect)) +
           ", amber warning " + std::string(j1939::lampStatusName(lamps.amberWarning)) + ", red stop " +
           std::string(j1939::lampStatusName(lamps.redStop)) + ", malfunction " +
           std::string(j1939::lampStatusName(lamps.malfunction)) + "; " + std::to_string(maybeDm->dtcCount) +
           (maybeDm->dtcCount == 1 ? " DTC\n" : " DTCs\n");
    for (const j1939::Dtc& dtc : maybeDm->activeDtcs()) {
      out += "    SPN " + std::to_string(dtc.spn) + " FMI " + std::to_string(dtc.fmi) + " occurrences " +
             (dtc.occurrenceCount == j1939::DTC_MAX_OCCURRENCE_COUNT ? std::string("n/a")
                                                                     : std::to_string(dtc.occurrenceCount)) +
             "\n";
    }
  }

  void appendDbc(std::string& out, std::uint32_t canId, std::span<const std::uint8_t> data) const {
    const std::int32_t match = m_matcher.match(canId, true);
    if (match == dbc::MessageMatcher::NO_MATCH) return;
    const auto index = static_cast<std::size_t>(match);
    const dbc::Message& message = m_database.messages[index];
    out += "  " + message.displayName + ":";
    std::size_t decoded = 0;
    m_codecs[index].decode(data, [&](std::uint32_t signalIndex, const dbc::DecodedValue& value) {
      const dbc::Signal& signal = message.signals[signalIndex];
      out += decoded++ == 0 ? " " : ", ";
      out += signal.displayName + "=";
      appendNumber(out, value.physical, false);
      const std::string* valueText = nullptr;
      if (value.kind == dbc::RawKind::Unsigned)
        valueText = signal.describe(static_cast<std::int64_t>(value.rawUnsigned));
      if (value.kind == dbc::RawKind::Signed) valueText = signal.describe(value.rawSigned);
      if (valueText != nullptr) {
        out += " \"" + *valueText + "\"";
      } else if (!signal.unit.empty()) {
        out += " " + signal.unit;
      }
    });
    if (decoded == 0) out += " no signal in the received bytes";
    out += '\n';
  }

  const dbc::Database& m_database;
  dbc::MessageMatcher m_matcher;
  dbc::DatabaseCodec m_codecs;
};

/// Keeps the transfers the receiver completes; its CTS and EndOfMsgAck are dropped:
/// vcu-can-rx answers on the bus, the tool only listens.
class PassiveTpSink final : public j1939::TpSink {
 public:
  struct Message {
    std::uint32_t pgn{};
    std::uint8_t source{};
    std::uint8_t destination{};
    bool broadcast{};
    std::vector<std::uint8_t> data;
  };
  void send(const j1939::TpFrame& /*frame*/) noexcept override {}
  void completed(const j1939::TpMessage& message) noexcept override {
    try {
      m_completed.push_back(Message{message.pgn, message.source, message.destination, message.broadcast,
                                    std::vector<std::uint8_t>(message.data.begin(), message.data.end())});
    } catch (...) {  // out of memory: the transfer is lost, as if it never completed
    }
  }
  void event(const j1939::TpEvent& /*event*/) noexcept override {}
  std::vector<Message>& completedMessages() noexcept { return m_completed; }

 private:
  std::vector<Message> m_completed;
};

/// The VCU's claimed address on `bus` from vcu-can-tx's J1939 view, if one arrives in time.
std::optional<std::uint8_t> addressFromView(const config::VehicleConfig& config, const std::string& bus) {
  auto eventsResult = ipc::EventBus::open(config.lcmUrl, config.instance);
  if (!eventsResult) return std::nullopt;
  std::optional<std::uint8_t> address;
  auto subscribed = eventsResult->onJ1939Network([&](const ipc::J1939Network& network) {
    if (network.bus == bus && network.claimState == ipc::ClaimState::Claimed) address = network.address;
  });
  if (!subscribed) return std::nullopt;
  const auto deadline = std::chrono::steady_clock::now() + VIEW_WAIT;
  while (!address) {
    const auto left = std::chrono::ceil<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0 || eventsResult->handle(left) == ipc::HandleResult::Failed) break;
  }
  return address;
}

std::optional<std::uint8_t> nodeAddressOf(const config::VehicleConfig& config) {
  for (const dbc::Node& node : config.database.nodes) {
    if (node.name == config.node) return config::nodeAddress(config.database, node);
  }
  return std::nullopt;
}

}  // namespace

ExitCode runJ1939Request(const J1939RequestOptions& options, Streams streams) {
  const std::optional<std::uint32_t> maybePgn = parsePgn(options.pgn);
  if (!maybePgn) {
    reportError(streams.err, "PGN '" + options.pgn + "': not a PGN (0..262143 or 0x0..0x3FFFF)");
    return ExitCode::Usage;
  }
  const std::optional<std::uint8_t> maybeTo = parseJ1939Address(options.to);
  if (!maybeTo) {
    reportError(streams.err, "--to '" + options.to + "': not a J1939 address (0..255 or 0x00..0xFF; 255 = global)");
    return ExitCode::Usage;
  }
  std::optional<std::uint8_t> maybeFrom;
  if (!options.from.empty()) {
    maybeFrom = parseJ1939Address(options.from);
    if (!maybeFrom || *maybeFrom >= j1939::NULL_ADDRESS) {
      reportError(streams.err, "--from '" + options.from + "': not a source address (0..253 or 0x00..0xFD)");
      return ExitCode::Usage;
    }
  }
  const std::uint32_t pgn = *maybePgn;
  const std::uint8_t to = *maybeTo;
  const bool global = to == j1939::GLOBAL_ADDRESS;

  ExitCode exitCode = ExitCode::Ok;
  const auto maybeStack = loadStack(options.stack, streams.err, &exitCode);
  if (!maybeStack) return exitCode;
  const config::VehicleConfig& config = maybeStack->config;
  const config::BusConfig* bus = nullptr;
  if (options.bus.empty()) {
    if (config.buses.size() != 1) {
      reportError(streams.err,
                  config.path + " has " + std::to_string(config.buses.size()) + " buses: name one with --bus");
      return ExitCode::Usage;
    }
    bus = &config.buses.front();
  } else {
    bus = findJ1939Bus(config, options.bus, streams.err);
    if (bus == nullptr) return ExitCode::Failure;
  }
  if (!maybeFrom) maybeFrom = addressFromView(config, bus->name);
  if (!maybeFrom && bus->j1939) maybeFrom = bus->j1939->preferredAddress;
  if (!maybeFrom) maybeFrom = nodeAddressOf(config);
  if (!maybeFrom) {
    reportError(streams.err, "no source address: vcu-can-tx's J1939 view of bus '" + bus->name +
                                 "' names no claimed address, the bus has no \"j1939\" object and DBC node '" +
                                 config.node + "' has no NmStationAddress; give --from");
    return ExitCode::Failure;
  }
  const std::uint8_t from = *maybeFrom;

  if (const Status initResult = ipc::Runtime::init("vcu-j1939-" + std::to_string(::getpid())); !initResult) {
    reportError(streams.err, initResult.error().message);
    return ExitCode::Failure;
  }
  // The rx subscription first: RouDi connects a new subscription in its first discovery
  // pass, and can-tx's subscription to the send publisher below takes at least that pass,
  // so once can-tx is connected this subscription is too and sees the answer.
  const ipc::FrameTopic rxTopic{config.instance, bus->name, ipc::FrameStream::Received};
  auto subscriberResult = ipc::FrameSubscriber::create(rxTopic);
  if (!subscriberResult) {
    reportError(streams.err, subscriberResult.error().message);
    return ExitCode::Failure;
  }
  ipc::FrameSubscriber& subscriber = *subscriberResult;
  const ipc::FrameTopic sendTopic{config.instance, bus->name, ipc::FrameStream::SendRequest};
  auto publisherResult = ipc::FramePublisher::create(sendTopic);
  if (!publisherResult) {
    reportError(streams.err, publisherResult.error().message);
    return ExitCode::Failure;
  }
  auto waiterResult = ipc::Waiter::create();
  if (!waiterResult) {
    reportError(streams.err, waiterResult.error().message);
    return ExitCode::Failure;
  }
  ipc::Waiter& waiter = *waiterResult;
  if (const Status attached = waiter.attach(subscriber, 0); !attached) {
    reportError(streams.err, attached.error().message);
    return ExitCode::Failure;
  }
  if (!publisherResult->waitForSubscribers(CAN_TX_CONNECT_TIMEOUT)) {
    reportError(streams.err, "nothing sent: nobody listens on " + sendTopic.toString() + " (is vcu-can-tx running?)");
    return ExitCode::Failure;
  }
  auto receiveConfig = config::loadReceiveConfig(config);
  j1939::TpReceiverConfig tpConfig;
  tpConfig.ownAddress = from;  // RTS/CTS sessions to the VCU: the windows can-rx grants
  if (receiveConfig) tpConfig.maxPacketsPerCts = receiveConfig->maxPacketsPerCts;
  j1939::TpReceiver transport(tpConfig);
  PassiveTpSink tpSink;
  const AnswerDecoder decoder(config.database);

  const j1939::RequestFrame request = j1939::buildRequest(pgn, j1939::REQUEST_DEFAULT_PRIORITY, from, to);
  ipc::FrameSample sample{};
  sample.busIndex = static_cast<std::uint16_t>(bus - config.buses.data());
  sample.frame.id = request.canId;
  sample.frame.flags = can::FLAG_EXTENDED;
  sample.frame.length = static_cast<std::uint8_t>(request.payload.size());
  std::copy(request.payload.begin(), request.payload.end(), sample.frame.data.begin());
  if (!publisherResult->publish(sample)) {
    reportError(streams.err, "nothing sent: no room on " + sendTopic.toString() + " (mempool exhausted)");
    return ExitCode::Failure;
  }
  const std::string requestText = pgnText(pgn) + " to " + (global ? std::string("global") : addressText(config, to)) +
                                  " from " + formatJ1939Address(from);
  streams.err.write("requested " + requestText + " on bus " + bus->name + "\n");
  streams.err.flush();

  const auto fromPeer = [&](std::uint8_t source) { return global || source == to; };
  std::size_t dataAnswers = 0;
  std::size_t negativeAnswers = 0;
  std::size_t answers = 0;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration_cast<std::chrono::nanoseconds>(
                                                               std::chrono::duration<double>(options.timeoutSeconds));
  while (global || answers == 0) {
    const auto left = deadline - std::chrono::steady_clock::now();
    if (left <= std::chrono::nanoseconds::zero()) break;
    if (waiter.waitFor(std::chrono::duration_cast<std::chrono::nanoseconds>(left)).empty()) continue;
    std::string out;
    while (global || answers == 0) {
      const std::optional<ipc::FrameSample> maybeSample = subscriber.take();
      if (!maybeSample) break;
      const can::Frame& frame = maybeSample->frame;
      if (!frame.extended() || (frame.flags & (can::FLAG_ERROR | can::FLAG_RTR)) != 0) continue;
      const j1939::Id id = j1939::Id::fromCanId(frame.id);
      if (id.pgn() == pgn && fromPeer(id.sourceAddress)) {
        out += pgnText(pgn) + " from " + addressText(config, id.sourceAddress) + ", " + std::to_string(frame.length) +
               " bytes: " + hexBytes(frame.payload()) + "\n";
        out += decoder.decode(frame.id, pgn, frame.payload());
        ++dataAnswers;
        ++answers;
        continue;
      }
      if (id.pgn() == j1939::PGN_ACKNOWLEDGEMENT && fromPeer(id.sourceAddress)) {
        const auto maybeAck = j1939::decodeAcknowledgement(frame.payload());
        if (maybeAck && maybeAck->pgn == pgn) {
          static constexpr std::array<const char*, 4> ACK_TEXT{"ACK", "NACK", "Access denied", "Cannot respond"};
          out += std::string(ACK_TEXT[static_cast<std::size_t>(maybeAck->control)]) + " from " +
                 addressText(config, id.sourceAddress) + " for " + pgnText(pgn) + "\n";
          if (maybeAck->control != j1939::AckControl::Positive) ++negativeAnswers;
          ++answers;
          continue;
        }
      }
      transport.onFrame(frame.id, frame.payload(), maybeSample->monotonicNs, tpSink);
      for (const PassiveTpSink::Message& message : tpSink.completedMessages()) {
        if (message.pgn != pgn || !fromPeer(message.source)) continue;
        out += pgnText(pgn) + " from " + addressText(config, message.source) + ", " +
               std::to_string(message.data.size()) + " bytes by " + (message.broadcast ? "BAM" : "RTS/CTS") + ": " +
               hexBytes(message.data) + "\n";
        out += decoder.decode(
            j1939::Id::fromPgn(pgn, j1939::REQUEST_DEFAULT_PRIORITY, message.source, message.destination).toCanId(),
            pgn, message.data);
        ++dataAnswers;
        ++answers;
      }
      tpSink.completedMessages().clear();
    }
    if (!out.empty()) {
      streams.out.write(out);
      if (!streams.out.flush()) return ExitCode::Failure;
    }
  }
  if (answers == 0) {
    reportError(streams.err, "no answer to the request for " + requestText + " within " +
                                 formatNumber(options.timeoutSeconds) + " s on " + rxTopic.toString() +
                                 " (is vcu-can-rx running, is there a node at that address?)");
    return ExitCode::Failure;
  }
  return dataAnswers > 0 || negativeAnswers == 0 ? ExitCode::Ok : ExitCode::Failure;
}

void addJ1939Request(CLI::App& j1939, CommandContext& context) {
  auto options = std::make_shared<J1939RequestOptions>();
  CLI::App* request = j1939.add_subcommand("request", REQUEST_DESCRIPTION);
  request->footer(REQUEST_FOOTER);
  request->add_option("PGN", options->pgn, "the PGN to request, decimal or 0x hex")->required()->type_name("");
  request->add_option("--to", options->to, "destination address, 0..255 (255 = global)")
      ->required()
      ->option_text("ADDR");
  request->add_option("-b,--bus", options->bus, "bus name (default: the only bus)")->option_text("BUS");
  request->add_option("--from", options->from, "source address (default: the VCU's)")->option_text("SA");
  request->add_option("--timeout", options->timeoutSeconds, "seconds to wait for the answer (default 2)")
      ->check(CLI::PositiveNumber)
      ->option_text("SECONDS");
  addStackOptions(*request, options->stack);
  request->callback([options, &context] { context.exitCode = runJ1939Request(*options, context.streams); });
}

}  // namespace openvcu::cli
