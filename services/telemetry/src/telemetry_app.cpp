#include "telemetry_app.hpp"

#include <openssl/evp.h>

#include <array>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "disk_queue.hpp"
#include "engine.hpp"
#include "openvcu/config/telemetry.hpp"
#include "openvcu/core/clock.hpp"
#include "openvcu/service/timer.hpp"
#include "remote_commands.hpp"
#include "sender.hpp"

namespace openvcu::telemetry {
namespace {

using Json = nlohmann::json;
namespace fs = std::filesystem;

constexpr std::chrono::milliseconds PUMP_PERIOD{10};
constexpr std::chrono::seconds TICK_PERIOD{1};

ClockPair readClocks() {
  return ClockPair{.monoNs = clock::monotonicNs(), .unixMs = clock::realtimeNs() / 1'000'000};
}

}  // namespace

Result<std::string> hashFiles(const std::vector<std::string>& files) {
  EVP_MD_CTX* context = EVP_MD_CTX_new();
  if (context == nullptr || EVP_DigestInit_ex(context, EVP_sha256(), nullptr) != 1) {
    EVP_MD_CTX_free(context);
    return Error{"SHA-256 is not available"};
  }
  for (const std::string& file : files) {
    std::ifstream in(file, std::ios::binary);
    std::ostringstream text;
    text << in.rdbuf();
    if (!in) {
      EVP_MD_CTX_free(context);
      return Error{file + ": cannot read it for the configuration hash"};
    }
    const std::string name = fs::path(file).filename().string() + '\n';
    const std::string bytes = text.str();
    EVP_DigestUpdate(context, name.data(), name.size());
    EVP_DigestUpdate(context, bytes.data(), bytes.size());
  }
  std::array<unsigned char, EVP_MAX_MD_SIZE> digest{};
  unsigned int length = 0;
  EVP_DigestFinal_ex(context, digest.data(), &length);
  EVP_MD_CTX_free(context);
  static constexpr char HEX[] = "0123456789abcdef";
  std::string out = "sha256:";
  for (unsigned int i = 0; i < length; ++i) {
    out += HEX[digest[i] >> 4];
    out += HEX[digest[i] & 0xF];
  }
  return out;
}

struct TelemetryAppImpl {
  service::Service& runtime;
  config::TelemetryConfig settings;
  DiskQueue queue;
  Engine engine;
  std::unique_ptr<Sender> sender;
  std::unique_ptr<RemoteCommands> remoteCommands;  ///< with remoteCommands.enabled only
  std::string birthBase;  ///< the birth's members but nextSeq and t
  std::vector<ipc::Subscription> subscriptions;
  std::optional<service::PeriodicTimer> pumpTimer;
  std::optional<service::PeriodicTimer> tickTimer;
  service::CounterRef queuedCounter;
  service::CounterRef pendingCounter;
  service::CounterRef droppedCounter;
  service::CounterRef connectsCounter;
  service::CounterRef refusedCounter;
  std::uint64_t queued{0};
  bool queueFailed{false};
  bool wakeWatched{false};  ///< the loop watches sender->wakeFd()

  TelemetryAppImpl(service::Service& service, config::TelemetryConfig telemetrySettings, DiskQueue diskQueue,
                   Engine telemetryEngine)
      : runtime(service),
        settings(std::move(telemetrySettings)),
        queue(std::move(diskQueue)),
        engine(std::move(telemetryEngine)) {}

  ~TelemetryAppImpl() {
    if (wakeWatched) runtime.loop().removeFd(sender->wakeFd());
    for (const ipc::Subscription subscription : subscriptions) runtime.events().unsubscribe(subscription);
  }

  std::string birth(const ClockPair& clocks) const {
    return "{" + birthBase + ",\"nextSeq\":" + std::to_string(queue.stats().nextSequence) +
           ",\"t\":" + std::to_string(clocks.unixMs) + "}";
  }

  void pump() {
    if (remoteCommands) takeCommands();
    if (auto pumped = sender->pump(queue); !pumped && !queueFailed) {
      queueFailed = true;  // logged once; the service goes on (the link side may still recover)
      runtime.log().error("telemetry: " + pumped.error().toString());
    }
  }

  /// Remote commands from the broker to their checks; their answers into the queue at once (one batch).
  void takeCommands() {
    const ClockPair clocks = readClocks();
    for (const InboundMessage& message : sender->takeMessages()) remoteCommands->onMessage(message, clocks);
    const std::uint64_t first = queue.stats().nextSequence;
    const std::vector<std::string> records = remoteCommands->takeRecords(first, clocks);
    if (records.empty()) return;
    std::vector<std::string_view> views(records.begin(), records.end());
    if (auto appended = queue.appendBatch(views); !appended || *appended != first) {
      runtime.log().error("telemetry queue: remote command answers lost: " +
                          (appended ? "numbered from " + std::to_string(*appended) : appended.error().toString()));
      return;
    }
    queued += records.size();
  }

  void tick() {
    const ClockPair clocks = readClocks();
    engine.sample(clocks.monoNs);
    TickInputs inputs{.clocks = clocks, .queue = queue.stats(), .drops = queue.takeDrops(), .link = sender->counters()};
    for (const QueueDrop& drop : inputs.drops) {
      runtime.log().warning("telemetry queue full: dropped records " + std::to_string(drop.firstSequence) + ".." +
                            std::to_string(drop.lastSequence) + " before the broker confirmed them");
    }
    const std::uint64_t first = inputs.queue.nextSequence;
    const std::vector<std::string> records = engine.tick(first, inputs);
    if (!records.empty()) {
      std::vector<std::string_view> views(records.begin(), records.end());
      auto appended = queue.appendBatch(views);
      if (!appended) {
        runtime.log().error("telemetry queue: " + appended.error().toString() + " (this tick's records are lost)");
      } else if (*appended != first) {
        runtime.log().error("telemetry queue numbered the batch from " + std::to_string(*appended) + ", not " +
                            std::to_string(first) + " (the messages carry the wrong seq)");
      } else {
        queued += records.size();
      }
    }
    sender->setBirth(birth(clocks));
    pump();
    const QueueStats stats = queue.stats();
    const LinkCounters link = sender->counters();
    queuedCounter.set(static_cast<std::int64_t>(queued));
    pendingCounter.set(static_cast<std::int64_t>(stats.pendingRecords));
    droppedCounter.set(static_cast<std::int64_t>(stats.droppedRecords));
    connectsCounter.set(static_cast<std::int64_t>(link.connects));
    refusedCounter.set(static_cast<std::int64_t>(link.refused));
    runtime.setStatus(sender->connected() ? "ok" : "broker not connected; " + std::to_string(stats.pendingRecords) +
                                                     " record(s) waiting");
  }

  Status subscribe() {
    ipc::EventBus& events = runtime.events();
    auto heartbeat = events.onHeartbeat(
        [this](const ipc::Heartbeat& beat) { engine.onHeartbeat(beat, clock::monotonicNs()); });
    if (!heartbeat) return heartbeat.error();
    subscriptions.push_back(*heartbeat);
    auto fault = events.onFault([this](const ipc::FaultEvent& event) { engine.onFault(event); });
    if (!fault) return fault.error();
    subscriptions.push_back(*fault);
    auto transition = events.onFsmTransition([this](const ipc::FsmTransition& event) { engine.onTransition(event); });
    if (!transition) return transition.error();
    subscriptions.push_back(*transition);
    auto dm1 = events.onNodeDm1([this](const ipc::NodeDm1& event) { engine.onDm1(event); });
    if (!dm1) return dm1.error();
    subscriptions.push_back(*dm1);
    return {};
  }

  Status startTimers() {
    queuedCounter = runtime.addCounter("records_queued");
    pendingCounter = runtime.addCounter("records_pending");
    droppedCounter = runtime.addCounter("records_dropped");
    connectsCounter = runtime.addCounter("broker_connects");
    refusedCounter = runtime.addCounter("broker_refused");
    auto pumpResult = service::PeriodicTimer::create(PUMP_PERIOD);
    if (!pumpResult) return pumpResult.error();
    pumpTimer.emplace(std::move(*pumpResult));
    auto tickResult = service::PeriodicTimer::create(TICK_PERIOD);
    if (!tickResult) return tickResult.error();
    tickTimer.emplace(std::move(*tickResult));
    if (auto added = runtime.loop().addTimer(*pumpTimer, [this](const service::TimerTick&) {
          engine.sample(clock::monotonicNs());
          pump();
        });
        !added) {
      return added.error();
    }
    if (auto added = runtime.loop().addTimer(*tickTimer, [this](const service::TimerTick&) { tick(); }); !added) {
      return added.error();
    }
    // the drain after an outage: pump() as soon as the broker confirmed half the window (or the
    // link came up), not only every PUMP_PERIOD
    if (auto added = runtime.loop().addFd(sender->wakeFd(), [this] { pump(); }); !added) return added.error();
    wakeWatched = true;
    return {};
  }
};

TelemetryApp::TelemetryApp(std::unique_ptr<TelemetryAppImpl> impl) : m_impl(std::move(impl)) {}
TelemetryApp::~TelemetryApp() = default;

Result<std::unique_ptr<TelemetryApp>> TelemetryApp::create(service::Service& runtime, const TelemetryOverrides& overrides) {
  const config::VehicleConfig& vehicle = runtime.config();
  if (vehicle.telemetryFile.empty()) {
    return Error{vehicle.path + ": names no \"telemetry\" file (telemetry.json: broker, vehicle id, signals)"};
  }
  std::vector<Error> warnings;
  auto loaded = config::loadTelemetryConfig(vehicle.telemetryFile, &warnings);
  if (!loaded) return loaded.error();
  config::TelemetryConfig settings = std::move(*loaded);
  for (const Error& warning : warnings) runtime.log().warning(warning.toString());
  if (!overrides.queueFolder.empty()) settings.queueFolder = overrides.queueFolder;
  if (!overrides.vehicleId.empty()) {
    if (!config::isValidVehicleId(overrides.vehicleId)) {
      return Error{"--vehicle-id '" + overrides.vehicleId + "': 1-64 of A-Z a-z 0-9 - _"};
    }
    settings.vehicleId = overrides.vehicleId;
  }
  if (!overrides.broker.empty()) {
    auto broker = config::parseBrokerUrl(overrides.broker);
    if (!broker) return Error{"--broker " + broker.error().message};
    if (broker->tls != settings.broker.tls) return Error{"--broker: the scheme must stay the file's (TLS settings)"};
    settings.broker = *broker;
    settings.brokerUrl = overrides.broker;
  }

  std::vector<Error> queueWarnings;
  auto queue = DiskQueue::open({.folder = settings.queueFolder, .maxBytes = settings.maxQueueBytes}, &queueWarnings);
  if (!queue) return Error{"telemetry queue: " + queue.error().toString()};
  for (const Error& warning : queueWarnings) runtime.log().warning("telemetry queue: " + warning.toString());
  auto engine = Engine::create(settings, runtime.catalog(), runtime.table());
  if (!engine) return Error{vehicle.telemetryFile + ": " + engine.error().message};

  SenderOptions senderOptions;
  senderOptions.logInfo = [&runtime](const std::string& text) { runtime.log().info(text); };
  senderOptions.logWarning = [&runtime](const std::string& text) { runtime.log().warning(text); };
  auto sender = Sender::create(settings, std::move(senderOptions));
  if (!sender) return sender.error();

  // the birth: what this vehicle is (docs/design/telemetry.md, "Payloads")
  std::vector<std::string> files{vehicle.path};
  for (const std::string& file : vehicle.dbcFiles) files.push_back(file);
  for (const std::string* file : {&vehicle.fsmFile, &vehicle.scheduleFile, &vehicle.gpioFile, &vehicle.simulationFile,
                                  &vehicle.receiveFile, &vehicle.diagnosticsFile, &vehicle.webFile, &vehicle.telemetryFile}) {
    if (!file->empty()) files.push_back(*file);
  }
  auto configHash = hashFiles(files);
  if (!configHash) return configHash.error();
  Json dbc = Json::array();
  for (const std::string& file : vehicle.dbcFiles) {
    auto hash = hashFiles({file});
    if (!hash) return hash.error();
    dbc.push_back({{"file", fs::path(file).filename().string()}, {"hash", *hash}, {"version", vehicle.database.version}});
  }
  Json signalList = Json::array();
  for (const config::TelemetrySignal& signal : settings.signals) {
    const auto index = runtime.catalog().indexOf(signal.name);
    signalList.push_back({{"name", signal.name},
                          {"unit", index ? runtime.catalog()[*index].unit : std::string()},
                          {"maxRateHz", signal.maxRateHz},
                          {"deadband", signal.deadband}});
  }
  const Json birth = {{"v", 1},
                      {"vehicleId", settings.vehicleId},
                      {"instance", runtime.instance()},
                      {"software", OPENVCU_VERSION},
                      {"configHash", *configHash},
                      {"dbc", std::move(dbc)},
                      {"signals", std::move(signalList)},
                      {"commands", {{"enabled", settings.remoteCommandsEnabled}, {"keys", settings.remoteCommandKeys}}}};
  const std::string birthText = birth.dump();

  std::unique_ptr<RemoteCommands> remoteCommands;
  if (settings.remoteCommandsEnabled) {
    std::vector<Error> memoryWarnings;
    auto created = RemoteCommands::create(
        {.vehicleId = settings.vehicleId,
         .keys = settings.remoteCommandKeys,
         .stateFolder = settings.queueFolder,
         .catalog = &runtime.catalog(),
         .database = &vehicle.database,
         .send = [instance = runtime.instance()](const ipc::CommandRequest& request, std::chrono::nanoseconds timeout) {
           return commands::sendCommand(instance, request, timeout);
         },
         .logInfo = [&runtime](const std::string& text) { runtime.log().info(text); },
         .logWarning = [&runtime](const std::string& text) { runtime.log().warning(text); }},
        &memoryWarnings);
    for (const Error& warning : memoryWarnings) runtime.log().warning("remote commands: " + warning.toString());
    if (!created) return Error{vehicle.telemetryFile + ": " + created.error().message};
    remoteCommands = std::move(*created);
  }

  auto impl = std::make_unique<TelemetryAppImpl>(runtime, std::move(settings), std::move(*queue), std::move(*engine));
  impl->sender = std::move(*sender);
  impl->remoteCommands = std::move(remoteCommands);
  impl->birthBase = birthText.substr(1, birthText.size() - 2);
  impl->sender->setBirth(impl->birth(readClocks()));
  if (auto subscribed = impl->subscribe(); !subscribed) return subscribed.error();
  if (auto started = impl->startTimers(); !started) return started.error();
  if (auto started = impl->sender->start(); !started) return started.error();
  runtime.log().info("publishing vehicle '" + impl->settings.vehicleId + "' to " + impl->settings.brokerUrl +
                     "; queue " + impl->settings.queueFolder + " (" +
                     std::to_string(impl->queue.stats().pendingRecords) + " record(s) waiting)" +
                     (impl->remoteCommands ? "; remote commands on for " + std::to_string(impl->settings.remoteCommandKeys.size()) +
                                                 " key(s)"
                                           : ""));
  return std::unique_ptr<TelemetryApp>(new TelemetryApp(std::move(impl)));
}

}  // namespace openvcu::telemetry
