#include "remote_commands.hpp"

#include <algorithm>
#include <nlohmann/json.hpp>
#include <variant>

#include "openvcu/commands/command_check.hpp"
#include "openvcu/config/json.hpp"
#include "openvcu/core/clock.hpp"
#include "openvcu/fleet/topics.hpp"

namespace openvcu::telemetry {
namespace {

using Json = nlohmann::json;

constexpr std::size_t MAX_CMD_ID = 64;

/// A cmdId names an answer topic: 1-64 of A-Z a-z 0-9 - _ . (no '/', '+', '#').
bool isValidCmdId(std::string_view id) {
  if (id.empty() || id.size() > MAX_CMD_ID) return false;
  return std::all_of(id.begin(), id.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' || c == '_' ||
           c == '.';
  });
}

std::string keyList(const std::vector<std::string>& keys) {
  std::string out;
  for (const std::string& key : keys) out += (out.empty() ? "" : ", ") + key;
  return out.empty() ? "none" : out;
}

/// A payload that passed the first checks: its object without deadlineUnixMs, and that deadline.
struct Envelope {
  Json body;
  std::int64_t deadlineUnixMs{};
};

/// The payload read as the configuration files are (config::parseJson: a key given twice at any
/// level, or a number beyond a double, is refused with its JSON path), then its deadline
/// checked; or the refusal reason.
std::variant<Envelope, std::string> readEnvelope(const std::string& payload, const ClockPair& now) {
  if (payload.size() > MAX_COMMAND_PAYLOAD) {
    return "the command has " + std::to_string(payload.size()) + " bytes, at most " +
           std::to_string(MAX_COMMAND_PAYLOAD);
  }
  auto parsed = config::parseJson(payload, "");
  if (!parsed) return config::bodyErrorText(parsed.error());
  Envelope envelope{.body = std::move(*parsed), .deadlineUnixMs = 0};
  Json& body = envelope.body;
  if (!body.is_object()) return std::string("/: expected an object {\"kind\", \"key\", \"value\", \"deadlineUnixMs\"}");
  const auto deadlineIt = body.find("deadlineUnixMs");
  if (deadlineIt == body.end() || !deadlineIt->is_number_integer()) {
    return std::string("/deadlineUnixMs: missing (Unix ms, at most 10 s ahead)");
  }
  envelope.deadlineUnixMs = deadlineIt->get<std::int64_t>();
  if (envelope.deadlineUnixMs <= now.unixMs) {
    return "/deadlineUnixMs: " + std::to_string(now.unixMs - envelope.deadlineUnixMs) + " ms in the past";
  }
  if (envelope.deadlineUnixMs - now.unixMs > MAX_DEADLINE_AHEAD_MS) {
    return "/deadlineUnixMs: " + std::to_string(envelope.deadlineUnixMs - now.unixMs) + " ms ahead, at most " +
           std::to_string(MAX_DEADLINE_AHEAD_MS);
  }
  body.erase("deadlineUnixMs");
  return envelope;
}

/// The key a command names, before the full check: kind faultReset names the FSM's reset switch.
std::string commandKey(const Json& body) {
  if (const auto kind = body.find("kind"); kind != body.end() && *kind == "faultReset") {
    return std::string(commands::FAULT_RESET_KEY);
  }
  if (const auto named = body.find("key"); named != body.end() && named->is_string()) return named->get<std::string>();
  return {};
}

}  // namespace

RemoteCommands::RemoteCommands(RemoteCommandsOptions options, ReplayGuard guard)
    : m_options(std::move(options)),
      m_topicPrefix(fleet::commandTopicPrefix(m_options.vehicleId)),
      m_guard(std::move(guard)) {}

RemoteCommands::~RemoteCommands() {
  m_worker.reset();
}

Result<std::unique_ptr<RemoteCommands>> RemoteCommands::create(RemoteCommandsOptions options,
                                                               std::vector<Error>* warnings) {
  if (options.catalog == nullptr || options.database == nullptr || !options.send || options.stateFolder.empty()) {
    return Error{"remote commands need the catalog, the DBC database, a send function and a state folder"};
  }
  for (std::size_t i = 0; i < options.keys.size(); ++i) {
    const std::string& key = options.keys[i];
    const dbc::Message* message = options.database->findMessage(key);
    if (!options.catalog->indexOf(key) && (message == nullptr || message->pseudo)) {
      return Error{"/remoteCommands/keys/" + std::to_string(i) + ": '" + key +
                   "' is neither a signal of this vehicle nor a DBC message"};
    }
  }
  auto guard = ReplayGuard::open(options.stateFolder, warnings);
  if (!guard) return Error{"remote commands' memory of received cmdIds: " + guard.error().toString()};
  std::unique_ptr<RemoteCommands> handler(new RemoteCommands(std::move(options), std::move(*guard)));
  handler->m_worker = std::make_unique<commands::Worker>("telemetry-cmd", MAX_WAITING_COMMANDS);
  return handler;
}

void RemoteCommands::refuse(const std::string& cmdId, std::string reason) {
  Answer answer{.cmdId = cmdId,
                .accepted = false,
                .reason = std::move(reason),
                .responder = std::string(LOCAL_RESPONDER),
                .what = {}};
  m_ready.push_back(std::move(answer));
}

std::optional<std::string> RemoteCommands::check(const std::string& key, const std::string& commandJson,
                                                 std::int64_t deadlineUnixMs, const ClockPair& now,
                                                 ipc::CommandRequest& request) const {
  if (std::find(m_options.keys.begin(), m_options.keys.end(), key) == m_options.keys.end()) {
    return "/key: '" + key + "' is not among telemetry.json's remoteCommands keys (" + keyList(m_options.keys) + ")";
  }
  auto parsed = commands::parseCommand(commandJson, *m_options.catalog, *m_options.database);
  if (!parsed) return parsed.error().message;
  request = std::move(*parsed);
  request.issuer = std::string(REMOTE_ISSUER);
  request.timestampNs = now.unixMs * 1'000'000;
  const std::int64_t waitMs = std::min(MAX_REQUEST_WAIT_MS, deadlineUnixMs - now.unixMs);
  request.deadlineNs = now.monoNs + waitMs * 1'000'000;
  return std::nullopt;
}

void RemoteCommands::onMessage(const InboundMessage& message, const ClockPair& now) {
  if (!message.topic.starts_with(m_topicPrefix)) {
    if (m_options.logWarning)
      m_options.logWarning("remote command on unexpected topic '" + message.topic + "' ignored");
    return;
  }
  const std::string cmdId = message.topic.substr(m_topicPrefix.size());
  if (!isValidCmdId(cmdId)) {  // no answer topic can be built from it
    if (m_options.logWarning) {
      m_options.logWarning("remote command on '" + message.topic +
                           "' ignored: the cmdId must be 1-64 of A-Z a-z 0-9 - _ . (no answer)");
    }
    return;
  }
  if (message.retained) {
    refuse(cmdId,
           "retained: a remote command must be published with retain off (a retained one would run again "
           "at every reconnect)");
    return;
  }
  auto envelope = readEnvelope(message.payload, now);
  if (auto* refusal = std::get_if<std::string>(&envelope)) return refuse(cmdId, std::move(*refusal));
  const Envelope& command = std::get<Envelope>(envelope);
  // remembered (on disk) before anything else can refuse it or send it: whatever its answer, it runs once at most
  if (auto replay = m_guard.admit(cmdId, command.deadlineUnixMs, now.unixMs)) {
    return refuse(cmdId, std::move(replay->reason));
  }
  ipc::CommandRequest request;
  if (auto refusal = check(commandKey(command.body), command.body.dump(), command.deadlineUnixMs, now, request)) {
    return refuse(cmdId, std::move(*refusal));
  }
  const std::string what = commands::describeCommand(request);
  const auto timeout = std::chrono::nanoseconds(request.deadlineNs - now.monoNs);
  const bool queued = m_worker->submit([this, request, timeout, cmdId, what] {
    commands::CommandOutcome outcome = m_options.send(request, timeout);
    const std::lock_guard lock(m_mutex);
    m_finished.push_back(Finished{.cmdId = cmdId, .what = what, .outcome = std::move(outcome)});
  });
  if (!queued) {
    return refuse(cmdId, "busy: " + std::to_string(MAX_WAITING_COMMANDS) + " remote commands are already waiting");
  }
  ++m_inFlight;
}

std::vector<std::string> RemoteCommands::takeRecords(std::uint64_t firstSequence, const ClockPair& now) {
  std::vector<Finished> finished;
  {
    const std::lock_guard lock(m_mutex);
    finished.swap(m_finished);
  }
  for (Finished& done : finished) {
    --m_inFlight;
    const commands::CommandOutcome& outcome = done.outcome;
    const bool answered = outcome.kind == commands::CommandOutcome::Kind::Answered;
    Answer answer{.cmdId = done.cmdId,
                  .accepted = outcome.accepted(),
                  .reason = answered ? outcome.ack.reason : outcome.verdict(),
                  .responder = answered ? outcome.ack.responder : std::string(LOCAL_RESPONDER),
                  .what = done.what};
    m_ready.push_back(std::move(answer));
  }
  std::vector<std::string> records;
  records.reserve(m_ready.size());
  for (const Answer& answer : m_ready) {
    const std::string verdict =
        answer.accepted ? "accepted by " + answer.responder : "refused by " + answer.responder + ": " + answer.reason;
    const std::string line =
        "remote command " + answer.cmdId + (answer.what.empty() ? "" : " (" + answer.what + ")") + ": " + verdict;
    const auto& sink = answer.accepted ? m_options.logInfo : m_options.logWarning;
    if (sink) sink(line);
    const nlohmann::ordered_json body = {{"v", 1},
                                         {"seq", firstSequence + records.size()},
                                         {"t", now.unixMs},
                                         {"cmdId", answer.cmdId},
                                         {"accepted", answer.accepted},
                                         {"reason", answer.reason},
                                         {"responder", answer.responder}};
    records.push_back(fleet::commandAnswerSuffix(answer.cmdId) + "\n" + body.dump());
  }
  m_ready.clear();
  return records;
}

}  // namespace openvcu::telemetry
