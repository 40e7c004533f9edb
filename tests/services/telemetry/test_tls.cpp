// vcu-telemetry over TLS (issue 25, docs/design/telemetry.md "telemetry.json": mqtts:// and
// "tls"), inside the sandbox of tests/harness/run_isolated.sh (loopback only). At run time the
// `openssl` CLI makes throw-away keys and certificates in the sandbox's /tmp (none are in the
// repository): a test CA, a server certificate for 127.0.0.1/localhost signed by it, client
// certificates (CN = the vehicle id, or the watcher) signed by it, and a second, unrelated CA
// with a server and a client certificate of its own. One mosquitto has three TLS listeners that
// all want a client certificate signed by the test CA, its CN the username for the ACL of
// services/telemetry/examples/acl (use_identity_as_username):
//   8883: the server certificate of the test CA for IP:127.0.0.1 (the right broker);
//   8884: a server certificate signed by the other CA;
//   8885: a server certificate of the test CA but for the name broker.invalid only.
// Shown with the real vcu-telemetry (mqtts:// with caFile, certFile, keyFile) and a TLS
// subscriber (libmosquitto, the watcher's certificate):
//   1. hhea-01 (its certificate from the test CA) connects to 8883: status "online" and the
//      birth arrive, retained for a later subscriber, and its signals records flow;
//   2. hhea-02, whose certificate is signed by the other CA, is refused by the broker in the
//      handshake: its log says so, nothing under openvcu/hhea-02 arrives;
//   3. hhea-03 on 8884 and hhea-04 on 8885 (valid client certificates) refuse the broker: its
//      certificate is not signed by their caFile, or does not name 127.0.0.1. Nothing under
//      their ids arrives, while subscribers that trust the other CA (8884) or skip the name
//      check (8885) are let in on the same listeners and get hhea-01's messages.
#include <doctest/doctest.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "broker_fixture.hpp"
#include "harness/harness.hpp"
#include "openvcu/config/catalog.hpp"
#include "openvcu/config/vehicle.hpp"
#include "openvcu/core/clock.hpp"
#include "openvcu/signals/table.hpp"
#include "skip.hpp"

namespace {

using namespace openvcu;
using namespace std::chrono_literals;
using telemetry_test::listening;
using telemetry_test::Message;
using telemetry_test::Subscriber;
using telemetry_test::TlsClientFiles;
using telemetry_test::writeFile;
using Json = nlohmann::json;
namespace fs = std::filesystem;

constexpr const char* OPENSSL = "/usr/bin/openssl";
constexpr const char* SOC_KEY = "VIC.HVESSD2_PGN61585.HS_FastUpdSOC";
constexpr int GOOD_PORT = 8883;
constexpr int OTHER_CA_PORT = 8884;
constexpr int WRONG_NAME_PORT = 8885;

/// Throw-away keys (EC P-256) and certificates made with the openssl CLI in one folder:
/// `<name>.key`, `<name>.crt`.
class Pki {
 public:
  Pki(harness::Harness& sut, fs::path folder) : m_sut(sut), m_folder(std::move(folder)) {
    fs::create_directories(m_folder);
  }
  /// A self-signed CA certificate.
  void ca(const std::string& name, const std::string& commonName) {
    run({OPENSSL, "req", "-x509", "-newkey", "ec", "-pkeyopt", "ec_paramgen_curve:prime256v1", "-nodes", "-keyout",
         key(name), "-out", crt(name), "-days", "1", "-subj", "/CN=" + commonName});
  }
  /// A certificate for `commonName` signed by the CA `caName`, with the extensions `extensions`
  /// (openssl x509 -extfile lines).
  void issue(const std::string& name, const std::string& commonName, const std::string& caName,
             const std::string& extensions) {
    const std::string csr = (m_folder / (name + ".csr")).string();
    const std::string ext = (m_folder / (name + ".ext")).string();
    run({OPENSSL, "req", "-new", "-newkey", "ec", "-pkeyopt", "ec_paramgen_curve:prime256v1", "-nodes", "-keyout",
         key(name), "-out", csr, "-subj", "/CN=" + commonName});
    writeFile(ext, extensions);
    run({OPENSSL, "x509", "-req", "-in", csr, "-CA", crt(caName), "-CAkey", key(caName), "-set_serial",
         std::to_string(++m_serial), "-days", "1", "-extfile", ext, "-out", crt(name)});
  }
  [[nodiscard]] std::string key(const std::string& name) const { return (m_folder / (name + ".key")).string(); }
  [[nodiscard]] std::string crt(const std::string& name) const { return (m_folder / (name + ".crt")).string(); }

 private:
  void run(std::vector<std::string> argv) {
    const auto made = m_sut.run(std::move(argv));
    REQUIRE_MESSAGE(made.exitCode() == 0, made.describe());
  }
  harness::Harness& m_sut;
  fs::path m_folder;
  int m_serial{0};
};

constexpr const char* SERVER_EXTENSIONS = "basicConstraints=CA:FALSE\nextendedKeyUsage=serverAuth\n";
constexpr const char* CLIENT_EXTENSIONS = "basicConstraints=CA:FALSE\nextendedKeyUsage=clientAuth\n";

/// Messages under openvcu/<id>/.
std::vector<Message> of(const std::vector<Message>& messages, const std::string& id) {
  std::vector<Message> found;
  for (const Message& message : messages) {
    if (message.topic.starts_with("openvcu/" + id + "/")) found.push_back(message);
  }
  return found;
}

bool has(const std::vector<Message>& messages, const std::string& topic) {
  return std::ranges::any_of(messages, [&](const Message& message) { return message.topic == topic; });
}

/// A subscriber over TLS to 127.0.0.1:`port`, connected (retried while mosquitto starts).
void connectTls(Subscriber& subscriber, const TlsClientFiles& files) {
  REQUIRE(subscriber.useTls(files));
  bool connected = false;
  for (int attempt = 0; attempt < 50 && !(connected = subscriber.connect()); ++attempt) {
    std::this_thread::sleep_for(100ms);
  }
  REQUIRE(connected);
}

}  // namespace

TEST_CASE(
    "vcu-telemetry over TLS: its client certificate lets it in, a certificate of another CA is refused by the broker, "
    "a broker certificate of another CA or for another name is refused by vcu-telemetry") {
  if (!harness::isolated()) OPENVCU_SKIP(harness::NOT_ISOLATED);
  if (!fs::exists("/usr/sbin/mosquitto")) {
    OPENVCU_SKIP("skipped: needs mosquitto (Debian's mosquitto package; scripts/install-deps.sh)");
  }
  if (!fs::exists(OPENSSL)) OPENVCU_SKIP("skipped: needs the openssl command (Debian's openssl package)");
  const std::string bin = OPENVCU_BINARY_DIR "/bin";
  harness::Harness sut;
  const fs::path work = fs::temp_directory_path() / "telemetry-tls";  // the sandbox's own /tmp
  fs::remove_all(work);

  // the keys and certificates, made now
  Pki pki(sut, work / "pki");
  pki.ca("ca", "openvcu test CA");
  pki.ca("other-ca", "another CA");
  pki.issue("server", "localhost", "ca", std::string(SERVER_EXTENSIONS) + "subjectAltName=IP:127.0.0.1,DNS:localhost\n");
  pki.issue("server-other-ca", "localhost", "other-ca",
            std::string(SERVER_EXTENSIONS) + "subjectAltName=IP:127.0.0.1,DNS:localhost\n");
  pki.issue("server-wrong-name", "broker.invalid", "ca",
            std::string(SERVER_EXTENSIONS) + "subjectAltName=DNS:broker.invalid\n");
  for (const char* id : {"hhea-01", "hhea-03", "hhea-04", "fleet-watcher"}) pki.issue(id, id, "ca", CLIENT_EXTENSIONS);
  pki.issue("hhea-02", "hhea-02", "other-ca", CLIENT_EXTENSIONS);

  const auto listener = [&](int port, const std::string& server) {
    return telemetry_test::TlsListener{.port = port, .caFile = pki.crt("ca"), .certFile = pki.crt(server),
                                       .keyFile = pki.key(server)};
  };
  REQUIRE_STATUS(sut.start(telemetry_test::tlsBrokerSpec(
      work / "broker", fs::path(OPENVCU_SOURCE_DIR) / "services/telemetry/examples/acl",
      {listener(GOOD_PORT, "server"), listener(OTHER_CA_PORT, "server-other-ca"),
       listener(WRONG_NAME_PORT, "server-wrong-name")})));
  bool up = false;
  for (int attempt = 0; attempt < 100 && !(up = listening(WRONG_NAME_PORT)); ++attempt) {
    std::this_thread::sleep_for(50ms);
  }
  REQUIRE_MESSAGE(up, "mosquitto does not listen on 127.0.0.1:8885");

  const TlsClientFiles watcher{.caFile = pki.crt("ca"), .certFile = pki.crt("fleet-watcher"),
                               .keyFile = pki.key("fleet-watcher")};
  Subscriber subscriber("tls-watcher", false, nullptr, nullptr, GOOD_PORT);
  connectTls(subscriber, watcher);

  // the vehicles: each a copy of config/hhea with its own telemetry.json (mqtts://, its files)
  // and its own instance; hhea-01 sends the SOC at 10 Hz
  const auto vehicleFolder = [&](const std::string& id, int port, const std::string& clientCert) {
    const fs::path folder = work / id;
    fs::create_directories(folder);
    for (const auto& entry : fs::directory_iterator(fs::path(OPENVCU_SOURCE_DIR) / "config/hhea")) {
      if (entry.is_regular_file()) fs::copy_file(entry.path(), folder / entry.path().filename());
    }
    writeFile(folder / "telemetry.json",
              Json{{"broker", "mqtts://127.0.0.1:" + std::to_string(port)},
                   {"vehicleId", id},
                   {"tls", {{"caFile", pki.crt("ca")}, {"certFile", pki.crt(clientCert)}, {"keyFile", pki.key(clientCert)}}},
                   {"queueFolder", (work / ("queue-" + id)).string()},
                   {"signals", {{{"name", SOC_KEY}, {"maxRateHz", 10}, {"deadband", 0}}}}}
                  .dump(2));
    return (folder / "vehicle.json").string();
  };
  const std::string goodPath = vehicleFolder("hhea-01", GOOD_PORT, "hhea-01");
  auto config = config::loadVehicleConfig(goodPath);
  REQUIRE_STATUS(config);
  auto catalog = config::buildCatalog(*config);
  REQUIRE_STATUS(catalog);
  auto table = signals::SignalTable::open(*catalog, "tls-hhea-01");
  REQUIRE_STATUS(table);
  const auto soc = *catalog->indexOf(SOC_KEY);
  telemetry_test::PeriodicWriter writer(50ms, [&](int step) {
    table->writeBus(soc, 50 + (step % 2) * 0.1, clock::monotonicNs(), 0xF3, signals::Quality::Valid);
  });

  const auto startBridge = [&](const std::string& id, const std::string& vehiclePath) {
    auto bridge = sut.start({.name = "vcu-telemetry-" + id,
                             .argv = {bin + "/vcu-telemetry", "--config", vehiclePath, "--instance", "tls-" + id},
                             .notifyReadiness = true,
                             .captureOutput = true});
    REQUIRE_STATUS(bridge);
    return *bridge;
  };
  harness::Process* good = startBridge("hhea-01", goodPath);
  harness::Process* otherCaClient = startBridge("hhea-02", vehicleFolder("hhea-02", GOOD_PORT, "hhea-02"));
  harness::Process* otherCaBroker = startBridge("hhea-03", vehicleFolder("hhea-03", OTHER_CA_PORT, "hhea-03"));
  harness::Process* wrongNameBroker = startBridge("hhea-04", vehicleFolder("hhea-04", WRONG_NAME_PORT, "hhea-04"));

  // 1. hhea-01 is let in: online, its birth, then signals records with rising seq
  REQUIRE_MESSAGE(subscriber.waitFor(
                      [](const std::vector<Message>& messages) {
                        std::vector<std::uint64_t> seqs;
                        for (const Message& message : of(messages, "hhea-01")) {
                          if (message.topic.ends_with("/signals")) seqs.push_back(message.body["seq"].get<std::uint64_t>());
                        }
                        return has(messages, "openvcu/hhea-01/birth") && seqs.size() >= 3 &&
                               std::ranges::is_sorted(seqs) && seqs.front() < seqs.back();
                      },
                      8s),
                  good->output());
  const auto goodMessages = of(subscriber.messages(), "hhea-01");
  CHECK(std::ranges::any_of(goodMessages, [](const Message& message) {
    return message.topic == "openvcu/hhea-01/status" && message.body == "online";
  }));
  for (const Message& message : goodMessages) {
    if (!message.topic.ends_with("/signals")) continue;
    CHECK(message.body["names"] == Json::array({SOC_KEY}));
    CHECK(!message.body["samples"].empty());
  }
  CHECK_MESSAGE(good->waitForLine("connected to the broker", 1s), good->output());

  // a later subscriber gets the status and birth retained; so do subscribers on the other two
  // listeners when they trust that listener's certificate (they are not broken listeners)
  Subscriber later("tls-later", false, nullptr, nullptr, GOOD_PORT);
  connectTls(later, watcher);
  Subscriber trustsOtherCa("tls-other-ca", false, nullptr, nullptr, OTHER_CA_PORT);
  connectTls(trustsOtherCa, {.caFile = pki.crt("other-ca"), .certFile = pki.crt("fleet-watcher"),
                             .keyFile = pki.key("fleet-watcher")});
  Subscriber noNameCheck("tls-no-name-check", false, nullptr, nullptr, WRONG_NAME_PORT);
  connectTls(noNameCheck, {.caFile = pki.crt("ca"), .certFile = pki.crt("fleet-watcher"),
                           .keyFile = pki.key("fleet-watcher"), .insecure = true});
  const auto retainedBirthAndStatus = [](const std::vector<Message>& messages) {
    const auto retained = [&](const std::string& topic) {
      return std::ranges::any_of(messages, [&](const Message& m) { return m.topic == topic && m.retained; });
    };
    return retained("openvcu/hhea-01/status") && retained("openvcu/hhea-01/birth");
  };
  CHECK(later.waitFor(retainedBirthAndStatus, 5s));
  CHECK(trustsOtherCa.waitFor(retainedBirthAndStatus, 5s));
  CHECK(noNameCheck.waitFor(retainedBirthAndStatus, 5s));

  // 2. and 3.: each tried and failed (its log), and nothing under its id reached any subscriber
  // (twice: it keeps retrying, records wait in its queue)
  for (harness::Process* refused : {otherCaClient, otherCaBroker, wrongNameBroker}) {
    CHECK_MESSAGE(refused->waitForLine("TLS handshake failed", 5s), refused->output());
    CHECK_MESSAGE(refused->waitForLine("TLS handshake failed", 5s), refused->output());
    CHECK_MESSAGE(refused->output().find("connected to the broker") == std::string::npos, refused->output());
    CHECK_MESSAGE(refused->running(), refused->output());
  }
  for (const char* id : {"hhea-02", "hhea-03", "hhea-04"}) {
    for (Subscriber* watching : {&subscriber, &later, &trustsOtherCa, &noNameCheck}) {
      const auto seen = of(watching->messages(), id);
      CHECK_MESSAGE(seen.empty(), id << ": " << seen.size() << " message(s), first on " << (seen.empty() ? std::string() : seen.front().topic));
    }
  }
}
