#include "sender.hpp"

#include <mosquitto.h>
#include <mqtt_protocol.h>

#include <sys/eventfd.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <string_view>

#include "openvcu/fleet/topics.hpp"

namespace openvcu::telemetry {
namespace {

constexpr int KEEPALIVE_S = 10;
/// The network thread's longest wait in mosquitto_loop (a publish from pump() wakes it at once).
constexpr int LOOP_TIMEOUT_MS = 500;
/// How long the destructor's DISCONNECT may take to go out before the network thread ends.
constexpr auto STOP_WAIT = std::chrono::seconds(2);
constexpr int QOS_AT_LEAST_ONCE = 1;
/// MQTT v5 reason codes from 0x80 (128) on are failures (e.g. 0x87 not authorized).
constexpr int FIRST_FAILURE_REASON = 0x80;

/// libmosquitto is set up once per process (lib_init/lib_cleanup are not reference counted).
void initLibrary() {
  static const int once = [] { return mosquitto_lib_init(); }();
  (void)once;
}

void onConnect(mosquitto* /*mosq*/, void* self, int reasonCode, int /*flags*/,
                          const mosquitto_property* /*props*/) {
  static_cast<Sender*>(self)->noteConnect(reasonCode);
}
void onDisconnect(mosquitto* /*mosq*/, void* self, int reasonCode, const mosquitto_property* /*props*/) {
  static_cast<Sender*>(self)->noteDisconnect(reasonCode);
}
void onPublish(mosquitto* /*mosq*/, void* self, int mid, int reasonCode, const mosquitto_property* /*props*/) {
  static_cast<Sender*>(self)->notePublished(mid, reasonCode);
}
void onMessage(mosquitto* /*mosq*/, void* self, const mosquitto_message* message, const mosquitto_property* /*props*/) {
  static_cast<Sender*>(self)->noteMessage(message->topic, message->payload, message->payloadlen, message->retain);
}
void onSubscribe(mosquitto* /*mosq*/, void* self, int /*mid*/, int count, const int* grantedQos,
                 const mosquitto_property* /*props*/) {
  if (count > 0) static_cast<Sender*>(self)->noteSubscribed(grantedQos[0]);
}

}  // namespace

Sender::Sender(const config::TelemetryConfig& settings, SenderOptions options)
    : m_topicRoot(fleet::vehicleTopicRoot(settings.vehicleId)),
      m_statusTopic(fleet::vehicleTopic(settings.vehicleId, fleet::Topic::Status)),
      m_birthTopic(fleet::vehicleTopic(settings.vehicleId, fleet::Topic::Birth)),
      m_commandTopic(settings.remoteCommandsEnabled ? fleet::commandFilter(settings.vehicleId) : std::string()),
      m_options(std::move(options)),
      m_retryDelay(std::chrono::seconds(m_options.reconnectMinS)) {}

Result<std::unique_ptr<Sender>> Sender::create(const config::TelemetryConfig& settings, SenderOptions options) {
  initLibrary();
  if (options.maxInFlight == 0) return Error{"maxInFlight: at least 1"};
  std::unique_ptr<Sender> sender(new Sender(settings, std::move(options)));
  sender->m_wakeFd = ::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
  if (sender->m_wakeFd < 0) return Error{std::string("eventfd for the sender's wake-ups: ") + std::strerror(errno)};
  const std::string clientId = "openvcu-" + settings.vehicleId;
  sender->m_mosq = mosquitto_new(clientId.c_str(), true, sender.get());
  if (sender->m_mosq == nullptr) return Error{"libmosquitto: cannot create a client (out of memory)"};
  mosquitto* mosq = sender->m_mosq;
  mosquitto_int_option(mosq, MOSQ_OPT_PROTOCOL_VERSION, MQTT_PROTOCOL_V5);
  mosquitto_threaded_set(mosq, true);  // runNetwork's thread, not mosquitto_loop_start's
  mosquitto_connect_v5_callback_set(mosq, onConnect);
  mosquitto_disconnect_v5_callback_set(mosq, onDisconnect);
  mosquitto_publish_v5_callback_set(mosq, onPublish);
  if (!sender->m_commandTopic.empty()) {
    mosquitto_message_v5_callback_set(mosq, onMessage);
    mosquitto_subscribe_v5_callback_set(mosq, onSubscribe);
  }
  if (const int rc = mosquitto_will_set_v5(mosq, sender->m_statusTopic.c_str(),
                                          static_cast<int>(fleet::STATUS_OFFLINE.size()), fleet::STATUS_OFFLINE.data(),
                                          QOS_AT_LEAST_ONCE, true, nullptr);
      rc != MOSQ_ERR_SUCCESS) {
    return Error{std::string("libmosquitto: the last will: ") + mosquitto_strerror(rc)};
  }
  if (!settings.username.empty()) {
    std::string password;
    if (!settings.passwordFile.empty()) {
      std::ifstream in(settings.passwordFile);
      if (!in || !std::getline(in, password)) return Error{settings.passwordFile + ": cannot read the password"};
    }
    if (const int rc = mosquitto_username_pw_set(mosq, settings.username.c_str(),
                                                 settings.passwordFile.empty() ? nullptr : password.c_str());
        rc != MOSQ_ERR_SUCCESS) {
      return Error{std::string("libmosquitto: username: ") + mosquitto_strerror(rc)};
    }
  }
  if (settings.tls) {
    const config::TelemetryTls& tls = *settings.tls;
    const bool systemStore = tls.caFile.empty();
    if (const int rc = mosquitto_tls_set(mosq, systemStore ? nullptr : tls.caFile.c_str(),
                                         systemStore ? "/etc/ssl/certs" : nullptr,
                                         tls.certFile.empty() ? nullptr : tls.certFile.c_str(),
                                         tls.keyFile.empty() ? nullptr : tls.keyFile.c_str(), nullptr);
        rc != MOSQ_ERR_SUCCESS) {
      return Error{std::string("libmosquitto: TLS files: ") + mosquitto_strerror(rc)};
    }
  }
  sender->m_host = settings.broker.host;
  sender->m_port = settings.broker.port;
  sender->m_brokerUrl = settings.brokerUrl;
  sender->m_tls = settings.tls.has_value();
  return sender;
}

Sender::~Sender() {
  if (m_mosq != nullptr) {
    if (m_started) {
      {
        const std::lock_guard lock(m_mutex);
        m_stopping = true;
      }
      m_wake.notify_all();
      mosquitto_disconnect_v5(m_mosq, 0, nullptr);  // a clean disconnect: the broker keeps the will back
      m_network.join();
    }
    mosquitto_destroy(m_mosq);
  }
  if (m_wakeFd >= 0) ::close(m_wakeFd);  // after the network thread ended: it writes it
}

void Sender::setBirth(std::string birth) {
  const std::lock_guard lock(m_mutex);
  m_birth = std::move(birth);
}

Status Sender::start() {
  m_wanted = true;
  return tryConnect();
}

Status Sender::tryConnect() {
  // the network thread starts once a first connect is under way and reconnects from then on;
  // a first connect that failed at once is retried by this thread (pump())
  const auto now = std::chrono::steady_clock::now();
  const int rc = mosquitto_connect_async(m_mosq, m_host.c_str(), m_port, KEEPALIVE_S);
  if (rc == MOSQ_ERR_SUCCESS) {
    m_network = std::thread([this] { runNetwork(); });  // backs off from m_retryDelay on
    m_started = true;
    return {};
  }
  // MOSQ_ERR_TLS: the handshake failed, e.g. the broker's certificate is not signed by caFile
  // or does not name the host (libmosquitto checks both); never connected, retried like an
  // unreachable broker (it may be fixed later), each time logged
  if (rc != MOSQ_ERR_ERRNO && rc != MOSQ_ERR_EAI && rc != MOSQ_ERR_TLS) {
    return Error{"broker " + m_brokerUrl + ": " + mosquitto_strerror(rc)};
  }
  if (rc == MOSQ_ERR_TLS) {
    log(true, tlsFailure());
  } else if (m_firstRetry) {
    log(true, "broker " + m_brokerUrl + " not reachable (" + mosquitto_strerror(rc) + "); retrying, records wait in the queue");
    m_firstRetry = false;
  }
  m_nextAttempt = now + m_retryDelay;
  m_retryDelay = std::min(m_retryDelay * 2, std::chrono::seconds(m_options.reconnectMaxS));
  return {};
}

std::string Sender::tlsFailure() const {
  return "broker " + m_brokerUrl + ": TLS handshake failed (its certificate not signed by caFile or not for " + m_host +
         ", or ours refused by it); not connected, retrying, records wait in the queue";
}

void Sender::runNetwork() {
  // libmosquitto's mosquitto_loop_forever (mosquitto_loop_start's thread) returns for good on
  // some errors, MOSQ_ERR_TLS among them (seen with 2.0.11: a broker refusing the client
  // certificate, a broker certificate for another name): this loop retries after any failure
  std::chrono::seconds delay = m_retryDelay;  // where pump()'s retries of the first connect left it
  bool linkUp = true;  // tryConnect's connect is under way
  while (!m_stopping) {
    if (linkUp) {
      const int rc = mosquitto_loop(m_mosq, LOOP_TIMEOUT_MS, 1);
      if (rc == MOSQ_ERR_SUCCESS) {
        if (connected()) delay = std::chrono::seconds(m_options.reconnectMinS);
        continue;
      }
      linkUp = false;
      if (rc == MOSQ_ERR_TLS) {
        const std::lock_guard lock(m_mutex);
        m_notes.push_back({Note::Kind::TlsFailed, 0, rc});
      }
      continue;
    }
    {
      std::unique_lock lock(m_mutex);
      if (m_wake.wait_for(lock, delay, [&] { return m_stopping.load(); })) break;
    }
    delay = std::min(delay * 2, std::chrono::seconds(m_options.reconnectMaxS));
    const int rc = mosquitto_reconnect(m_mosq);  // blocking: name, TCP, TLS handshake, CONNECT sent
    if (rc == MOSQ_ERR_SUCCESS) {
      linkUp = true;
    } else if (rc == MOSQ_ERR_TLS) {
      const std::lock_guard lock(m_mutex);
      m_notes.push_back({Note::Kind::TlsFailed, 0, rc});
    }
  }
  if (!linkUp) return;
  // stopping: the destructor's DISCONNECT goes out, then libmosquitto closes the link
  const auto until = std::chrono::steady_clock::now() + STOP_WAIT;
  while (mosquitto_loop(m_mosq, LOOP_TIMEOUT_MS, 1) == MOSQ_ERR_SUCCESS && std::chrono::steady_clock::now() < until) {
  }
}

bool Sender::connected() const {
  const std::lock_guard lock(m_mutex);
  return m_connected;
}

LinkCounters Sender::counters() const {
  const std::lock_guard lock(m_mutex);
  return m_counters;
}

std::uint64_t Sender::wakeUps() const {
  const std::lock_guard lock(m_mutex);
  return m_wakeUps;
}

void Sender::signalWakeLocked() {
  m_wakeAfterPublishes = 0;  // one wake-up until pump() arms the next
  if (m_wakeSignalled) return;
  const std::uint64_t one = 1;
  // EAGAIN (the counter full) cannot happen: pump() reads it before the next write
  if (::write(m_wakeFd, &one, sizeof one) == static_cast<ssize_t>(sizeof one)) {
    m_wakeSignalled = true;
    ++m_wakeUps;
  }
}

void Sender::publishRetained(const std::string& topic, const std::string& payload) {
  mosquitto_publish_v5(m_mosq, nullptr, topic.c_str(), static_cast<int>(payload.size()), payload.data(),
                       QOS_AT_LEAST_ONCE, true, nullptr);
}

void Sender::noteConnect(int reasonCode) {
  std::string birth;
  {
    const std::lock_guard lock(m_mutex);
    m_connackSeen = true;
    if (reasonCode != 0) {
      m_notes.push_back({Note::Kind::Refused, 0, reasonCode});
      return;
    }
    m_connected = true;
    ++m_counters.connects;
    m_notes.push_back({Note::Kind::Connected, 0, 0});
    birth = m_birth;
    signalWakeLocked();  // records that waited for the link go out now, not at the next periodic pump()
  }
  // on the network thread, before any queued record of this connection; the subscription
  // first, so whoever sees this connection's birth knows commands are read (a clean session:
  // the broker forgot the last one)
  if (!m_commandTopic.empty()) {
    mosquitto_subscribe_v5(m_mosq, nullptr, m_commandTopic.c_str(), QOS_AT_LEAST_ONCE,
                           MQTT_SUB_OPT_RETAIN_AS_PUBLISHED, nullptr);
  }
  publishRetained(m_statusTopic, std::string(fleet::STATUS_ONLINE));
  if (!birth.empty()) publishRetained(m_birthTopic, birth);
}

void Sender::noteDisconnect(int reasonCode) {
  const std::lock_guard lock(m_mutex);
  // closed before its CONNACK: over TLS, the broker refused our certificate in the handshake
  m_notes.push_back({m_connackSeen ? Note::Kind::Disconnected : Note::Kind::LostBeforeConnack, 0, reasonCode});
  m_connected = false;
  m_connackSeen = false;
}

void Sender::notePublished(int mid, int reasonCode) {
  const std::lock_guard lock(m_mutex);
  if (reasonCode >= FIRST_FAILURE_REASON) ++m_counters.refused;
  m_notes.push_back({Note::Kind::Published, mid, reasonCode});
  ++m_publishesSincePump;
  if (m_wakeAfterPublishes > 0 && m_publishesSincePump >= m_wakeAfterPublishes) signalWakeLocked();
}

void Sender::noteMessage(const char* topic, const void* payload, int length, bool retained) {
  const std::lock_guard lock(m_mutex);
  if (m_inbound.size() >= m_options.maxInbound) {
    ++m_inboundDropped;
    return;
  }
  m_inbound.push_back(InboundMessage{.topic = topic != nullptr ? topic : "",
                                     .payload = std::string(static_cast<const char*>(payload),
                                                            static_cast<std::size_t>(std::max(length, 0))),
                                     .retained = retained});
}

void Sender::noteSubscribed(int grantedQos) {
  if (grantedQos < FIRST_FAILURE_REASON) return;
  const std::lock_guard lock(m_mutex);
  m_notes.push_back({Note::Kind::SubscribeRefused, 0, grantedQos});
}

std::vector<InboundMessage> Sender::takeMessages() {
  std::vector<InboundMessage> messages;
  const std::lock_guard lock(m_mutex);
  messages.swap(m_inbound);
  return messages;
}

void Sender::log(bool warning, const std::string& text) const {
  const auto& sink = warning ? m_options.logWarning : m_options.logInfo;
  if (sink) sink(text);
}

Status Sender::pump(DiskQueue& queue) {
  if (m_wanted && !m_started && std::chrono::steady_clock::now() >= m_nextAttempt) {
    if (auto tried = tryConnect(); !tried) return tried.error();
  }
  std::vector<Note> notes;
  bool connected = false;
  std::uint64_t inboundDropped = 0;
  {
    const std::lock_guard lock(m_mutex);
    notes.swap(m_notes);
    connected = m_connected;
    std::swap(inboundDropped, m_inboundDropped);
    m_publishesSincePump = 0;
    m_wakeAfterPublishes = 0;  // armed again below when records still wait
    if (m_wakeSignalled) {
      std::uint64_t count = 0;
      (void)!::read(m_wakeFd, &count, sizeof count);  // back to not readable (EAGAIN: already read)
      m_wakeSignalled = false;
    }
  }
  if (inboundDropped > 0) {
    log(true, std::to_string(inboundDropped) + " remote command message(s) dropped unread: " +
                  std::to_string(m_options.maxInbound) + " were already waiting");
  }
  for (const Note& note : notes) {
    switch (note.kind) {
      case Note::Kind::Connected:
        log(false, "connected to the broker; " + std::to_string(m_handed.size()) + " record(s) in flight, " +
                       std::to_string(queue.stats().pendingRecords) + " waiting");
        break;
      case Note::Kind::Refused:
        log(true, std::string("the broker refused the connection: ") + mosquitto_reason_string(note.reasonCode));
        break;
      case Note::Kind::Disconnected:
        log(true, "link to the broker lost (" + std::string(mosquitto_strerror(note.reasonCode)) +
                      "); records wait in the queue");
        break;
      case Note::Kind::TlsFailed:
        log(true, tlsFailure());
        break;
      case Note::Kind::LostBeforeConnack:
        log(true, m_tls ? tlsFailure()
                        : "the broker closed the connection before accepting it (" +
                              std::string(mosquitto_strerror(note.reasonCode)) + "); retrying, records wait in the queue");
        break;
      case Note::Kind::SubscribeRefused:
        log(true, "the broker refused the subscription to " + m_commandTopic + ": " +
                      mosquitto_reason_string(note.reasonCode) + " (no remote commands arrive; its ACL)");
        break;
      case Note::Kind::Published: {
        const auto it = m_midToSequence.find(note.mid);
        if (it == m_midToSequence.end()) break;  // status and birth
        const std::uint64_t sequence = it->second;
        m_midToSequence.erase(it);
        for (Handed& handed : m_handed) {
          if (handed.sequence == sequence) handed.done = true;
        }
        if (note.reasonCode >= FIRST_FAILURE_REASON) {
          log(true, "record " + std::to_string(sequence) + " refused by the broker: " +
                        mosquitto_reason_string(note.reasonCode) + " (not sent again)");
        }
        break;
      }
    }
  }
  // ack the contiguous prefix of confirmed records
  std::uint64_t ackUpTo = 0;
  while (!m_handed.empty() && m_handed.front().done) {
    ackUpTo = m_handed.front().sequence;
    m_handed.pop_front();
  }
  if (ackUpTo > 0) {
    if (auto acked = queue.ack(ackUpTo); !acked) return acked.error();
  }
  if (!connected) return {};
  if (m_handed.size() < m_options.maxInFlight) {
    if (auto handed = handOut(queue); !handed) return handed;
  }
  // records still wait behind a full window (records or bytes): wake at once when the broker
  // confirmed half of what is in flight (or all of one), so the drain runs at the broker's pace,
  // not the periodic one
  if (queue.stats().pendingRecords > m_handed.size() && !m_handed.empty()) {
    const std::size_t after = std::max<std::size_t>(1, m_handed.size() / 2);
    const std::lock_guard lock(m_mutex);
    m_wakeAfterPublishes = after;
    if (m_publishesSincePump >= after) signalWakeLocked();  // confirmed while this pump() ran
  }
  return {};
}

Status Sender::handOut(DiskQueue& queue) {
  // the records after the last one handed (the queue peeks from the oldest unacked, so the
  // handed ones come first and count against both bounds)
  auto peeked = queue.peek(m_options.maxInFlight, m_options.maxInFlightBytes);
  if (!peeked) return peeked.error();
  for (const QueueRecord& entry : *peeked) {
    if (m_handed.size() >= m_options.maxInFlight) break;
    if (entry.sequence <= m_lastHanded) continue;
    const std::size_t newline = entry.payload.find('\n');
    if (newline == std::string::npos) {  // not ours: never send it, never block the queue on it
      log(true, "record " + std::to_string(entry.sequence) + " has no topic line; skipped");
      m_handed.push_back({entry.sequence, true});
      m_lastHanded = entry.sequence;
      continue;
    }
    const std::string_view suffix = std::string_view(entry.payload).substr(0, newline);
    const std::string topic = m_topicRoot + std::string(suffix);
    // state, faults and health retained (the last one stays for a watcher that comes later)
    const auto kind = fleet::topicFromSuffix(suffix);
    const bool retain = kind.has_value() && fleet::isRetained(*kind);
    const char* body = entry.payload.data() + newline + 1;
    const int length = static_cast<int>(entry.payload.size() - newline - 1);
    int mid = 0;
    // the mid is noted before the PUBACK can be handled: notes are read by this thread only
    const int rc = mosquitto_publish_v5(m_mosq, &mid, topic.c_str(), length, body, QOS_AT_LEAST_ONCE, retain, nullptr);
    if (rc == MOSQ_ERR_SUCCESS || (rc == MOSQ_ERR_NO_CONN && mid != 0)) {
      // NO_CONN: the link dropped just now; libmosquitto keeps the message and sends it after the reconnect
      m_midToSequence[mid] = entry.sequence;
      m_handed.push_back({entry.sequence, false});
      m_lastHanded = entry.sequence;
      if (rc == MOSQ_ERR_NO_CONN) break;
      continue;
    }
    log(true, "publish of record " + std::to_string(entry.sequence) + ": " + mosquitto_strerror(rc));
    break;
  }
  return {};
}

}  // namespace openvcu::telemetry
