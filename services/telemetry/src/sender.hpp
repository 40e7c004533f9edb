#pragma once
// vcu-telemetry's sender (docs/design/telemetry.md, "Store and forward"): the disk queue's
// records to the broker over libmosquitto, MQTT v5, QoS 1. A network thread of the sender's
// own (runNetwork: mosquitto_loop, and mosquitto_reconnect with backoff after any failure, a
// failed TLS handshake among them, which libmosquitto's own loop thread gives up on) runs
// libmosquitto, which calls back; the callbacks only note what happened,
// and pump() (on the owner's thread, which owns the queue) acts on it:
//   - wakeFd() (an eventfd) turns readable when pump() should run at once rather than at the
//     owner's next periodic call: at a connect, and while records wait in the queue beyond the
//     full window, once PUBACKs confirmed half of it (one wake-up per half window; none while
//     nothing waits, so the steady state adds none): the broker's confirmations pace the drain;
//   - while connected, hands libmosquitto the records after the last one handed, at most
//     maxInFlight unconfirmed at a time and maxInFlightBytes of their payloads (libmosquitto
//     holds whatever it is handed);
//   - on each PUBACK (or a v5 refusal, counted) marks the record done and acks the queue up to
//     the highest record below which every record is done;
//   - never publishes while disconnected: after a reconnect libmosquitto resends what it held.
// At each connect: the retained status "online" and the retained birth; the last will is the
// retained status "offline". With remote commands enabled, also the subscription to
// openvcu/<id>/cmd/+ (QoS 1, retain as published, so a retained command is seen as one); the
// messages are only noted (at most maxInbound waiting) and taken by the owner with takeMessages().
//
//   auto sender = Sender::create(settings, {.maxInFlight = 200});
//   sender->setBirth(birthJson);
//   sender->start();                 // connect in the background (pump() retries a refused first connect)
//   loop.addFd(sender->wakeFd(), [&] { sender->pump(queue); });   // the drain, paced by the broker
//   sender->pump(queue);             // also periodically, on the queue's thread
//   for (auto& message : sender->takeMessages()) handle(message);   // remote commands, same thread

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "disk_queue.hpp"
#include "engine.hpp"
#include "openvcu/config/telemetry.hpp"
#include "openvcu/core/result.hpp"

struct mosquitto;

namespace openvcu::telemetry {

/// A message the broker delivered on a subscribed topic (remote commands).
struct InboundMessage {
  std::string topic;
  std::string payload;
  bool retained{false};  ///< as published (the subscription keeps the flag)
};

struct SenderOptions {
  /// records handed to libmosquitto and not yet confirmed (libmosquitto sends at most the
  /// broker's receive maximum of them at a time and the rest as PUBACKs come: the drain needs
  /// no loop wake-up between two of them); 200: docs/benchmarks.md, "Telemetry"
  std::size_t maxInFlight{200};
  /// and their payload bytes (libmosquitto holds a copy of each until its PUBACK); a record
  /// larger than this still goes out alone
  std::size_t maxInFlightBytes{std::size_t{1} << 20};
  std::size_t maxInbound{64};  ///< delivered messages waiting for takeMessages(); more are dropped and logged
  unsigned reconnectMinS{1};   ///< first reconnect delay; doubles up to reconnectMaxS
  unsigned reconnectMaxS{30};
  std::function<void(const std::string&)> logInfo;     ///< called on the pump()'s thread
  std::function<void(const std::string&)> logWarning;  ///< called on the pump()'s thread
};

/// @note restricted thread-safe: create, setBirth, start, pump and the destructor on one
///       thread; libmosquitto's callbacks run on the network thread and only queue notes.
class Sender {
 public:
  /// Errors: libmosquitto cannot be set up (the TLS files, the password file).
  static Result<std::unique_ptr<Sender>> create(const config::TelemetryConfig& settings, SenderOptions options);
  ~Sender();
  Sender(const Sender&) = delete;
  Sender& operator=(const Sender&) = delete;

  /// The retained birth published at each connect from now on.
  void setBirth(std::string birth);
  /// Connects in the background: the network thread once the first connect is under way (it
  /// reconnects from then on); until then pump() retries with the same backoff.
  /// Error: the broker address cannot be used at all.
  Status start();
  /// Retries a first connect when due, acts on what the network thread noted and hands out
  /// records; an error for the queue's I/O or an unusable broker address. Consumes wakeFd().
  Status pump(DiskQueue& queue);
  /// Readable (an eventfd) when pump() has work now: a connect, or half the window confirmed
  /// while more records wait. Owned by the sender; watch it for pump() (level-triggered: pump()
  /// reads it).
  [[nodiscard]] int wakeFd() const noexcept { return m_wakeFd; }
  /// Wake-ups signalled on wakeFd() since create (tests, benchmarks).
  [[nodiscard]] std::uint64_t wakeUps() const;

  [[nodiscard]] bool connected() const;
  [[nodiscard]] LinkCounters counters() const;
  [[nodiscard]] std::size_t inFlight() const noexcept { return m_handed.size(); }
  /// The messages delivered on openvcu/<id>/cmd/+ since the last call, in arrival order.
  std::vector<InboundMessage> takeMessages();

  // libmosquitto's callbacks (network thread)
  void noteConnect(int reasonCode);
  void noteDisconnect(int reasonCode);
  void notePublished(int mid, int reasonCode);
  void noteMessage(const char* topic, const void* payload, int length, bool retained);
  void noteSubscribed(int grantedQos);

 private:
  Sender(const config::TelemetryConfig& settings, SenderOptions options);
  struct Handed {
    std::uint64_t sequence{};
    bool done{false};
  };
  struct Note {
    enum class Kind { Connected, Refused, Disconnected, Published, SubscribeRefused, TlsFailed, LostBeforeConnack } kind;
    int mid{};
    int reasonCode{};
  };
  void publishRetained(const std::string& topic, const std::string& payload);
  void signalWakeLocked();  ///< m_mutex held
  Status tryConnect();
  Status handOut(DiskQueue& queue);  ///< connected, room in the window
  /// The network thread: runs libmosquitto until the destructor asks it to stop.
  void runNetwork();
  [[nodiscard]] std::string tlsFailure() const;
  void log(bool warning, const std::string& text) const;

  std::string m_topicRoot;  ///< "openvcu/<id>/"
  std::string m_statusTopic;  ///< "openvcu/<id>/status" (online, the will offline)
  std::string m_birthTopic;   ///< "openvcu/<id>/birth"
  std::string m_commandTopic;  ///< "openvcu/<id>/cmd/+" with remote commands enabled, else empty
  SenderOptions m_options;
  mosquitto* m_mosq{nullptr};
  int m_wakeFd{-1};  ///< eventfd: the network thread writes, pump() reads
  std::string m_host;
  int m_port{};
  std::string m_brokerUrl;
  bool m_tls{false};      ///< mqtts://
  bool m_wanted{false};   ///< start() was called
  bool m_started{false};  ///< the network thread runs (after the first connect was under way)
  std::thread m_network;
  std::atomic<bool> m_stopping{false};  ///< set (under m_mutex) by the destructor
  std::condition_variable m_wake;       ///< wakes the network thread's backoff wait to stop
  bool m_firstRetry{true};
  std::chrono::seconds m_retryDelay;
  std::chrono::steady_clock::time_point m_nextAttempt{};

  mutable std::mutex m_mutex;  // guards what the network thread writes:
  std::vector<Note> m_notes;
  bool m_connected{false};
  bool m_connackSeen{false};  ///< a CONNACK (accepting or not) arrived on the current link
  std::string m_birth;
  LinkCounters m_counters;
  std::vector<InboundMessage> m_inbound;
  std::uint64_t m_inboundDropped{0};  ///< beyond maxInbound since the last pump()
  bool m_wakeSignalled{false};            ///< m_wakeFd holds a count pump() has not read yet
  std::size_t m_publishesSincePump{0};    ///< PUBACKs (any publish) noted since the last pump()
  std::size_t m_wakeAfterPublishes{0};    ///< wake pump() at this many; 0: no wake (nothing waits)
  std::uint64_t m_wakeUps{0};

  // the owner's thread only
  std::deque<Handed> m_handed;            ///< in the order handed
  std::map<int, std::uint64_t> m_midToSequence;
  std::uint64_t m_lastHanded{0};          ///< the highest sequence handed to libmosquitto
  std::map<std::string, bool> m_refusedTopics;  ///< logged once each
};

}  // namespace openvcu::telemetry
