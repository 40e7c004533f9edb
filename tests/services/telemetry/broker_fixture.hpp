#pragma once
// What the broker tests of vcu-telemetry share (test_broker.cpp, test_remote_commands.cpp,
// test_queue_limit.cpp, test_fleet_watch.cpp, test_tls.cpp): writing a file, a received message, a
// subscriber to openvcu/# that keeps every message (over TLS when asked), a port check, a mosquitto
// configuration with a password file (made by mosquitto_passwd at run time, test passwords only)
// and an ACL file, one with TLS listeners that want client certificates, and an MQTT v5 client
// on libmosquitto that reports what the broker answered (CONNACK, SUBACK and PUBACK reason
// codes). Runs inside tests/harness/run_isolated.sh only (loopback).
//
//   const harness::ProcessSpec spec = brokerSpec(sut, work / "broker", {{"hhea-01", "secret"}}, aclFile, 1883);
//   auto broker = sut.start(spec);
//   MqttClient operatorClient("op", "fleet-operator", "op-secret");
//   REQUIRE(operatorClient.connect(1883) == 0);
//   CHECK(operatorClient.publish("openvcu/hhea-01/cmd/c1", body) == 0);   // 0x87: not authorized

#include <doctest/doctest.h>
#include <mosquitto.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <functional>
#include <thread>
#include <condition_variable>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "harness/harness.hpp"

namespace openvcu::telemetry_test {

namespace fs = std::filesystem;
using Json = nlohmann::json;

/// MQTT v5 reason code 0x87 (135) "Not authorized" (OASIS MQTT 5.0, 2.4).
inline constexpr int REASON_NOT_AUTHORIZED = 0x87;
/// What the waiting calls of MqttClient report when the broker did not answer in time.
inline constexpr int NO_ANSWER = -1;

inline void writeFile(const fs::path& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
  REQUIRE(out.good());
}

struct Message {
  std::string topic;
  Json body;  ///< the JSON payload, or the text when it is not JSON (the status)
  bool retained{};
};

/// mosquitto on 127.0.0.1:`port` without anonymous access, with a password file of `users`
/// (made in `folder` by mosquitto_passwd) and the ACL file `acl`; no persistence. The spec to start it.
inline harness::ProcessSpec brokerSpec(harness::Harness& sut, const fs::path& folder,
                                       const std::vector<std::pair<std::string, std::string>>& users,
                                       const fs::path& acl, int port) {
  fs::create_directories(folder);
  bool first = true;
  for (const auto& [user, password] : users) {
    std::vector<std::string> argv{"mosquitto_passwd", "-b", (folder / "passwords").string(), user, password};
    if (first) argv.insert(argv.begin() + 1, "-c");  // creates the file
    first = false;
    const auto added = sut.run(argv);
    REQUIRE_MESSAGE(added.exitCode() == 0, added.describe());
  }
  writeFile(folder / "mosquitto.conf",
            "listener " + std::to_string(port) + " 127.0.0.1\nallow_anonymous false\npassword_file " +
                (folder / "passwords").string() + "\nacl_file " + acl.string() + "\nuser root\nlog_dest stdout\n");
  return harness::ProcessSpec{.name = "mosquitto",
                              .argv = {"/usr/sbin/mosquitto", "-c", (folder / "mosquitto.conf").string()}};
}

/// One TLS listener of tlsBrokerSpec: its port on 127.0.0.1, the CA its clients' certificates
/// must be signed by, the broker's own certificate and key.
struct TlsListener {
  int port{8883};
  fs::path caFile;
  fs::path certFile;
  fs::path keyFile;
};

/// mosquitto with one TLS listener per entry of `listeners`, each wanting a client certificate
/// whose CN becomes the username (use_identity_as_username) for the ACL file `acl`; no password
/// file, no anonymous access, no persistence. The configuration is written to `folder`.
inline harness::ProcessSpec tlsBrokerSpec(const fs::path& folder, const fs::path& acl,
                                          const std::vector<TlsListener>& listeners) {
  fs::create_directories(folder);
  std::string conf = "allow_anonymous false\nacl_file " + acl.string() + "\nuser root\nlog_dest stdout\n";
  for (const TlsListener& listener : listeners) {
    conf += "listener " + std::to_string(listener.port) + " 127.0.0.1\ncafile " + listener.caFile.string() +
            "\ncertfile " + listener.certFile.string() + "\nkeyfile " + listener.keyFile.string() +
            "\nrequire_certificate true\nuse_identity_as_username true\n";
  }
  writeFile(folder / "mosquitto.conf", conf);
  return harness::ProcessSpec{.name = "mosquitto",
                              .argv = {"/usr/sbin/mosquitto", "-c", (folder / "mosquitto.conf").string()}};
}

/// A TLS client's files: the CA it trusts for the broker's certificate and its own certificate
/// and key. `insecure`: no check of the broker's name against its certificate (mosquitto_tls_insecure_set).
struct TlsClientFiles {
  fs::path caFile;
  fs::path certFile;
  fs::path keyFile;
  bool insecure{false};
};

/// An MQTT v5 client (libmosquitto, its own network thread, no reconnects) that keeps every
/// message of its subscriptions and reports the broker's reason codes.
/// @note the calls from one thread (the test's); the callbacks only record.
class MqttClient {
 public:
  MqttClient(const std::string& clientId, const std::string& user, const std::string& password) {
    mosquitto_lib_init();
    m_mosq = mosquitto_new(clientId.c_str(), true, this);
    REQUIRE(m_mosq != nullptr);
    mosquitto_int_option(m_mosq, MOSQ_OPT_PROTOCOL_VERSION, MQTT_PROTOCOL_V5);
    mosquitto_username_pw_set(m_mosq, user.c_str(), password.c_str());
    mosquitto_connect_v5_callback_set(m_mosq, [](mosquitto*, void* self, int rc, int, const mosquitto_property*) {
      static_cast<MqttClient*>(self)->record([&](MqttClient& client) { client.m_connack = rc; });
    });
    mosquitto_publish_v5_callback_set(m_mosq, [](mosquitto*, void* self, int mid, int rc, const mosquitto_property*) {
      static_cast<MqttClient*>(self)->record([&](MqttClient& client) { client.m_pubacks[mid] = rc; });
    });
    mosquitto_subscribe_v5_callback_set(
        m_mosq, [](mosquitto*, void* self, int mid, int count, const int* granted, const mosquitto_property*) {
          static_cast<MqttClient*>(self)->record(
              [&](MqttClient& client) { client.m_subacks[mid] = count > 0 ? granted[0] : NO_ANSWER; });
        });
    mosquitto_message_v5_callback_set(m_mosq, [](mosquitto*, void* self, const mosquitto_message* message,
                                                 const mosquitto_property*) {
      const std::string text(static_cast<const char*>(message->payload), static_cast<std::size_t>(message->payloadlen));
      Json body = Json::parse(text, nullptr, false);
      if (body.is_discarded()) body = text;
      static_cast<MqttClient*>(self)->record([&](MqttClient& client) {
        client.m_messages.push_back({message->topic, std::move(body), message->retain});
      });
    });
  }
  ~MqttClient() {
    mosquitto_disconnect_v5(m_mosq, 0, nullptr);
    mosquitto_loop_stop(m_mosq, true);
    mosquitto_destroy(m_mosq);
  }
  MqttClient(const MqttClient&) = delete;
  MqttClient& operator=(const MqttClient&) = delete;

  /// Connects to 127.0.0.1:`port`; the CONNACK reason (0: accepted), or NO_ANSWER.
  int connect(int port, std::chrono::milliseconds timeout = std::chrono::seconds(5)) {
    if (mosquitto_connect(m_mosq, "127.0.0.1", port, 10) != MOSQ_ERR_SUCCESS) return NO_ANSWER;
    if (mosquitto_loop_start(m_mosq) != MOSQ_ERR_SUCCESS) return NO_ANSWER;
    std::unique_lock lock(m_mutex);
    m_changed.wait_for(lock, timeout, [&] { return m_connack.has_value(); });
    return m_connack.value_or(NO_ANSWER);
  }
  /// Subscribes at QoS 1; the SUBACK's granted QoS (>= 0x80: refused), or NO_ANSWER.
  int subscribe(const std::string& topic, std::chrono::milliseconds timeout = std::chrono::seconds(5)) {
    int mid = 0;
    if (mosquitto_subscribe_v5(m_mosq, &mid, topic.c_str(), 1, 0, nullptr) != MOSQ_ERR_SUCCESS) return NO_ANSWER;
    std::unique_lock lock(m_mutex);
    m_changed.wait_for(lock, timeout, [&] { return m_subacks.contains(mid); });
    return m_subacks.contains(mid) ? m_subacks[mid] : NO_ANSWER;
  }
  /// Publishes at QoS 1; the PUBACK's reason (0: accepted, 0x87: not authorized), or NO_ANSWER.
  int publish(const std::string& topic, const std::string& payload, bool retain = false,
              std::chrono::milliseconds timeout = std::chrono::seconds(5)) {
    int mid = 0;
    if (mosquitto_publish_v5(m_mosq, &mid, topic.c_str(), static_cast<int>(payload.size()), payload.data(), 1, retain,
                             nullptr) != MOSQ_ERR_SUCCESS) {
      return NO_ANSWER;
    }
    std::unique_lock lock(m_mutex);
    m_changed.wait_for(lock, timeout, [&] { return m_pubacks.contains(mid); });
    return m_pubacks.contains(mid) ? m_pubacks[mid] : NO_ANSWER;
  }
  /// Waits until `done(messages)` holds; false on timeout.
  template <typename Predicate>
  bool waitFor(Predicate done, std::chrono::milliseconds timeout) {
    std::unique_lock lock(m_mutex);
    return m_changed.wait_for(lock, timeout, [&] { return done(m_messages); });
  }
  /// The first message on `topic` within `timeout`.
  std::optional<Message> waitForTopic(const std::string& topic, std::chrono::milliseconds timeout) {
    std::optional<Message> found;
    waitFor(
        [&](const std::vector<Message>& messages) {
          for (const Message& message : messages) {
            if (message.topic == topic) {
              found = message;
              return true;
            }
          }
          return false;
        },
        timeout);
    return found;
  }
  std::vector<Message> messages() {
    const std::lock_guard lock(m_mutex);
    return m_messages;
  }

 private:
  template <typename Change>
  void record(Change change) {
    const std::lock_guard lock(m_mutex);
    change(*this);
    m_changed.notify_all();
  }

  mosquitto* m_mosq{nullptr};
  std::mutex m_mutex;
  std::condition_variable m_changed;
  std::optional<int> m_connack;
  std::map<int, int> m_pubacks;
  std::map<int, int> m_subacks;
  std::vector<Message> m_messages;
};

/// A libmosquitto subscriber to openvcu/# (MQTT 3.1.1, QoS 1), reconnecting by itself every
/// second; with `persistent` (clean session off) the broker keeps its subscription across a
/// restart. A username (with its password) when the broker wants one. Each message keeps its
/// retain flag: set for a retained copy given at a (re)subscription, not for a live one.
class Subscriber {
 public:
  Subscriber(const char* clientId, bool persistent, const char* username = nullptr, const char* password = nullptr,
             int port = 1883)
      : m_port(port) {
    mosquitto_lib_init();
    m_mosq = mosquitto_new(clientId, !persistent, this);
    REQUIRE(m_mosq != nullptr);
    if (username != nullptr) mosquitto_username_pw_set(m_mosq, username, password);
    mosquitto_reconnect_delay_set(m_mosq, 1, 1, false);
    mosquitto_connect_callback_set(m_mosq, [](mosquitto* mosq, void*, int rc) {
      if (rc == 0) mosquitto_subscribe(mosq, nullptr, "openvcu/#", 1);
    });
    mosquitto_message_callback_set(m_mosq, [](mosquitto*, void* self, const mosquitto_message* message) {
      static_cast<Subscriber*>(self)->add(message);
    });
    mosquitto_subscribe_callback_set(m_mosq, [](mosquitto*, void* self, int, int, const int*) {
      auto* subscriber = static_cast<Subscriber*>(self);
      const std::lock_guard lock(subscriber->m_mutex);
      ++subscriber->m_subacks;
      subscriber->m_changed.notify_all();
    });
  }
  ~Subscriber() {
    mosquitto_disconnect(m_mosq);
    mosquitto_loop_stop(m_mosq, true);
    mosquitto_destroy(m_mosq);
  }
  /// TLS for the next connect() (before it); false when libmosquitto refuses the files.
  bool useTls(const TlsClientFiles& files) {
    if (mosquitto_tls_set(m_mosq, files.caFile.c_str(), nullptr, files.certFile.c_str(), files.keyFile.c_str(),
                          nullptr) != MOSQ_ERR_SUCCESS) {
      return false;
    }
    return mosquitto_tls_insecure_set(m_mosq, files.insecure) == MOSQ_ERR_SUCCESS;
  }
  bool connect() {
    if (mosquitto_connect(m_mosq, "127.0.0.1", m_port, 10) != MOSQ_ERR_SUCCESS) return false;
    return mosquitto_loop_start(m_mosq) == MOSQ_ERR_SUCCESS;
  }
  /// Waits until the broker has confirmed a subscription (its SUBACK); false on timeout.
  bool waitSubscribed(std::chrono::milliseconds timeout) {
    std::unique_lock lock(m_mutex);
    return m_changed.wait_for(lock, timeout, [&] { return m_subacks > 0; });
  }
  void add(const mosquitto_message* message) {
    const std::string text(static_cast<const char*>(message->payload), static_cast<std::size_t>(message->payloadlen));
    Json body = Json::parse(text, nullptr, false);
    if (body.is_discarded()) body = text;  // the status is plain text
    const std::lock_guard lock(m_mutex);
    m_messages.push_back({message->topic, std::move(body), message->retain});
    m_changed.notify_all();
  }
  /// Waits until `done(messages)` holds; false on timeout.
  template <typename Predicate>
  bool waitFor(Predicate done, std::chrono::milliseconds timeout) {
    std::unique_lock lock(m_mutex);
    return m_changed.wait_for(lock, timeout, [&] { return done(m_messages); });
  }
  std::vector<Message> messages() {
    const std::lock_guard lock(m_mutex);
    return m_messages;
  }

 private:
  mosquitto* m_mosq{nullptr};
  int m_port;
  std::mutex m_mutex;
  std::condition_variable m_changed;
  int m_subacks{0};  ///< SUBACKs received (one per connect)
  std::vector<Message> m_messages;
};

/// Calls `step(n)` (n = 0, 1, ...) every `period` on a thread of its own until stop() or the
/// destructor: the tests' writer of the signal table.
class PeriodicWriter {
 public:
  PeriodicWriter(std::chrono::milliseconds period, std::function<void(int)> step)
      : m_thread([this, period, step = std::move(step)] {
          for (int n = 0; m_running; ++n) {
            step(n);
            std::this_thread::sleep_for(period);
          }
        }) {}
  ~PeriodicWriter() { stop(); }
  PeriodicWriter(const PeriodicWriter&) = delete;
  PeriodicWriter& operator=(const PeriodicWriter&) = delete;
  void stop() {
    m_running = false;
    if (m_thread.joinable()) m_thread.join();
  }

 private:
  std::atomic<bool> m_running{true};
  std::thread m_thread;
};

/// True once something accepts TCP connections on 127.0.0.1:port.
inline bool listening(int port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(static_cast<std::uint16_t>(port));
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  const bool ok = ::connect(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address) == 0;
  ::close(fd);
  return ok;
}

}  // namespace openvcu::telemetry_test
