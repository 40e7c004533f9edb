// Unit tests of openvcu::ipc that need no RouDi and no network: the event bus over LCM's
// in-process memq:// transport, the names, and the errors before a Runtime exists.

#include <doctest/doctest.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>

#include <chrono>
#include <optional>
#include <stdexcept>

#include "openvcu/ipc/command_socket.hpp"
#include "openvcu/ipc/event_bus.hpp"
#include "openvcu/ipc/frame_stream.hpp"
#include "openvcu/ipc/host_filter.hpp"
#include "openvcu/ipc/topics.hpp"
#include "openvcu/ipc/waiter.hpp"

namespace ipc = openvcu::ipc;
using namespace std::chrono_literals;

namespace {

constexpr auto MEMQ_URL = "memq://";
constexpr std::int64_t SOME_TIME_NS = 1'700'000'000'123'456'789;

ipc::EventBus openMemq(std::string_view instance = "test") {
  auto openResult = ipc::EventBus::open(MEMQ_URL, instance);
  REQUIRE_MESSAGE(openResult.ok(), (openResult.ok() ? "" : openResult.error().toString()));
  return std::move(*openResult);
}

/// Publishes `message` and dispatches until the callback registered by `subscribe` has seen it.
template <typename Message, typename Subscribe>
std::optional<Message> roundTrip(ipc::EventBus& sut, Subscribe subscribe, const Message& message) {
  std::optional<Message> received;
  auto subscription = subscribe([&](const Message& m) { received = m; });
  REQUIRE(subscription.ok());
  REQUIRE(sut.publish(message));
  sut.handleAll();
  sut.unsubscribe(*subscription);
  return received;
}

}  // namespace

TEST_CASE("channel names are OPENVCU_<INSTANCE>_<KIND> with the instance in upper case") {
  CHECK(ipc::channelName("hhea", ipc::EventKind::Heartbeat) == "OPENVCU_HHEA_HEARTBEAT");
  CHECK(ipc::channelName("bench-2", ipc::EventKind::Command) == "OPENVCU_BENCH-2_COMMAND");
  CHECK(ipc::channelName("hhea", ipc::EventKind::Ack) == "OPENVCU_HHEA_ACK");
  CHECK(ipc::channelName("hhea", ipc::EventKind::Fsm) == "OPENVCU_HHEA_FSM");
  CHECK(ipc::channelName("hhea", ipc::EventKind::Fault) == "OPENVCU_HHEA_FAULT");
  CHECK(ipc::channelName("hhea", ipc::EventKind::Log) == "OPENVCU_HHEA_LOG");
  CHECK(ipc::channelName("hhea", ipc::EventKind::Snapshot) == "OPENVCU_HHEA_SNAPSHOT");
  CHECK(ipc::channelName("hhea", ipc::EventKind::Stats) == "OPENVCU_HHEA_STATS");
  CHECK(ipc::channelName("hhea", ipc::EventKind::Schedule) == "OPENVCU_HHEA_SCHEDULE");
  CHECK(ipc::channelName("hhea", ipc::EventKind::J1939) == "OPENVCU_HHEA_J1939");
  CHECK(ipc::channelName("hhea", ipc::EventKind::Dm1) == "OPENVCU_HHEA_DM1");
}

TEST_CASE("a node's DM1 goes out and comes back field by field, extreme SPN, FMI, OC and CM included (#25)") {
  ipc::EventBus sut = openMemq("hhea");
  ipc::NodeDm1 sent{.timestampNs = SOME_TIME_NS, .service = "vcu-can-rx", .instance = "hhea", .bus = "vehicle",
                    .node = "BMS", .source = 0xF3, .lamps = 0x44, .flash = 0xFF, .dtcs = {}};
  sent.dtcs.push_back(ipc::NodeDtc{.spn = 524287, .fmi = 31, .occurrences = 127, .conversionMethod = true});
  sent.dtcs.push_back(ipc::NodeDtc{.spn = 100, .fmi = 1, .occurrences = 3, .conversionMethod = false});
  const auto received = roundTrip(sut, [&](auto callback) { return sut.onNodeDm1(callback); }, sent);
  REQUIRE(received.has_value());
  CHECK(*received == sent);
  CHECK(ipc::encodedSize(sent) < ipc::datagramPayloadLimit(sut.channel(ipc::EventKind::Dm1)));
}

TEST_CASE("a J1939 network view goes out and comes back field by field, a full NAME included (#24)") {
  ipc::EventBus sut = openMemq("hhea");
  ipc::J1939Network sent{.timestampNs = SOME_TIME_NS, .service = "vcu-can-tx", .instance = "hhea", .pid = 44,
                         .bus = "vehicle", .claimState = ipc::ClaimState::Claimed, .address = 0x21,
                         .name = 0xA00C'8100'0020'0001ull, .nodes = {}, .dtcs = {}, .lamps = 0x14};
  sent.nodes.push_back(ipc::J1939Node{0xF3, 0x8000'0000'0000'00F3ull});
  sent.nodes.push_back(ipc::J1939Node{0x10, 0x0123'4567'89AB'CDEFull});
  sent.dtcs.push_back(ipc::J1939Dtc{"Battery Fault", 520192, 31, 3, true});
  sent.dtcs.push_back(ipc::J1939Dtc{"Crash", 524287, 0, 126, false});
  std::vector<ipc::J1939Network> received;
  auto subscription = sut.onJ1939Network([&](const ipc::J1939Network& message) { received.push_back(message); });
  REQUIRE(subscription.ok());
  REQUIRE(sut.publish(sent));
  sut.handleAll();
  REQUIRE(received.size() == 1);
  CHECK(received[0] == sent);
  CHECK(ipc::claimStateName(received[0].claimState) == "claimed");
}

TEST_CASE("statistics and the transmit schedule go out in parts that each fit one datagram (#19)") {
  ipc::EventBus sut = openMemq("hhea");
  // 400 counters of 46-character names: about 24 kB, LCM would send it in 18 fragments
  ipc::Stats whole{.timestampNs = SOME_TIME_NS, .service = "vcu-can-rx", .instance = "hhea", .pid = 42, .part = 0,
                   .parts = 0, .counters = {}};
  for (int i = 0; i < 400; ++i) {
    whole.counters.push_back(ipc::Counter{"rx.Message_" + std::to_string(1000 + i) + "_PGN61234.max_period_us", i});
  }
  REQUIRE(ipc::encodedSize(whole) > 10 * ipc::LCM_DATAGRAM_BYTES);
  std::vector<ipc::Stats> parts;
  auto subscription = sut.onStats([&](const ipc::Stats& part) { parts.push_back(part); });
  REQUIRE(subscription.ok());
  REQUIRE(sut.publish(whole));
  sut.handleAll();
  REQUIRE(parts.size() > 10);
  std::vector<ipc::Counter> joined;
  for (std::size_t k = 0; k < parts.size(); ++k) {
    CHECK(parts[k].part == static_cast<std::int32_t>(k));
    CHECK(parts[k].parts == static_cast<std::int32_t>(parts.size()));
    CHECK(parts[k].timestampNs == SOME_TIME_NS);
    CHECK(parts[k].service == "vcu-can-rx");
    CHECK(parts[k].pid == 42);
    CHECK(ipc::encodedSize(parts[k]) <= ipc::datagramPayloadLimit(sut.channel(ipc::EventKind::Stats)));
    joined.insert(joined.end(), parts[k].counters.begin(), parts[k].counters.end());
  }
  CHECK(joined == whole.counters);

  ipc::TxSchedule schedule{.timestampNs = SOME_TIME_NS, .service = "vcu-can-tx", .instance = "hhea", .pid = 43,
                           .part = 0, .parts = 0, .entries = {}};
  for (int i = 0; i < 200; ++i) {
    schedule.entries.push_back(ipc::ScheduleEntry{"Message_" + std::to_string(i), 1000 * i, i % 2 == 0, i % 3 == 0});
  }
  std::vector<ipc::TxSchedule> scheduleParts;
  auto scheduleSubscription = sut.onSchedule([&](const ipc::TxSchedule& part) { scheduleParts.push_back(part); });
  REQUIRE(scheduleSubscription.ok());
  REQUIRE(sut.publish(schedule));
  sut.handleAll();
  REQUIRE(scheduleParts.size() > 1);
  std::vector<ipc::ScheduleEntry> entries;
  for (const ipc::TxSchedule& part : scheduleParts) {
    CHECK(part.parts == static_cast<std::int32_t>(scheduleParts.size()));
    CHECK(ipc::encodedSize(part) <= ipc::datagramPayloadLimit(sut.channel(ipc::EventKind::Schedule)));
    entries.insert(entries.end(), part.entries.begin(), part.entries.end());
  }
  CHECK(entries == schedule.entries);

  // a small message is one part; an empty one still tells "0 counters" in one part
  parts.clear();
  REQUIRE(sut.publish(ipc::Stats{.timestampNs = SOME_TIME_NS, .service = "s", .instance = "hhea", .pid = 1, .part = 7,
                                 .parts = 9, .counters = {{"vehicle.frames", 5}}}));
  sut.handleAll();
  REQUIRE(parts.size() == 1);
  CHECK(parts[0].part == 0);
  CHECK(parts[0].parts == 1);
}

TEST_CASE("frame topics name service openvcu, instance <instance>.<bus> and event rx/tx/send") {
  CHECK(ipc::FrameTopic{"hhea", "vehicle", ipc::FrameStream::Received}.toString() == "openvcu/hhea.vehicle/rx");
  CHECK(ipc::FrameTopic{"hhea", "battery", ipc::FrameStream::Sent}.toString() == "openvcu/hhea.battery/tx");
  CHECK(ipc::FrameTopic{"hhea", "vehicle", ipc::FrameStream::SendRequest}.toString() == "openvcu/hhea.vehicle/send");
}

TEST_CASE("names accept 1..32 characters of [A-Za-z0-9_-] only") {
  CHECK(ipc::isValidName("vehicle"));
  CHECK(ipc::isValidName("bus_2-a"));
  CHECK_FALSE(ipc::isValidName(""));
  CHECK_FALSE(ipc::isValidName("has.dot"));
  CHECK_FALSE(ipc::isValidName("OPENVCU_.*"));
  CHECK_FALSE(ipc::isValidName(std::string(33, 'a')));
}

TEST_CASE("the bus name hash is FNV-1a 32 bit and stable") {
  CHECK(ipc::fnv1a32("") == 0x811C9DC5u);
  CHECK(ipc::fnv1a32("a") == 0xE40C292Cu);
  static_assert(ipc::fnv1a32("vehicle") == ipc::fnv1a32("vehicle"));
}

TEST_CASE("every event type survives the trip through LCM's encoding unchanged") {
  ipc::EventBus sut = openMemq();

  // Requests travel on command sockets, in the same encoding (command_socket.hpp).
  const ipc::CommandRequest command{SOME_TIME_NS, 42,  "vcu-hmi",      ipc::CommandKind::SetOverride,
                                    "PDU.Relay1", 1.5, "commissioning", 987654321};
  const auto commandBytes = ipc::encodeCommandRequest(command);
  CHECK(ipc::decodeCommandRequest(commandBytes.data(), commandBytes.size()) == command);

  const ipc::CommandAck ack{SOME_TIME_NS, 42, "vcu-hmi", "vcu-fsm", false, "override forbidden in Driving"};
  CHECK(roundTrip(
            sut, [&](auto cb) { return sut.onAck(cb); }, ack) == ack);
  const ipc::CommandAck notMine{SOME_TIME_NS, 43, "vcu", "vcu-gpio", false, "", false};
  const auto ackBytes = ipc::encodeCommandAck(notMine);
  CHECK(ipc::decodeCommandAck(ackBytes.data(), ackBytes.size()) == notMine);

  const ipc::FsmTransition transition{SOME_TIME_NS, "Standby", "Precharge", "operator Start"};
  CHECK(roundTrip(
            sut, [&](auto cb) { return sut.onFsmTransition(cb); }, transition) == transition);

  const ipc::FaultEvent fault{SOME_TIME_NS, "BMS_Isolation",    "vcu-can-rx", ipc::FaultSeverity::Critical,
                              true,         "isolation 80 kOhm"};
  CHECK(roundTrip(
            sut, [&](auto cb) { return sut.onFault(cb); }, fault) == fault);

  const ipc::LogRecord log{SOME_TIME_NS, "vcu-can-tx", ipc::LogLevel::Warning, "schedule overrun 2.1 ms"};
  CHECK(roundTrip(
            sut, [&](auto cb) { return sut.onLog(cb); }, log) == log);

  const ipc::Heartbeat heartbeat{
      SOME_TIME_NS, "vcu-can-rx", "test", 1234, 98765, {{"frames_rx", 100000}, {"decode_errors", 3}}, "ok"};
  CHECK(roundTrip(
            sut, [&](auto cb) { return sut.onHeartbeat(cb); }, heartbeat) == heartbeat);

  const ipc::SignalSnapshot snapshot{
      SOME_TIME_NS, "vcu-can-rx", {{"BMS.SOC", 81.5, 1}, {"INV1.Speed", -1200.0, 3}, {"PDU.Relay1", 0.0, 0}}};
  CHECK(roundTrip(
            sut, [&](auto cb) { return sut.onSnapshot(cb); }, snapshot) == snapshot);
}

TEST_CASE("empty arrays, empty strings and unknown command kinds are carried as they are") {
  ipc::EventBus sut = openMemq();
  const ipc::Heartbeat quiet{SOME_TIME_NS, "", "", 0, 0, {}, ""};
  CHECK(roundTrip(
            sut, [&](auto cb) { return sut.onHeartbeat(cb); }, quiet) == quiet);
  const ipc::SignalSnapshot none{SOME_TIME_NS, "x", {}};
  CHECK(roundTrip(
            sut, [&](auto cb) { return sut.onSnapshot(cb); }, none) == none);
  constexpr auto UNKNOWN_KIND = static_cast<ipc::CommandKind>(99);
  const ipc::CommandRequest future{SOME_TIME_NS, 1, "vcu", UNKNOWN_KIND, "k", 0.0, ""};
  const auto bytes = ipc::encodeCommandRequest(future);
  const auto received = ipc::decodeCommandRequest(bytes.data(), bytes.size());
  REQUIRE(received);
  CHECK(received->kind == UNKNOWN_KIND);
}

TEST_CASE("a command message whose string length is INT32_MIN or beyond the message does not decode (fuzz_lcm)") {
  const ipc::CommandRequest request{SOME_TIME_NS, 7, "vcu", ipc::CommandKind::SetSignal, "internal.x", 1.0, "", 5};
  auto bytes = ipc::encodeCommandRequest(request);
  // hash (8), timestamp (8), request id (8), then the issuer's length: lcm-gen's decoder
  // copied ~2 GiB for INT32_MIN (SIGSEGV) before the layout check.
  constexpr std::size_t ISSUER_LENGTH = 24;
  for (const std::uint32_t length : {0x80000000u, 0xFFFFFFFFu, 0u, 0x7FFFFFFFu}) {
    auto forged = bytes;
    forged[ISSUER_LENGTH] = static_cast<std::uint8_t>(length >> 24);
    forged[ISSUER_LENGTH + 1] = static_cast<std::uint8_t>(length >> 16);
    forged[ISSUER_LENGTH + 2] = static_cast<std::uint8_t>(length >> 8);
    forged[ISSUER_LENGTH + 3] = static_cast<std::uint8_t>(length);
    CHECK_FALSE(ipc::decodeCommandRequest(forged.data(), forged.size()));
    auto ack = ipc::encodeCommandAck(ipc::CommandAck{SOME_TIME_NS, 7, "vcu", "vcu-fsm", true, ""});
    std::copy(forged.begin() + ISSUER_LENGTH, forged.begin() + ISSUER_LENGTH + 4, ack.begin() + ISSUER_LENGTH);
    CHECK_FALSE(ipc::decodeCommandAck(ack.data(), ack.size()));
  }
  CHECK(ipc::decodeCommandRequest(bytes.data(), bytes.size()) == request);
}

TEST_CASE("a command message that is cut, padded or of another type does not decode") {
  const ipc::CommandRequest request{SOME_TIME_NS, 7, "vcu", ipc::CommandKind::SetSignal, "internal.x", 1.0, "", 5};
  auto bytes = ipc::encodeCommandRequest(request);
  CHECK_FALSE(ipc::decodeCommandRequest(bytes.data(), bytes.size() - 1));
  bytes.push_back(0);
  CHECK_FALSE(ipc::decodeCommandRequest(bytes.data(), bytes.size()));
  const auto ackBytes = ipc::encodeCommandAck(ipc::CommandAck{SOME_TIME_NS, 7, "vcu", "vcu-fsm", true, ""});
  CHECK_FALSE(ipc::decodeCommandRequest(ackBytes.data(), ackBytes.size()));
  CHECK_FALSE(ipc::decodeCommandRequest(nullptr, 0));
}

TEST_CASE("publishing stamps the current time into a zero timestamp and keeps a given one") {
  ipc::EventBus sut = openMemq();
  const auto received = roundTrip(
      sut, [&](auto cb) { return sut.onLog(cb); }, ipc::LogRecord{0, "svc", {}, "t"});
  REQUIRE(received);
  const auto nowNs =
      std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch()).count();
  CHECK(received->timestampNs > nowNs - std::int64_t{60'000'000'000});
  CHECK(received->timestampNs <= nowNs);
}

TEST_CASE("messages reach only the subscriptions of their own instance and kind") {
  auto sutResult = ipc::EventBus::open(MEMQ_URL, "alpha");
  REQUIRE(sutResult.ok());
  ipc::EventBus& sut = *sutResult;
  int heartbeats = 0;
  int logs = 0;
  REQUIRE(sut.onHeartbeat([&](const ipc::Heartbeat&) { ++heartbeats; }).ok());
  REQUIRE(sut.onLog([&](const ipc::LogRecord&) { ++logs; }).ok());
  REQUIRE(sut.publish(ipc::Heartbeat{}));
  REQUIRE(sut.publish(ipc::Heartbeat{}));
  REQUIRE(sut.publish(ipc::FsmTransition{}));
  sut.handleAll();  // memq drops the transition at once: nobody subscribed to FSM
  CHECK(heartbeats == 2);
  CHECK(logs == 0);
  CHECK(sut.channel(ipc::EventKind::Heartbeat) == "OPENVCU_ALPHA_HEARTBEAT");
}

TEST_CASE("an unsubscribed callback is not called again") {
  ipc::EventBus sut = openMemq();
  int calls = 0;
  auto subscription = sut.onFault([&](const ipc::FaultEvent&) { ++calls; });
  REQUIRE(subscription.ok());
  REQUIRE(sut.publish(ipc::FaultEvent{}));
  sut.handleAll();
  sut.unsubscribe(*subscription);
  REQUIRE(sut.publish(ipc::FaultEvent{}));
  sut.handleAll();
  CHECK(calls == 1);
}

TEST_CASE("an exception thrown by a callback is caught and counted, later messages still arrive") {
  ipc::EventBus sut = openMemq();
  int calls = 0;
  REQUIRE(sut.onAck([&](const ipc::CommandAck&) {
               ++calls;
               if (calls == 1) throw std::runtime_error("callback bug");
             })
              .ok());
  REQUIRE(sut.publish(ipc::CommandAck{}));
  REQUIRE(sut.publish(ipc::CommandAck{}));
  sut.handleAll();
  CHECK(calls == 2);
  CHECK(sut.callbackErrors() == 1);
  CHECK(sut.decodeErrors() == 0);
}

TEST_CASE("handle times out when nothing was published and fileno is valid for poll") {
  ipc::EventBus sut = openMemq();
  CHECK(sut.fileno() >= 0);
  CHECK(sut.handle(0ms) == ipc::HandleResult::Timeout);
  CHECK(sut.handle(10ms) == ipc::HandleResult::Timeout);
}

TEST_CASE("opening the event bus fails with a clear error for a bad URL or instance") {
  auto badUrl = ipc::EventBus::open("bogus://nowhere", "test");
  REQUIRE_FALSE(badUrl.ok());
  CHECK(badUrl.error().message.find("bogus://nowhere") != std::string::npos);

  auto badInstance = ipc::EventBus::open(MEMQ_URL, "no spaces");
  REQUIRE_FALSE(badInstance.ok());
  CHECK(badInstance.error().message.find("invalid instance name") != std::string::npos);
}

TEST_CASE("a tcpq event URL is refused because its hub relays events from other hosts") {
  auto sut = ipc::EventBus::open("tcpq://127.0.0.1:7700", "test");
  REQUIRE_FALSE(sut.ok());
  CHECK(sut.error().message.find("refusing LCM URL tcpq://127.0.0.1:7700") != std::string::npos);
  CHECK(sut.error().message.find("another host") != std::string::npos);
}

TEST_CASE("a fault encoded for a datagram decodes to the same fault") {
  const ipc::FaultEvent fault{SOME_TIME_NS, "BMS_Isolation", "vcu-can-rx", ipc::FaultSeverity::Critical, true, "low"};
  const auto decoded = ipc::decodeFaultEvent(ipc::encodeFaultEvent(fault).data(), ipc::encodeFaultEvent(fault).size());
  REQUIRE(decoded);
  CHECK(*decoded == fault);
}

namespace {

/// A UDP socket on 127.0.0.1 (an ephemeral port), closed at the end of the scope;
/// `reuseAddress`: SO_REUSEADDR on, as LCM sets up its udpm receive socket.
struct LoopbackUdp {
  int fd{::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0)};
  sockaddr_in address{};
  explicit LoopbackUdp(bool reuseAddress = true) {
    address.sin_family = AF_INET;
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    REQUIRE(fd >= 0);
    const int on = reuseAddress ? 1 : 0;
    REQUIRE(::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &on, sizeof on) == 0);
    REQUIRE(::bind(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address) == 0);
    socklen_t length = sizeof address;
    REQUIRE(::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length) == 0);
  }
  LoopbackUdp(const LoopbackUdp&) = delete;
  LoopbackUdp& operator=(const LoopbackUdp&) = delete;
  ~LoopbackUdp() { ::close(fd); }
  [[nodiscard]] std::uint16_t port() const { return ntohs(address.sin_port); }
};

}  // namespace

TEST_CASE("a UDP socket restricted to this host still receives a datagram sent to it over loopback") {
  LoopbackUdp sut;
  LoopbackUdp sender;
  REQUIRE(ipc::acceptOnlyFromThisHost(sut.fd).ok());
  CHECK(ipc::acceptsOnlyFromThisHost(sut.fd));
  CHECK_FALSE(ipc::acceptsOnlyFromThisHost(sender.fd));

  const std::array<char, 5> sent{'h', 'e', 'l', 'l', 'o'};
  REQUIRE(::sendto(sender.fd, sent.data(), sent.size(), 0, reinterpret_cast<const sockaddr*>(&sut.address),
                   sizeof sut.address) == static_cast<ssize_t>(sent.size()));
  pollfd readable{sut.fd, POLLIN, 0};
  REQUIRE(::poll(&readable, 1, 1000) == 1);
  std::array<char, 16> received{};
  CHECK(::recv(sut.fd, received.data(), received.size(), 0) == static_cast<ssize_t>(sent.size()));
}

TEST_CASE("the host filter goes on a new UDP socket set up as LCM's receive socket and on no other") {
  LoopbackUdp older;
  const auto known = ipc::openSocketInodes();
  REQUIRE(known.ok());
  LoopbackUdp sut;
  LoopbackUdp withoutReuse(false);  // as LCM's send socket or a resolver's query socket
  LoopbackUdp otherPort;

  const auto restricted = ipc::restrictNewUdpSockets(*known, sut.port());
  REQUIRE_MESSAGE(restricted.ok(), (restricted.ok() ? "" : restricted.error().toString()));
  CHECK(*restricted == 1);
  CHECK(ipc::acceptsOnlyFromThisHost(sut.fd));
  CHECK_FALSE(ipc::acceptsOnlyFromThisHost(older.fd));
  CHECK_FALSE(ipc::acceptsOnlyFromThisHost(withoutReuse.fd));
  CHECK_FALSE(ipc::acceptsOnlyFromThisHost(otherPort.fd));
}

TEST_CASE("finding no new UDP socket bound to the port is an error that names the port") {
  LoopbackUdp older;
  const auto known = ipc::openSocketInodes();
  REQUIRE(known.ok());

  const auto sut = ipc::restrictNewUdpSockets(*known, older.port());
  REQUIRE_FALSE(sut.ok());
  CHECK(sut.error().message.find("no new UDP socket bound to port " + std::to_string(older.port())) !=
        std::string::npos);
  CHECK_FALSE(ipc::acceptsOnlyFromThisHost(older.fd));
}

TEST_CASE("frame streams and waiters refuse to open before the runtime is initialised") {
  auto publisher = ipc::FramePublisher::create({"test", "vehicle", ipc::FrameStream::Received});
  REQUIRE_FALSE(publisher.ok());
  CHECK(publisher.error().message.find("Runtime::init") != std::string::npos);
  auto subscriber = ipc::FrameSubscriber::create({"test", "vehicle", ipc::FrameStream::Received});
  REQUIRE_FALSE(subscriber.ok());
  auto waiter = ipc::Waiter::create();
  REQUIRE_FALSE(waiter.ok());
}
