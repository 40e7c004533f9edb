#include "web_app.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <boost/asio/io_context.hpp>
#include <filesystem>
#include <mutex>
#include <nlohmann/json.hpp>
#include <thread>

#include "auth.hpp"
#include "http_server.hpp"
#include "live_state.hpp"
#include "openvcu/commands/command_check.hpp"
#include "openvcu/commands/command_sender.hpp"
#include "openvcu/commands/worker.hpp"
#include "openvcu/config/dashboard.hpp"
#include "openvcu/config/json.hpp"
#include "openvcu/config/web.hpp"
#include "openvcu/core/clock.hpp"
#include "openvcu/ipc/command_socket.hpp"
#include "openvcu/service/timer.hpp"
#include "recordings.hpp"
#include "same_origin.hpp"
#include "web_reports.hpp"

#ifndef OPENVCU_VERSION
#define OPENVCU_VERSION "0.0.0"
#endif
#ifndef OPENVCU_WEB_SOURCE_ROOT
#define OPENVCU_WEB_SOURCE_ROOT ""
#endif

namespace openvcu::web {
namespace {

using Json = nlohmann::json;
namespace fs = std::filesystem;

constexpr const char* SESSION_COOKIE = "vcu_session";
/// How long a command waits for its owner's answer (the request's deadline too).
constexpr std::chrono::seconds COMMAND_TIMEOUT{2};
constexpr std::size_t COMMAND_QUEUE = 16;
constexpr std::size_t FILE_QUEUE = 8;

/// The pages: --www, else the installed share/openvcu/www beside bin/, else the source tree's.
fs::path wwwRoot(const std::string& overridden) {
  if (!overridden.empty()) return overridden;
  std::error_code code;
  const fs::path self = fs::read_symlink("/proc/self/exe", code);
  if (!code) {
    const fs::path installed = self.parent_path().parent_path() / "share" / "openvcu" / "www";
    if (fs::is_regular_file(installed / "index.html", code)) return installed;
  }
  return OPENVCU_WEB_SOURCE_ROOT;
}

std::string sessionCookie(const std::string& token, std::int64_t maxAgeS) {
  return std::string(SESSION_COOKIE) + "=" + token +
         "; Path=/; HttpOnly; SameSite=Strict; Max-Age=" + std::to_string(maxAgeS);
}

/// The media type of the page's uploads (www/api.js postFile): a raw body, never a form.
constexpr std::string_view UPLOAD_MEDIA_TYPE = "application/octet-stream";

/// A JSON body of a POST: 415 for another media type, 400 for malformed JSON.
std::optional<Response> refuseBody(const Request& request, Json& out) {
  if (auto refused = refuseMediaType(request, "application/json")) return refused->response();
  auto parsed = config::parseJson(request.body, "");
  if (!parsed) return Response::error(400, config::bodyErrorText(parsed.error()));
  out = std::move(*parsed);
  if (!out.is_object()) return Response::error(400, "/: expected an object");
  return std::nullopt;
}

Json entriesJson(const std::vector<RecordingEntry>& entries) {
  Json list = Json::array();
  for (const RecordingEntry& entry : entries) {
    Json files = Json::array();
    for (const RecordedFile& file : entry.files) files.push_back({{"name", file.name}, {"bytes", file.bytes}});
    list.push_back({{"name", entry.name},
                    {"bytes", entry.bytes},
                    {"modifiedUnixMs", entry.modifiedUnixMs},
                    {"files", std::move(files)}});
  }
  return list;
}

/// "/api/recordings/drive1/report" with prefix "/api/recordings/" -> {"drive1", "report"}.
std::optional<std::pair<std::string, std::string>> nameAndAction(const std::string& path, std::string_view prefix) {
  const std::string rest = path.substr(prefix.size());
  const auto slash = rest.find('/');
  if (slash == std::string::npos || rest.find('/', slash + 1) != std::string::npos) return std::nullopt;
  return std::pair{rest.substr(0, slash), rest.substr(slash + 1)};
}

}  // namespace

struct WebAppImpl {
  service::Service& runtime;
  config::WebConfig settings;
  DataFolder data;
  LiveState live;
  HttpServer server;
  RequestGuard guard;
  Sessions sessions;
  std::mutex sessionsMutex;
  TraceReports reports;
  std::vector<ipc::Subscription> subscriptions;
  std::optional<service::PeriodicTimer> counterTimer;
  service::CounterRef requestsCounter;
  service::CounterRef streamsCounter;
  service::CounterRef eventsCounter;
  service::CounterRef commandsCounter;
  service::CounterRef refusedCounter;
  int auditFd{-1};
  // Workers last among the members that they use, first to go: no job outlives what it touches.
  commands::Worker commands{"web-commands", COMMAND_QUEUE};
  commands::Worker files{"web-files", FILE_QUEUE};
  std::thread ioThread;

  WebAppImpl(service::Service& service, config::WebConfig webSettings, LiveSetup liveSetup, ServerOptions options)
      : runtime(service),
        settings(std::move(webSettings)),
        data(settings.dataFolder),
        live(service.catalog(), service.table(), std::move(liveSetup)),
        server(std::move(options)),
        guard(settings.trustedOrigins),
        sessions(std::chrono::minutes(settings.sessionMinutes)),
        reports(service.config().path) {}

  ~WebAppImpl() {
    for (const ipc::Subscription subscription : subscriptions) runtime.events().unsubscribe(subscription);
    server.stop();
    if (ioThread.joinable()) ioThread.join();
    if (auditFd >= 0) ::close(auditFd);
  }

  /// The logged-in user of a request, empty when none.
  std::string userOf(const Request& request) {
    const std::string token = request.cookie(SESSION_COOKIE);
    if (token.empty()) return {};
    const std::lock_guard lock(sessionsMutex);
    const Session* session = sessions.find(token, Sessions::Clock::now());
    return session != nullptr ? session->user : std::string();
  }

  void audit(const std::string& user, const std::string& client, const std::string& what, bool accepted,
             const std::string& answer) {
    const Json line = {{"unixMs", clock::realtimeNs() / 1'000'000},
                       {"user", user},
                       {"client", client},
                       {"command", what},
                       {"accepted", accepted},
                       {"answer", answer}};
    const std::string text = line.dump() + "\n";
    if (auditFd >= 0 && ::write(auditFd, text.data(), text.size()) < 0) {
      runtime.log().warning("command log " + (data.root() / "web-commands.log").string() + ": write failed");
    }
  }

  /// A route that changes something: taken only from vcu-web's own pages (same origin).
  void postRoute(std::string path, Handler handler) {
    server.route(Method::Post, std::move(path),
                 [this, handler = std::move(handler)](const Request& request, const Responder& respond) {
                   if (auto refused = guard.refuseCrossOrigin(request)) {
                     runtime.log().warning("refused " + request.path + " from " + request.clientAddress + ": " +
                                           refused->message);
                     return respond(refused->response());
                   }
                   handler(request, respond);
                 });
  }

  void routes() {
    server.route(Method::Get, "/api/info", [this](const Request& request, const Responder& respond) {
      const std::string user = userOf(request);
      Json info = {{"instance", runtime.instance()},
                   {"vehicle", runtime.config().node},
                   {"version", OPENVCU_VERSION},
                   {"user", user.empty() ? Json(nullptr) : Json(user)},
                   {"loginAvailable", fs::exists(settings.usersFile)},
                   {"maxUpdatesPerSecond", settings.maxUpdatesPerSecond},
                   {"maxSignals", MAX_LIVE_SIGNALS},
                   {"maxPlotted", MAX_PLOTTED_SIGNALS},
                   {"fsmRules", live.rulesError()}};
      respond(Response::json(200, info.dump()));
    });
    server.route(Method::Get, "/api/catalog", [this](const Request&, const Responder& respond) {
      respond(Response::json(200, live.catalogJson()));
    });
    server.stream("/api/live", [this](const Request& request) {
      const auto it = request.query.find("signals");
      return live.openStream(it == request.query.end() ? std::string() : it->second);
    });
    postRoute("/api/login", [this](const Request& request, const Responder& respond) { login(request, respond); });
    postRoute("/api/logout", [this](const Request& request, const Responder& respond) {
      const std::string token = request.cookie(SESSION_COOKIE);
      if (userOf(request).empty()) return respond(Response::error(401, "not logged in"));
      {
        const std::lock_guard lock(sessionsMutex);
        sessions.logout(token);
      }
      Response response = Response::json(200, "{}");
      response.headers.emplace_back("Set-Cookie", sessionCookie("", 0));
      respond(std::move(response));
    });
    postRoute("/api/command", [this](const Request& request, const Responder& respond) { command(request, respond); });
    server.route(Method::Get, "/api/recordings", [this](const Request&, const Responder& respond) {
      const Json listing = {{"recordings", entriesJson(data.listRecordings())},
                            {"uploads", entriesJson(data.listUploads())}};
      respond(Response::json(200, listing.dump()));
    });
    server.route(Method::Get, "/api/recordings/",
                 [this](const Request& request, const Responder& respond) { fileAction(request, respond, true); });
    server.route(Method::Get, "/api/uploads/",
                 [this](const Request& request, const Responder& respond) { fileAction(request, respond, false); });
    server.upload("/api/uploads",
                  UploadRoute{.authorize = [this](const Request& request) -> std::optional<Response> {
                                if (auto refused = guard.refuseCrossOrigin(request)) {
                                  runtime.log().warning("refused an upload from " + request.clientAddress + ": " +
                                                        refused->message);
                                  return refused->response();
                                }
                                if (userOf(request).empty()) return Response::error(401, "log in to upload");
                                if (auto refused = refuseMediaType(request, UPLOAD_MEDIA_TYPE))
                                  return refused->response();
                                const auto name = request.query.find("name");
                                if (name == request.query.end() || name->second.empty())
                                  return Response::error(400, "?name=FILE is missing");
                                return std::nullopt;
                              },
                              .onComplete =
                                  [this](const Request& request, fs::path file, const Responder& respond) {
                                    auto accepted = data.acceptUpload(file, request.query.at("name"));
                                    if (!accepted) {
                                      std::error_code ignored;
                                      fs::remove(file, ignored);
                                      respond(Response::error(400, accepted.error().message));
                                      return;
                                    }
                                    runtime.log().info("upload '" + *accepted + "' by " + userOf(request) + " from " +
                                                       request.clientAddress);
                                    respond(Response::json(200, Json{{"name", *accepted}}.dump()));
                                  }});
  }

  void login(const Request& request, const Responder& respond) {
    Json body;
    if (auto refused = refuseBody(request, body)) return respond(std::move(*refused));
    const auto user = body.find("user");
    const auto password = body.find("password");
    if (user == body.end() || !user->is_string()) return respond(Response::error(400, "/user: expected a string"));
    if (password == body.end() || !password->is_string())
      return respond(Response::error(400, "/password: expected a string"));
    const bool queued = commands.submit([this, name = user->get<std::string>(), secret = password->get<std::string>(),
                                         client = request.clientAddress, respond] {
      auto users = UserFile::load(settings.usersFile);
      if (!users) {
        respond(Response::error(503, "logins are not available: " + users.error().toString() +
                                         " (vcu-web passwd --users FILE NAME creates it)"));
        return;
      }
      bool allowed = false;
      std::chrono::seconds retry{0};
      {
        const std::lock_guard lock(sessionsMutex);
        allowed = sessions.beginLogin(client, Sessions::Clock::now());
        if (!allowed) retry = sessions.retryAfter(client, Sessions::Clock::now());
      }
      if (!allowed) {
        runtime.log().warning("login refused for '" + name + "' from " + client + ": too many failed logins");
        Response response =
            Response::error(429, "too many failed logins; retry in " + std::to_string(retry.count()) + " s");
        response.headers.emplace_back("Retry-After", std::to_string(retry.count()));
        respond(std::move(response));
        return;
      }
      const bool passwordOk = Sessions::checkPassword(*users, name, secret);  // tens of ms: outside the lock
      std::optional<Session> session;
      {
        const std::lock_guard lock(sessionsMutex);
        session = sessions.completeLogin(name, passwordOk, client, Sessions::Clock::now());
      }
      if (!session) {
        runtime.log().warning("login refused for '" + name + "' from " + client);
        respond(Response::error(401, "wrong user or password"));
        return;
      }
      runtime.log().info("login: '" + session->user + "' from " + client);
      const std::int64_t lifetimeS = settings.sessionMinutes * 60;
      Response response = Response::json(200, Json{{"user", session->user}, {"expiresInS", lifetimeS}}.dump());
      response.headers.emplace_back("Set-Cookie", sessionCookie(session->token, lifetimeS));
      respond(std::move(response));
    });
    if (!queued) respond(Response::error(503, "busy: too many logins and commands waiting; try again"));
  }

  void command(const Request& request, const Responder& respond) {
    const std::string user = userOf(request);
    if (user.empty()) return respond(Response::error(401, "log in to command the VCU"));
    if (auto refused = refuseMediaType(request, "application/json")) return respond(refused->response());
    auto parsed = commands::parseCommand(request.body, runtime.catalog(), runtime.config().database);
    if (!parsed) return respond(Response::error(400, parsed.error().message));
    ipc::CommandRequest commandRequest = std::move(*parsed);
    commandRequest.issuer = "vcu-web/" + user;
    commandRequest.timestampNs = clock::realtimeNs();
    const std::string what = commands::describeCommand(commandRequest);
    const bool queued = commands.submit([this, commandRequest, user, what, client = request.clientAddress, respond] {
      const commands::CommandOutcome outcome =
          commands::sendCommand(runtime.instance(), commandRequest, COMMAND_TIMEOUT);
      const std::string verdict = outcome.verdict();
      audit(user, client, what, outcome.accepted(), verdict);
      switch (outcome.kind) {
        case commands::CommandOutcome::Kind::Answered:
          runtime.log().info("command by " + user + " from " + client + ": " + what + ": " + verdict);
          respond(Response::json(200, Json{{"accepted", outcome.ack.accepted},
                                           {"reason", outcome.ack.reason},
                                           {"responder", outcome.ack.responder},
                                           {"text", verdict}}
                                          .dump()));
          return;
        case commands::CommandOutcome::Kind::NotReachable:
          respond(Response::error(503, verdict));
          return;
        case commands::CommandOutcome::Kind::NotOwned:  // nobody owning the key is said at once
        case commands::CommandOutcome::Kind::NoAnswer:  // no answer in time is a timeout
          runtime.log().warning("command by " + user + " from " + client + ": " + what + ": " + verdict);
          respond(Response::error(outcome.kind == commands::CommandOutcome::Kind::NotOwned ? 409 : 504, verdict));
          return;
      }
    });
    if (!queued) respond(Response::error(503, "busy: too many commands waiting; try again"));
  }

  void fileAction(const Request& request, const Responder& respond, bool recording) {
    const auto parts = nameAndAction(request.path, recording ? "/api/recordings/" : "/api/uploads/");
    if (!parts) return respond(Response::error(404, "no such resource"));
    const auto& [name, action] = *parts;
    auto path = recording ? data.recording(name) : data.upload(name);
    if (!path) return respond(Response::error(404, path.error().message));
    if (action == "archive" && recording) {
      const bool queued = files.submit([this, name, respond] {
        auto archive = data.archiveRecording(name);
        if (!archive) return respond(Response::error(500, archive.error().message));
        Response response;
        response.contentType = "application/gzip";
        response.file = *archive;
        response.downloadName = name + ".tar.gz";
        response.deleteFileAfter = true;
        respond(std::move(response));
      });
      if (!queued) respond(Response::error(503, "busy: archives and reports are being made; try again"));
      return;
    }
    if (action != "report" && action != "summary") return respond(Response::error(404, "no such resource"));
    const bool queued = files.submit([this, target = path->string(), recording, report = action == "report", respond] {
      auto made = report ? reports.report(target, recording) : reports.summary(target, recording);
      if (!made) return respond(Response::error(422, made.error().message));
      Response response;
      response.contentType = report ? "text/html; charset=utf-8" : "application/json";
      response.body = std::move(*made);
      respond(std::move(response));
    });
    if (!queued) respond(Response::error(503, "busy: archives and reports are being made; try again"));
  }

  Status subscribe() {
    ipc::EventBus& events = runtime.events();
    auto heartbeat = events.onHeartbeat([this](const ipc::Heartbeat& beat) {
      const std::int64_t at = clock::monotonicNs();
      server.post([this, beat, at] { live.onHeartbeat(beat, at); });
    });
    if (!heartbeat) return heartbeat.error();
    subscriptions.push_back(*heartbeat);
    auto fault =
        events.onFault([this](const ipc::FaultEvent& event) { server.post([this, event] { live.onFault(event); }); });
    if (!fault) return fault.error();
    subscriptions.push_back(*fault);
    auto transition = events.onFsmTransition(
        [this](const ipc::FsmTransition& event) { server.post([this, event] { live.onTransition(event); }); });
    if (!transition) return transition.error();
    subscriptions.push_back(*transition);
    return {};
  }

  Status startCounters() {
    requestsCounter = runtime.addCounter("http_requests");
    streamsCounter = runtime.addCounter("live_pages");
    eventsCounter = runtime.addCounter("live_events_sent");
    refusedCounter = runtime.addCounter("http_refused");
    auto timer = service::PeriodicTimer::create(std::chrono::seconds(1));
    if (!timer) return timer.error();
    counterTimer.emplace(std::move(*timer));
    return runtime.loop().addTimer(*counterTimer, [this](const service::TimerTick&) {
      const ServerCounters counters = server.counters();
      requestsCounter.set(static_cast<std::int64_t>(counters.requests));
      streamsCounter.set(static_cast<std::int64_t>(counters.streams));
      eventsCounter.set(static_cast<std::int64_t>(counters.eventsSent));
      refusedCounter.set(static_cast<std::int64_t>(counters.refusedConnections + counters.rateLimited));
    });
  }
};

WebApp::WebApp(std::unique_ptr<WebAppImpl> impl) : m_impl(std::move(impl)) {}
WebApp::~WebApp() = default;

Result<std::unique_ptr<WebApp>> WebApp::create(service::Service& runtime, const WebOverrides& overrides) {
  const config::VehicleConfig& vehicle = runtime.config();
  config::WebConfig settings;
  if (!vehicle.webFile.empty()) {
    std::vector<Error> warnings;
    auto loaded = config::loadWebConfig(vehicle.webFile, &warnings);
    if (!loaded) return loaded.error();
    settings = std::move(*loaded);
    for (const Error& warning : warnings) runtime.log().warning(warning.toString());
  }
  if (!overrides.listen.empty()) {
    auto listen = config::parseListenAddress(overrides.listen);
    if (!listen) return Error{"--listen " + listen.error().message};
    settings.address = listen->first;
    settings.port = listen->second;
    if (!config::isLoopbackAddress(settings.address)) {
      runtime.log().warning("--listen " + overrides.listen + ": the VCU's pages are reachable from its network");
    }
  }
  if (!overrides.dataFolder.empty()) settings.dataFolder = overrides.dataFolder;
  if (!overrides.usersFile.empty()) settings.usersFile = overrides.usersFile;

  LiveSetup liveSetup{.socKey = {}, .fsmFile = vehicle.fsmFile};
  if (const std::string dashboard = config::dashboardBeside(vehicle.path); !dashboard.empty()) {
    if (auto loaded = config::loadDashboardConfig(dashboard, runtime.catalog())) {
      liveSetup.socKey = loaded->socKey;
      liveSetup.busStaleAfterNs = loaded->staleAfterMs * 1'000'000;
    } else {
      runtime.log().warning(loaded.error().toString() + " (the header shows no SOC)");
    }
  }
  DataFolder data(settings.dataFolder);
  if (auto prepared = data.prepare(); !prepared) return Error{"data folder: " + prepared.error().message};

  const fs::path www = wwwRoot(overrides.www);
  std::error_code code;
  if (!fs::is_regular_file(www / "index.html", code)) {
    return Error{"the pages: no index.html in '" + www.string() + "' (--www DIR)"};
  }
  ServerOptions options;
  options.address = settings.address;
  options.port = settings.port;
  options.staticRoot = www;
  options.uploadFolder = data.incomingFolder();
  options.maxUploadBytes = settings.maxUploadBytes;
  options.maxConnections = settings.maxConnections;
  options.maxStreams = settings.maxClients;
  options.maxUpdatesPerSecond = settings.maxUpdatesPerSecond;
  if (config::isLoopbackAddress(settings.address)) {
    // reachable through this host (or an SSH tunnel) only: by an address or "localhost", never by another name
    options.allowedHosts = {"localhost", "127.0.0.1", settings.address, "[::1]"};
  }

  auto impl = std::make_unique<WebAppImpl>(runtime, settings, std::move(liveSetup), std::move(options));
  impl->routes();
  if (auto started = impl->server.start(); !started) return started.error();
  const std::string audit = (data.root() / "web-commands.log").string();
  impl->auditFd = ::open(audit.c_str(), O_WRONLY | O_APPEND | O_CREAT | O_CLOEXEC, 0640);
  if (impl->auditFd < 0) return Error{audit + ": cannot open the command log for appending"};
  if (auto subscribed = impl->subscribe(); !subscribed) return subscribed.error();
  if (auto counters = impl->startCounters(); !counters) return counters.error();
  WebAppImpl* raw = impl.get();
  impl->ioThread = std::thread([raw] { raw->server.run(); });
  pthread_setname_np(impl->ioThread.native_handle(), "web-io");
  runtime.log().info("serving http://" + settings.address + ":" + std::to_string(impl->server.port()) + "/ (pages " +
                     www.string() + ", data " + settings.dataFolder + ", users " + settings.usersFile +
                     (fs::exists(settings.usersFile) ? "" : ": missing, the pages are read-only") + ")");
  runtime.setStatus("serving on " + settings.address + ":" + std::to_string(impl->server.port()));
  return std::unique_ptr<WebApp>(new WebApp(std::move(impl)));
}

}  // namespace openvcu::web
