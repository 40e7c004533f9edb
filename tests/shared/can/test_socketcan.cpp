// The socketcan link without a CAN kernel: the pure codec (exact SocketCAN bit patterns),
// and the link itself over a fake OS edge (an AF_UNIX SOCK_SEQPACKET socketpair carries the
// same 16/72-byte datagrams a raw CAN socket does). What needs a real kernel (vcan, error
// frames from a driver, SO_RXQ_OVFL, interface up/down) runs in the VM test bed.

#include <doctest/doctest.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>
#include <ctime>
#include <random>
#include <vector>

#include "openvcu/can/socketcan_codec.hpp"
#include "openvcu/can/socketcan_link.hpp"

using namespace openvcu;
using namespace openvcu::can;

namespace {

constexpr std::uint32_t STANDARD_ID = 0x123;
constexpr std::uint32_t EXTENDED_ID = 0x18FEF100;  // SAE J1939-71 PGN 65265 (0xFEF1) CCVS from SA 0x00

Frame makeFrame(std::uint32_t id, std::uint8_t flags, std::initializer_list<std::uint8_t> bytes) {
  Frame frame;
  frame.id = id;
  frame.flags = flags;
  frame.length = static_cast<std::uint8_t>(bytes.size());
  std::copy(bytes.begin(), bytes.end(), frame.data.begin());
  return frame;
}

bool sameFrame(const Frame& a, const Frame& b) {
  return a.id == b.id && a.flags == b.flags && a.length == b.length && a.data == b.data;
}

can_frame makeCanFrame(canid_t canId, std::initializer_list<std::uint8_t> bytes) {
  can_frame frame{};
  frame.can_id = canId;
  frame.len = static_cast<std::uint8_t>(bytes.size());
  std::copy(bytes.begin(), bytes.end(), frame.data);
  return frame;
}

/// An error frame as the kernel delivers it: CAN_ERR_FLAG | class, 8 data bytes.
Frame makeErrorFrame(std::uint32_t errorClass, std::array<std::uint8_t, 8> data) {
  can_frame raw{};
  raw.can_id = CAN_ERR_FLAG | errorClass;
  raw.len = CAN_ERR_DLC;
  std::copy(data.begin(), data.end(), raw.data);
  return fromCanFrame(raw);
}

std::int64_t nowNs(clockid_t clock) {
  timespec now{};
  clock_gettime(clock, &now);
  return std::int64_t{now.tv_sec} * 1'000'000'000 + now.tv_nsec;
}

// ----- a fake kernel: the link's socket is one end of a socketpair, the test holds the other

struct FakeKernel {
  std::vector<int> peers;  // test ends, one per successful open
  int failWith = 0;        // errno the next opens fail with (0: succeed)
  const char* failWhat = "";
  int opens = 0;
  SocketSetup lastSetup{};
  std::vector<can_filter> lastFilters;
  bool smallSendBuffer = false;

  FakeKernel() = default;
  FakeKernel(const FakeKernel&) = delete;
  FakeKernel& operator=(const FakeKernel&) = delete;
  ~FakeKernel() {
    for (const int fd : peers) {
      if (fd >= 0) close(fd);
    }
  }

  SocketOpener opener() {
    return [this](const SocketSetup& setup) {
      ++opens;
      lastSetup = setup;
      lastFilters.assign(setup.filters.begin(), setup.filters.end());
      if (failWith != 0) return SocketAttempt{-1, failWith, failWhat};
      std::array<int, 2> ends{};
      if (socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_NONBLOCK | SOCK_CLOEXEC, 0, ends.data()) != 0) {
        return SocketAttempt{-1, errno, "socketpair"};
      }
      const int on = 1;
      setsockopt(ends[0], SOL_SOCKET, SO_TIMESTAMPNS, &on, sizeof on);
      if (smallSendBuffer) {
        const int smallest = 1;  // the kernel rounds up to its minimum
        setsockopt(ends[0], SOL_SOCKET, SO_SNDBUF, &smallest, sizeof smallest);
      }
      peers.push_back(ends[1]);
      return SocketAttempt{ends[0], 0, ""};
    };
  }

  [[nodiscard]] int peer() const { return peers.back(); }
  void closePeer() {
    close(peers.back());
    peers.back() = -1;
  }
  void write(const can_frame& frame) const { REQUIRE(::send(peer(), &frame, sizeof frame, 0) == sizeof frame); }
  void write(const canfd_frame& frame) const { REQUIRE(::send(peer(), &frame, sizeof frame, 0) == sizeof frame); }
  /// One datagram the link sent, or empty.
  [[nodiscard]] std::vector<std::uint8_t> read() const {
    std::array<std::uint8_t, 128> buffer{};
    const ssize_t size = ::recv(peer(), buffer.data(), buffer.size(), MSG_DONTWAIT);
    if (size <= 0) return {};
    return {buffer.begin(), buffer.begin() + size};
  }
};

bool readable(int fd, int timeoutMs) {
  pollfd watch{fd, POLLIN, 0};
  return poll(&watch, 1, timeoutMs) > 0 && (watch.revents & POLLIN) != 0;
}

/// Upper bound for waiting on the link's own timer; the wait ends as soon as it fires.
constexpr int TIMER_WAIT_MS = 5000;
constexpr std::chrono::milliseconds FAST_REOPEN{10};

std::vector<BusEvent> drainEvents(Link& link) {
  std::vector<BusEvent> events;
  while (auto maybeEvent = link.nextEvent()) events.push_back(*maybeEvent);
  return events;
}

std::unique_ptr<Link> openFake(FakeKernel& kernel, const LinkOptions& options, const std::string& name = "vcan0") {
  auto openResult = openSocketCanLinkWith(name, options, kernel.opener());
  REQUIRE_MESSAGE(openResult.ok(), (openResult.ok() ? "" : openResult.error().toString()));
  return std::move(*openResult);
}

LinkOptions fastReopenOptions() {
  LinkOptions options;
  options.reopenInterval = FAST_REOPEN;
  return options;
}

}  // namespace

// ======================================================================= Frame -> kernel

TEST_CASE("a standard data frame becomes a can_frame with the bare ID") {
  can_frame sut{};

  REQUIRE(toCanFrame(makeFrame(STANDARD_ID, 0, {0x11, 0x22, 0x33}), sut));

  CHECK(sut.can_id == 0x123u);
  CHECK(sut.len == 3);
  CHECK(sut.data[0] == 0x11);
  CHECK(sut.data[2] == 0x33);
  CHECK(sut.data[3] == 0);
  CHECK(sut.__pad == 0);
  CHECK(sut.__res0 == 0);
  CHECK(sut.len8_dlc == 0);
}

TEST_CASE("an extended data frame carries CAN_EFF_FLAG in bit 31") {
  can_frame sut{};

  REQUIRE(toCanFrame(makeFrame(EXTENDED_ID, FLAG_EXTENDED, {1, 2, 3, 4, 5, 6, 7, 8}), sut));

  CHECK(sut.can_id == 0x98FEF100u);
  CHECK(sut.len == 8);
  CHECK(sut.data[7] == 8);
}

TEST_CASE("a remote frame carries CAN_RTR_FLAG in bit 30, its requested length and no data") {
  Frame standardRemote = makeFrame(STANDARD_ID, FLAG_RTR, {0xAA, 0xBB});
  standardRemote.length = 5;
  Frame extendedRemote = makeFrame(EXTENDED_ID, FLAG_RTR | FLAG_EXTENDED, {});
  can_frame sut{};

  REQUIRE(toCanFrame(standardRemote, sut));
  CHECK(sut.can_id == 0x40000123u);
  CHECK(sut.len == 5);
  CHECK(sut.data[0] == 0);
  REQUIRE(toCanFrame(extendedRemote, sut));
  CHECK(sut.can_id == 0xD8FEF100u);
}

TEST_CASE("a frame that cannot be classic is refused as a can_frame") {
  can_frame sut{};
  Frame nineBytes = makeFrame(STANDARD_ID, 0, {1, 2, 3, 4, 5, 6, 7, 8, 9});

  CHECK_FALSE(toCanFrame(nineBytes, sut));
  CHECK_FALSE(toCanFrame(makeFrame(STANDARD_ID, FLAG_FD, {1}), sut));
  CHECK_FALSE(toCanFrame(makeFrame(0x4, FLAG_ERROR, {0, 0, 0, 0, 0, 0, 0, 0}), sut));
  CHECK_FALSE(toCanFrame(makeFrame(0x800, 0, {}), sut));                   // 12 bits on a standard ID
  CHECK_FALSE(toCanFrame(makeFrame(0x20000000, FLAG_EXTENDED, {}), sut));  // 30 bits on an extended ID
  CHECK(toCanFrame(makeFrame(0x7FF, 0, {}), sut));
  CHECK(toCanFrame(makeFrame(0x1FFFFFFF, FLAG_EXTENDED, {}), sut));
}

TEST_CASE("an FD frame becomes a canfd_frame with FDF and its BRS/ESI flags") {
  canfd_frame sut{};

  REQUIRE(toCanFdFrame(makeFrame(STANDARD_ID, FLAG_FD | FLAG_BRS, {0xDE, 0xAD}), sut));
  CHECK(sut.can_id == 0x123u);
  CHECK(sut.len == 2);
  CHECK(sut.flags == 0x05);  // CANFD_FDF 0x04 | CANFD_BRS 0x01
  CHECK(sut.data[1] == 0xAD);

  REQUIRE(toCanFdFrame(makeFrame(EXTENDED_ID, FLAG_FD | FLAG_EXTENDED | FLAG_ESI, {}), sut));
  CHECK(sut.can_id == 0x98FEF100u);
  CHECK(sut.flags == 0x06);  // CANFD_FDF | CANFD_ESI 0x02
  CHECK(sut.__res0 == 0);
  CHECK(sut.__res1 == 0);
}

TEST_CASE("an FD length between the DLC steps is rounded up and zero padded") {
  Frame nineBytes = makeFrame(STANDARD_ID, FLAG_FD, {1, 2, 3, 4, 5, 6, 7, 8, 9});
  nineBytes.data[10] = 0xEE;  // beyond length: must not leak into the padding
  canfd_frame sut{};

  REQUIRE(toCanFdFrame(nineBytes, sut));

  CHECK(sut.len == 12);
  CHECK(sut.data[8] == 9);
  CHECK(sut.data[9] == 0);
  CHECK(sut.data[10] == 0);
  CHECK(sut.data[11] == 0);
}

TEST_CASE("a frame that cannot be CAN FD is refused as a canfd_frame") {
  canfd_frame sut{};
  Frame tooLong = makeFrame(STANDARD_ID, FLAG_FD, {});
  tooLong.length = 65;

  CHECK_FALSE(toCanFdFrame(makeFrame(STANDARD_ID, 0, {1}), sut));
  CHECK_FALSE(toCanFdFrame(makeFrame(STANDARD_ID, FLAG_FD | FLAG_RTR, {}), sut));
  CHECK_FALSE(toCanFdFrame(tooLong, sut));
  CHECK_FALSE(toCanFdFrame(makeFrame(0x800, FLAG_FD, {}), sut));
}

// ======================================================================= kernel -> Frame

TEST_CASE("a can_frame becomes a Frame with the flag bits moved out of the ID") {
  const Frame extended = fromCanFrame(makeCanFrame(0x98FEF100, {1, 2, 3}));
  const Frame standard = fromCanFrame(makeCanFrame(0x123, {0xAB}));

  CHECK(extended.id == EXTENDED_ID);
  CHECK(extended.flags == FLAG_EXTENDED);
  CHECK(extended.length == 3);
  CHECK(extended.data[2] == 3);
  CHECK(standard.id == 0x123u);
  CHECK(standard.flags == 0);
  CHECK(standard.data[0] == 0xAB);
}

TEST_CASE("a remote can_frame keeps its length but no data, standard or extended") {
  can_frame raw = makeCanFrame(0x40000123, {9, 9, 9, 9, 9});
  const Frame standard = fromCanFrame(raw);
  raw.can_id = 0xD8FEF100;
  const Frame extended = fromCanFrame(raw);

  CHECK(standard.flags == FLAG_RTR);
  CHECK(standard.id == 0x123u);
  CHECK(standard.length == 5);
  CHECK(standard.data[0] == 0);
  CHECK(extended.flags == (FLAG_RTR | FLAG_EXTENDED));
  CHECK(extended.id == EXTENDED_ID);
}

TEST_CASE("an error can_frame becomes FLAG_ERROR with the error class as ID") {
  const Frame sut = fromCanFrame(makeCanFrame(0x20000004, {0, 0x20, 0, 0, 0, 0, 0x80, 0x10}));

  CHECK(sut.flags == FLAG_ERROR);
  CHECK(sut.id == 0x4u);
  CHECK(sut.length == 8);
  CHECK(sut.data[1] == 0x20);
}

TEST_CASE("a can_frame claiming more than 8 bytes is cut to 8") {
  can_frame raw = makeCanFrame(0x123, {1, 2, 3, 4, 5, 6, 7, 8});
  raw.len = 15;
  raw.len8_dlc = 15;

  CHECK(fromCanFrame(raw).length == 8);
}

TEST_CASE("a canfd_frame becomes an FD Frame with BRS and ESI, and no remote flag") {
  canfd_frame raw{};
  raw.can_id = 0xC8FEF100;  // EFF | RTR: RTR means nothing on CAN FD
  raw.len = 64;
  raw.flags = 0x07;  // FDF | ESI | BRS
  raw.data[63] = 0x5A;

  const Frame sut = fromCanFdFrame(raw);

  CHECK(sut.id == 0x08FEF100u);
  CHECK(sut.flags == (FLAG_FD | FLAG_EXTENDED | FLAG_BRS | FLAG_ESI));
  CHECK(sut.length == 64);
  CHECK(sut.data[63] == 0x5A);
}

TEST_CASE("only 16- and 72-byte datagrams decode as frames") {
  std::array<std::uint8_t, 80> bytes{};
  const can_frame classic = makeCanFrame(0x123, {7});
  std::memcpy(bytes.data(), &classic, sizeof classic);

  const auto maybeClassic = decodeSocketFrame(std::span(bytes.data(), 16));
  const auto maybeFd = decodeSocketFrame(std::span(bytes.data(), 72));

  REQUIRE(maybeClassic);
  CHECK(maybeClassic->flags == 0);
  CHECK(maybeClassic->data[0] == 7);
  REQUIRE(maybeFd);
  CHECK(maybeFd->fd());
  CHECK_FALSE(decodeSocketFrame(std::span(bytes.data(), 0)));
  CHECK_FALSE(decodeSocketFrame(std::span(bytes.data(), 15)));
  CHECK_FALSE(decodeSocketFrame(std::span(bytes.data(), 73)));
}

TEST_CASE("encodeSocketFrame picks the datagram size by frame kind and link kind") {
  std::array<std::uint8_t, FD_DATAGRAM_SIZE> buffer{};
  const Frame classic = makeFrame(STANDARD_ID, 0, {1});
  const Frame fd = makeFrame(STANDARD_ID, FLAG_FD, {1});
  const Frame nineClassic = makeFrame(STANDARD_ID, 0, {1, 2, 3, 4, 5, 6, 7, 8, 9});

  CHECK(encodeSocketFrame(classic, false, buffer) == 16);
  CHECK(encodeSocketFrame(classic, true, buffer) == 16);
  CHECK(encodeSocketFrame(fd, true, buffer) == 72);
  CHECK(encodeSocketFrame(fd, false, buffer) == 0);
  CHECK(encodeSocketFrame(nineClassic, true, buffer) == 0);
}

TEST_CASE("encode then decode gives back every valid frame") {
  std::mt19937 random(20240301);
  std::uniform_int_distribution<int> byte(0, 255);
  std::array<std::uint8_t, FD_DATAGRAM_SIZE> buffer{};
  constexpr int ROUNDS = 2000;
  for (int round = 0; round < ROUNDS; ++round) {
    Frame frame;
    const int kind = round % 4;  // standard, extended, remote, FD
    frame.flags = static_cast<std::uint8_t>((kind == 1 || round % 8 == 3) ? FLAG_EXTENDED : 0);
    frame.id = static_cast<std::uint32_t>(random()) & (frame.extended() ? EXTENDED_ID_MASK : STANDARD_ID_MASK);
    if (kind == 3) {
      frame.flags |= FLAG_FD;
      if (byte(random) & 1) frame.flags |= FLAG_BRS;
      if (byte(random) & 1) frame.flags |= FLAG_ESI;
      frame.length = dlcToLength(static_cast<std::uint8_t>(byte(random) & 0x0F));
    } else {
      frame.length = static_cast<std::uint8_t>(byte(random) % 9);
    }
    if (kind == 2) frame.flags |= FLAG_RTR;
    if (kind != 2) {
      for (std::size_t i = 0; i < frame.length; ++i) frame.data[i] = static_cast<std::uint8_t>(byte(random));
    }

    const std::size_t size = encodeSocketFrame(frame, true, buffer);
    REQUIRE(size != 0);
    const auto maybeBack = decodeSocketFrame(std::span(buffer.data(), size));

    REQUIRE(maybeBack);
    CHECK(sameFrame(*maybeBack, frame));
  }
}

// ======================================================================= error frames

TEST_CASE("a controller error frame with counters gives the worst state with both counters") {
  // data[1] 0x24: TX passive and RX warning; CAN_ERR_CNT: TX 0x80 (128), RX 0x60 (96).
  const Frame frame = makeErrorFrame(CAN_ERR_CRTL | CAN_ERR_CNT, {0, 0x24, 0, 0, 0, 0, 0x80, 0x60});
  std::array<BusEvent, MAX_ERROR_EVENTS> sut{};
  constexpr std::int64_t WHEN = 123456789;

  REQUIRE(decodeErrorFrame(frame, WHEN, sut) == 1);

  CHECK(sut[0].kind == BusEventKind::ErrorPassive);
  CHECK(sut[0].monotonicNs == WHEN);
  CHECK(sut[0].detail == 0x00240204u);
  CHECK(sut[0].txErrors == 0x80);
  CHECK(sut[0].rxErrors == 0x60);
}

TEST_CASE("controller warning, active and overflow bits give their own events") {
  std::array<BusEvent, MAX_ERROR_EVENTS> sut{};

  REQUIRE(decodeErrorFrame(makeErrorFrame(CAN_ERR_CRTL, {0, 0x08, 0, 0, 0, 0, 0x60, 0}), 0, sut) == 1);
  CHECK(sut[0].kind == BusEventKind::ErrorWarning);
  CHECK(sut[0].detail == 0x00080004u);
  CHECK(sut[0].txErrors == 0);  // no CAN_ERR_CNT: the counter bytes are not trusted

  REQUIRE(decodeErrorFrame(makeErrorFrame(CAN_ERR_CRTL, {0, 0x40, 0, 0, 0, 0, 0, 0}), 0, sut) == 1);
  CHECK(sut[0].kind == BusEventKind::ErrorActive);

  REQUIRE(decodeErrorFrame(makeErrorFrame(CAN_ERR_CRTL, {0, 0x03, 0, 0, 0, 0, 0, 0}), 0, sut) == 2);
  CHECK(sut[0].kind == BusEventKind::RxOverflow);
  CHECK(sut[0].detail == 0x00030004u);
  CHECK(sut[1].kind == BusEventKind::TxTimeout);

  CHECK(decodeErrorFrame(makeErrorFrame(CAN_ERR_CRTL, {}), 0, sut) == 0);  // CAN_ERR_CRTL_UNSPEC
}

TEST_CASE("bus-off, restart, no-ACK, TX timeout and transceiver classes map one to one") {
  std::array<BusEvent, MAX_ERROR_EVENTS> sut{};

  REQUIRE(decodeErrorFrame(makeErrorFrame(CAN_ERR_BUSOFF, {}), 0, sut) == 1);
  CHECK(sut[0].kind == BusEventKind::BusOff);
  CHECK(sut[0].detail == 0x40u);
  REQUIRE(decodeErrorFrame(makeErrorFrame(CAN_ERR_RESTARTED, {}), 0, sut) == 1);
  CHECK(sut[0].kind == BusEventKind::Restarted);
  CHECK(sut[0].detail == 0x100u);
  REQUIRE(decodeErrorFrame(makeErrorFrame(CAN_ERR_ACK, {}), 0, sut) == 1);
  CHECK(sut[0].kind == BusEventKind::NoAck);
  REQUIRE(decodeErrorFrame(makeErrorFrame(CAN_ERR_TX_TIMEOUT, {}), 0, sut) == 1);
  CHECK(sut[0].kind == BusEventKind::TxTimeout);
  CHECK(sut[0].detail == 0x1u);
  REQUIRE(decodeErrorFrame(makeErrorFrame(CAN_ERR_TRX, {0, 0, 0, 0, 0x70, 0, 0, 0}), 0, sut) == 1);
  CHECK(sut[0].kind == BusEventKind::TransceiverError);
  CHECK(sut[0].detail == 0x00700010u);  // CAN_ERR_TRX_CANL_SHORT_TO_GND
}

TEST_CASE("a protocol error keeps its type and location in the detail") {
  // data[2] 0x04 stuff error, data[3] 0x0A in the data section.
  const Frame frame = makeErrorFrame(CAN_ERR_PROT | CAN_ERR_BUSERROR, {0, 0, 0x04, 0x0A, 0, 0, 0, 0});
  std::array<BusEvent, MAX_ERROR_EVENTS> sut{};

  REQUIRE(decodeErrorFrame(frame, 0, sut) == 1);

  CHECK(sut[0].kind == BusEventKind::ProtocolError);
  CHECK(sut[0].detail == 0x0A040088u);
  REQUIRE(decodeErrorFrame(makeErrorFrame(CAN_ERR_BUSERROR, {}), 0, sut) == 1);
  CHECK(sut[0].kind == BusEventKind::ProtocolError);
}

TEST_CASE("lost arbitration yields no event and a data frame yields nothing") {
  std::array<BusEvent, MAX_ERROR_EVENTS> sut{};

  CHECK(decodeErrorFrame(makeErrorFrame(CAN_ERR_LOSTARB, {5, 0, 0, 0, 0, 0, 0, 0}), 0, sut) == 0);
  CHECK(decodeErrorFrame(makeFrame(CAN_ERR_BUSOFF, 0, {}), 0, sut) == 0);
}

TEST_CASE("an error frame with every class set fills all event slots in the documented order") {
  const std::uint32_t everything = CAN_ERR_MASK & 0x3FFu;
  const Frame frame = makeErrorFrame(everything, {0, 0x73, 0x01, 0x02, 0x04, 0, 0xF0, 0x0F});
  std::array<BusEvent, MAX_ERROR_EVENTS> sut{};

  REQUIRE(decodeErrorFrame(frame, 0, sut) == MAX_ERROR_EVENTS);

  const std::array<BusEventKind, MAX_ERROR_EVENTS> expected{
      BusEventKind::TxTimeout,    BusEventKind::RxOverflow,    BusEventKind::TxTimeout,
      BusEventKind::ErrorPassive, BusEventKind::ProtocolError, BusEventKind::TransceiverError,
      BusEventKind::NoAck,        BusEventKind::BusOff,        BusEventKind::Restarted};
  for (std::size_t i = 0; i < MAX_ERROR_EVENTS; ++i) {
    CAPTURE(i);
    CHECK(sut[i].kind == expected[i]);
    CHECK(sut[i].txErrors == 0xF0);
    CHECK(sut[i].rxErrors == 0x0F);
  }
}

// ======================================================================= filters

TEST_CASE("a standard filter masks EFF and RTR so it matches standard data frames only") {
  const can_filter sut = toKernelFilter(IdFilter{0x123, 0x7FF, false});

  CHECK(sut.can_id == 0x123u);
  CHECK(sut.can_mask == 0xC00007FFu);  // CAN_EFF_FLAG | CAN_RTR_FLAG | mask
}

TEST_CASE("an extended filter sets EFF in the ID and masks EFF and RTR") {
  const can_filter sut = toKernelFilter(IdFilter{EXTENDED_ID, 0x03FFFF00, true});

  CHECK(sut.can_id == 0x98FEF100u);
  CHECK(sut.can_mask == 0xC3FFFF00u);
}

TEST_CASE("filter bits beyond the ID width are dropped and the inversion bit is never set") {
  const can_filter standard = toKernelFilter(IdFilter{0xFFFFFFFF, 0xFFFFFFFF, false});
  const can_filter extended = toKernelFilter(IdFilter{0xFFFFFFFF, 0xFFFFFFFF, true});

  CHECK(standard.can_id == 0x7FFu);
  CHECK(standard.can_mask == 0xC00007FFu);
  CHECK(extended.can_id == 0x9FFFFFFFu);
  CHECK(extended.can_mask == 0xDFFFFFFFu);
  CHECK((standard.can_id & CAN_INV_FILTER) == 0);
  CHECK((extended.can_id & CAN_INV_FILTER) == 0);
}

TEST_CASE("filters that can never match are left out of the kernel list") {
  const std::vector<IdFilter> filters{{0x923, 0xFFF, false}, {0x100, 0x700, false}};

  const std::vector<can_filter> sut = toKernelFilters(filters);

  REQUIRE(sut.size() == 1);
  CHECK(sut[0].can_id == 0x100u);
  CHECK(sut[0].can_mask == 0xC0000700u);
}

TEST_CASE("the kernel takes up to CAN_RAW_FILTER_MAX filters") {
  CHECK(fitsKernelFilters(0));
  CHECK(fitsKernelFilters(512));
  CHECK_FALSE(fitsKernelFilters(513));
}

TEST_CASE("kernel filter matching equals acceptedByFilters on random frames and filters") {
  std::mt19937 random(42);
  const auto kernelAccepts = [](const std::vector<can_filter>& kernelFilters, bool installed, canid_t canId) {
    if (!installed) return true;
    return std::any_of(kernelFilters.begin(), kernelFilters.end(), [&](const can_filter& filter) {
      return (canId & filter.can_mask) == (filter.can_id & filter.can_mask);
    });
  };
  constexpr int ROUNDS = 3000;
  for (int round = 0; round < ROUNDS; ++round) {
    std::vector<IdFilter> filters(static_cast<std::size_t>(random() % 4));
    for (IdFilter& filter : filters) {
      filter.extended = (random() & 1) != 0;
      // Small ID space so that matches happen; now and then a bit beyond the ID width.
      filter.id = static_cast<std::uint32_t>(random() & 0xF) | ((random() % 16 == 0) ? 0x40000000u : 0u);
      filter.mask = (random() & 1) != 0 ? 0xFFFFFFFFu : static_cast<std::uint32_t>(random() & 0xF);
    }
    Frame frame;
    frame.id = static_cast<std::uint32_t>(random() & 0xF);
    if (random() & 1) frame.flags |= FLAG_EXTENDED;
    if (random() % 4 == 0) frame.flags |= FLAG_RTR;
    can_frame raw{};
    REQUIRE(toCanFrame(frame, raw));

    CAPTURE(round);
    CHECK(kernelAccepts(toKernelFilters(filters), !filters.empty(), raw.can_id) == acceptedByFilters(filters, frame));
  }
}

TEST_CASE("acceptedByFilters lets remote frames through only without filters, error frames always") {
  const std::vector<IdFilter> filters{{STANDARD_ID, 0x7FF, false}};
  const Frame remote = makeFrame(STANDARD_ID, FLAG_RTR, {});

  CHECK_FALSE(acceptedByFilters(filters, remote));
  CHECK(acceptedByFilters({}, remote));
  CHECK(acceptedByFilters(filters, makeFrame(STANDARD_ID, 0, {})));
  CHECK(acceptedByFilters(filters, makeFrame(0x4, FLAG_ERROR, {})));
}

// ======================================================================= control messages

namespace {

/// A msghdr with hand-made control messages, laid out as the kernel lays them out.
struct FakeMessage {
  alignas(cmsghdr) std::array<unsigned char, 256> control{};
  msghdr header{};
  std::size_t used = 0;

  void add(int level, int type, const void* payload, std::size_t size) {
    auto* item = reinterpret_cast<cmsghdr*>(control.data() + used);
    item->cmsg_level = level;
    item->cmsg_type = type;
    item->cmsg_len = CMSG_LEN(size);
    std::memcpy(CMSG_DATA(item), payload, size);
    used += CMSG_SPACE(size);
    header.msg_control = control.data();
    header.msg_controllen = used;
  }
};

}  // namespace

TEST_CASE("control messages give the receive stamp and the drop counter") {
  FakeMessage message;
  const timespec stamp{1436509052, 249713001};
  const std::uint32_t dropped = 17;
  message.add(SOL_SOCKET, SCM_TIMESTAMPNS, &stamp, sizeof stamp);
  message.add(SOL_SOCKET, SO_RXQ_OVFL, &dropped, sizeof dropped);

  const ReceiveMetadata sut = parseControlMessages(message.header);

  REQUIRE(sut.timestampNs);
  CHECK(*sut.timestampNs == 1436509052249713001);
  REQUIRE(sut.dropCount);
  CHECK(*sut.dropCount == 17u);
}

TEST_CASE("no control messages give no stamp and no drop counter") {
  msghdr empty{};
  FakeMessage otherLevel;
  const std::uint32_t value = 1;
  otherLevel.add(SOL_CAN_RAW, SO_RXQ_OVFL, &value, sizeof value);  // right type, wrong level

  CHECK_FALSE(parseControlMessages(empty).timestampNs);
  CHECK_FALSE(parseControlMessages(empty).dropCount);
  CHECK_FALSE(parseControlMessages(otherLevel.header).dropCount);
}

TEST_CASE("short or overlong control messages are ignored") {
  FakeMessage shortStamp;
  const std::uint32_t tooSmall = 5;
  shortStamp.add(SOL_SOCKET, SCM_TIMESTAMPNS, &tooSmall, sizeof tooSmall);  // 4 bytes, a timespec is 16
  FakeMessage overlong;
  const timespec stamp{1, 2};
  overlong.add(SOL_SOCKET, SCM_TIMESTAMPNS, &stamp, sizeof stamp);
  overlong.header.msg_controllen = CMSG_LEN(sizeof stamp) - 1;  // the buffer ends inside the message

  CHECK_FALSE(parseControlMessages(shortStamp.header).timestampNs);
  CHECK_FALSE(parseControlMessages(overlong.header).timestampNs);
}

TEST_CASE("a realtime stamp moves to the monotonic clock and never into the future") {
  CHECK(realtimeToMonotonic(1'000'000'000'500, 1'000'000'001'000, 7'000) == 6'500);
  CHECK(realtimeToMonotonic(1'000'000'002'000, 1'000'000'001'000, 7'000) == 7'000);
}

// ======================================================================= errors

TEST_CASE("open errors name the interface, the reason and the errno") {
  CHECK(openErrorMessage("can0", "", ENODEV) == "socketcan:can0: no such interface (ENODEV)");
  CHECK(openErrorMessage("vcan0", "", EAFNOSUPPORT) == "socketcan:vcan0: this kernel has no SocketCAN (EAFNOSUPPORT)");
  CHECK(openErrorMessage("lo", "", EMEDIUMTYPE) == "socketcan:lo: not a CAN interface (EMEDIUMTYPE)");
  CHECK(openErrorMessage("can0", "cannot bind", EADDRNOTAVAIL) ==
        "socketcan:can0: cannot bind: " + std::string(std::strerror(EADDRNOTAVAIL)) + " (EADDRNOTAVAIL)");
  CHECK(openErrorMessage("can0", "", 4000).find("(errno 4000)") != std::string::npos);
}

TEST_CASE("errno names cover the errors of a CAN socket") {
  CHECK(errnoName(ENETDOWN) == "ENETDOWN");
  CHECK(errnoName(EWOULDBLOCK) == "EAGAIN");
  CHECK(errnoName(ENOBUFS) == "ENOBUFS");
  CHECK(errnoName(0).empty());
}

TEST_CASE("interface names follow the kernel's rules") {
  CHECK(validInterfaceName("can0"));
  CHECK(validInterfaceName("vcan-test_15ch."));
  CHECK_FALSE(validInterfaceName(""));
  CHECK_FALSE(validInterfaceName("averyveryverylong"));
  CHECK_FALSE(validInterfaceName("can/0"));
  CHECK_FALSE(validInterfaceName("can:0"));
  CHECK_FALSE(validInterfaceName("can 0"));
  CHECK_FALSE(validInterfaceName(".."));
}

// ======================================================================= open on this kernel

namespace {
bool kernelHasSocketCan() {
  const int fd = socket(PF_CAN, SOCK_RAW, CAN_RAW);
  if (fd < 0) return false;
  close(fd);
  return true;
}
}  // namespace

TEST_CASE("opening a missing interface fails with a message naming it, CAN kernel or not") {
  const auto sut = openSocketCanLink("nonexistent0", LinkOptions{});

  REQUIRE_FALSE(sut.ok());
  if (kernelHasSocketCan()) {
    CHECK(sut.error().message == "socketcan:nonexistent0: no such interface (ENODEV)");
  } else {
    CHECK(sut.error().message == "socketcan:nonexistent0: this kernel has no SocketCAN (EAFNOSUPPORT)");
  }
}

TEST_CASE("opening a network interface that is not CAN fails clearly") {
  const auto sut = openSocketCanLink("lo", LinkOptions{});

  REQUIRE_FALSE(sut.ok());
  if (kernelHasSocketCan()) {
    CHECK(sut.error().message == "socketcan:lo: not a CAN interface (EMEDIUMTYPE)");
  } else {
    CHECK(sut.error().message == "socketcan:lo: this kernel has no SocketCAN (EAFNOSUPPORT)");
  }
}

TEST_CASE("an invalid interface name is refused before any socket is made") {
  const auto sut = openSocketCanLink("can/0", LinkOptions{});

  REQUIRE_FALSE(sut.ok());
  CHECK(sut.error().message.rfind("socketcan:can/0: not an interface name", 0) == 0);
}

// ======================================================================= the link over a fake kernel

TEST_CASE("a link that opens reports LinkUp first and a constant epoll wait handle") {
  FakeKernel kernel;

  auto sut = openFake(kernel, LinkOptions{});

  CHECK(sut->kind() == LinkKind::SocketCan);
  CHECK(sut->name() == "socketcan:vcan0");
  CHECK(sut->up());
  CHECK(sut->waitHandle().fd >= 0);
  CHECK(sut->waitHandle().source == nullptr);
  CHECK_FALSE(readable(sut->waitHandle().fd, 0));
  const auto events = drainEvents(*sut);
  REQUIRE(events.size() == 1);
  CHECK(events[0].kind == BusEventKind::LinkUp);
  CHECK(std::string(kernel.lastSetup.interfaceName) == "vcan0");
  CHECK(kernel.lastSetup.errorFrames);
  CHECK_FALSE(kernel.lastSetup.fd);
  CHECK_FALSE(kernel.lastSetup.kernelFilters);
}

TEST_CASE("the link receives classic and FD datagrams with their receive stamps") {
  FakeKernel kernel;
  LinkOptions options;
  options.fd = true;
  auto sut = openFake(kernel, options);
  canfd_frame fdFrame{};
  fdFrame.can_id = 0x456;
  fdFrame.len = 12;
  fdFrame.flags = 0x05;
  fdFrame.data[11] = 0x99;
  const std::int64_t realtimeBefore = nowNs(CLOCK_REALTIME);
  const std::int64_t monotonicBefore = nowNs(CLOCK_MONOTONIC);
  kernel.write(makeCanFrame(0x98FEF100, {1, 2}));
  kernel.write(fdFrame);
  std::array<ReceivedFrame, 8> batch{};

  REQUIRE(readable(sut->waitHandle().fd, 0));
  const std::size_t count = sut->receive(batch);

  REQUIRE(count == 2);
  CHECK(sameFrame(batch[0].frame, makeFrame(EXTENDED_ID, FLAG_EXTENDED, {1, 2})));
  CHECK(batch[1].frame.id == 0x456u);
  CHECK(batch[1].frame.flags == (FLAG_FD | FLAG_BRS));
  CHECK(batch[1].frame.data[11] == 0x99);
  for (const ReceivedFrame& received : std::span(batch.data(), count)) {
    CHECK(received.frame.timestampNs >= realtimeBefore);
    CHECK(received.frame.timestampNs <= nowNs(CLOCK_REALTIME));
    CHECK(received.monotonicNs <= nowNs(CLOCK_MONOTONIC));
    CHECK(received.monotonicNs >= monotonicBefore - 1'000'000);  // clock readings are not atomic
  }
  CHECK(sut->stats().framesReceived == 2);
  CHECK(kernel.lastSetup.fd);
  CHECK_FALSE(readable(sut->waitHandle().fd, 0));
}

TEST_CASE("receive fills at most out.size() frames and returns out.size() while more wait") {
  FakeKernel kernel;
  auto sut = openFake(kernel, LinkOptions{});
  constexpr int FRAMES = 5;
  for (int i = 0; i < FRAMES; ++i) kernel.write(makeCanFrame(static_cast<canid_t>(i), {}));
  std::array<ReceivedFrame, 2> batch{};

  CHECK(sut->receive(batch) == 2);
  CHECK(batch[1].frame.id == 1u);
  CHECK(sut->receive(batch) == 2);
  CHECK(sut->receive(batch) == 1);
  CHECK(batch[0].frame.id == 4u);
  CHECK(sut->receive(batch) == 0);
  CHECK(sut->receive(std::span<ReceivedFrame>{}) == 0);
}

TEST_CASE("error frames become bus events and are counted, not returned") {
  FakeKernel kernel;
  auto sut = openFake(kernel, LinkOptions{});
  drainEvents(*sut);
  // CAN_ERR_CRTL | CAN_ERR_BUSOFF | CAN_ERR_CNT, TX passive, TX 248 / RX 16.
  kernel.write(makeCanFrame(CAN_ERR_FLAG | 0x244, {0, 0x20, 0, 0, 0, 0, 248, 16}));
  kernel.write(makeCanFrame(0x123, {0x42}));
  std::array<ReceivedFrame, 8> batch{};

  REQUIRE(sut->receive(batch) == 1);

  CHECK(batch[0].frame.id == 0x123u);
  CHECK(sut->stats().errorFrames == 1);
  CHECK(sut->stats().framesReceived == 1);
  const auto events = drainEvents(*sut);
  REQUIRE(events.size() == 2);
  CHECK(events[0].kind == BusEventKind::ErrorPassive);
  CHECK(events[1].kind == BusEventKind::BusOff);
  CHECK(events[1].txErrors == 248);
  CHECK(events[1].rxErrors == 16);
  CHECK(events[1].monotonicNs > 0);
}

TEST_CASE("up to 512 filters go to the kernel with the flag bits") {
  FakeKernel kernel;
  LinkOptions options;
  options.filters = {{0x100, 0x7F0, false}, {EXTENDED_ID, 0x1FFFFFFF, true}};

  auto sut = openFake(kernel, options);

  CHECK(kernel.lastSetup.kernelFilters);
  REQUIRE(kernel.lastFilters.size() == 2);
  CHECK(kernel.lastFilters[0].can_id == 0x100u);
  CHECK(kernel.lastFilters[0].can_mask == 0xC00007F0u);
  CHECK(kernel.lastFilters[1].can_id == 0x98FEF100u);
  CHECK(kernel.lastFilters[1].can_mask == 0xDFFFFFFFu);
}

TEST_CASE("filters that cannot match install an empty kernel list, which receives nothing") {
  FakeKernel kernel;
  LinkOptions options;
  options.filters = {{0x923, 0xFFF, false}};

  auto sut = openFake(kernel, options);

  CHECK(kernel.lastSetup.kernelFilters);
  CHECK(kernel.lastFilters.empty());
}

TEST_CASE("more filters than the kernel takes are applied in user space and counted") {
  FakeKernel kernel;
  LinkOptions options;
  constexpr std::uint32_t FILTERS = 600;
  for (std::uint32_t i = 0; i < FILTERS; ++i) options.filters.push_back({0x100 + i, 0x7FF, false});
  auto sut = openFake(kernel, options);
  kernel.write(makeCanFrame(0x100, {1}));                 // passes
  kernel.write(makeCanFrame(0x7FF, {2}));                 // no filter for it
  kernel.write(makeCanFrame(CAN_RTR_FLAG | 0x100, {}));   // remote: filters take data frames only
  kernel.write(makeCanFrame(CAN_EFF_FLAG | 0x100, {3}));  // 29-bit ID, 11-bit filters
  std::array<ReceivedFrame, 8> batch{};

  REQUIRE(sut->receive(batch) == 1);

  CHECK_FALSE(kernel.lastSetup.kernelFilters);
  CHECK(batch[0].frame.data[0] == 1);
  CHECK(sut->stats().filteredOut == 3);
  CHECK(sut->stats().framesReceived == 1);
}

TEST_CASE("send writes the can_frame or canfd_frame datagram the kernel expects") {
  FakeKernel kernel;
  LinkOptions options;
  options.fd = true;
  auto sut = openFake(kernel, options);

  CHECK(sut->send(makeFrame(EXTENDED_ID, FLAG_EXTENDED, {0xAA, 0xBB})) == SendStatus::Sent);
  CHECK(sut->send(makeFrame(STANDARD_ID, FLAG_FD | FLAG_BRS, {1, 2, 3, 4, 5, 6, 7, 8, 9})) == SendStatus::Sent);

  const std::vector<std::uint8_t> classic = kernel.read();
  REQUIRE(classic.size() == 16);
  CHECK(classic[0] == 0x00);  // can_id 0x98FEF100, little endian on x86-64 and ARM
  CHECK(classic[1] == 0xF1);
  CHECK(classic[2] == 0xFE);
  CHECK(classic[3] == 0x98);
  CHECK(classic[4] == 2);  // len
  CHECK(classic[8] == 0xAA);
  CHECK(classic[9] == 0xBB);
  const std::vector<std::uint8_t> fd = kernel.read();
  REQUIRE(fd.size() == 72);
  CHECK(fd[4] == 12);    // len rounded up to a CAN FD size
  CHECK(fd[5] == 0x05);  // CANFD_FDF | CANFD_BRS
  CHECK(fd[16] == 9);
  CHECK(fd[17] == 0);
  CHECK(sut->stats().framesSent == 2);
}

TEST_CASE("send refuses FD frames on a classic link and classic frames over 8 bytes") {
  FakeKernel kernel;
  auto sut = openFake(kernel, LinkOptions{});

  CHECK(sut->send(makeFrame(STANDARD_ID, FLAG_FD, {1})) == SendStatus::Invalid);
  CHECK(sut->send(makeFrame(STANDARD_ID, 0, {1, 2, 3, 4, 5, 6, 7, 8, 9})) == SendStatus::Invalid);

  CHECK(kernel.read().empty());
  CHECK(sut->stats().sendFailures == 2);
  CHECK(sut->stats().framesSent == 0);
}

TEST_CASE("send reports Busy when the transmit queue is full") {
  FakeKernel kernel;
  kernel.smallSendBuffer = true;
  auto sut = openFake(kernel, LinkOptions{});
  const Frame frame = makeFrame(STANDARD_ID, 0, {1});
  constexpr int ENOUGH = 100000;

  SendStatus status = SendStatus::Sent;
  for (int i = 0; i < ENOUGH && status == SendStatus::Sent; ++i) status = sut->send(frame);

  CHECK(status == SendStatus::Busy);
  CHECK(sut->up());
  CHECK(sut->stats().sendFailures == 1);
  CHECK(sut->stats().framesSent > 0);
}

TEST_CASE("a failing socket takes the link down and the reopen timer brings it back") {
  FakeKernel kernel;
  auto sut = openFake(kernel, fastReopenOptions());
  const int handle = sut->waitHandle().fd;
  drainEvents(*sut);
  REQUIRE(sut->send(makeFrame(STANDARD_ID, 0, {1})) == SendStatus::Sent);
  kernel.closePeer();  // with our frame unread: the socket reports ECONNRESET
  std::array<ReceivedFrame, 8> batch{};

  REQUIRE(readable(handle, 0));
  CHECK(sut->receive(batch) == 0);
  CHECK_FALSE(sut->up());
  auto events = drainEvents(*sut);
  REQUIRE(events.size() == 1);
  CHECK(events[0].kind == BusEventKind::LinkDown);
  CHECK(events[0].detail == static_cast<std::uint32_t>(ECONNRESET));
  CHECK(sut->send(makeFrame(STANDARD_ID, 0, {1})) == SendStatus::Down);

  REQUIRE(readable(handle, TIMER_WAIT_MS));  // the reopen timer, not the old socket
  CHECK(sut->receive(batch) == 0);

  CHECK(sut->up());
  CHECK(sut->waitHandle().fd == handle);
  CHECK(kernel.opens == 2);
  CHECK(sut->stats().reopenings == 1);
  events = drainEvents(*sut);
  REQUIRE(events.size() == 1);
  CHECK(events[0].kind == BusEventKind::LinkUp);
  CHECK_FALSE(readable(handle, 0));  // timer consumed and disarmed
  kernel.write(makeCanFrame(0x321, {}));
  REQUIRE(readable(handle, 0));
  REQUIRE(sut->receive(batch) == 1);
  CHECK(batch[0].frame.id == 0x321u);
}

TEST_CASE("end of file on the socket takes the link down too") {
  FakeKernel kernel;
  auto sut = openFake(kernel, fastReopenOptions());
  drainEvents(*sut);
  kernel.closePeer();
  std::array<ReceivedFrame, 4> batch{};

  CHECK(sut->receive(batch) == 0);

  CHECK_FALSE(sut->up());
  const auto events = drainEvents(*sut);
  REQUIRE(events.size() == 1);
  CHECK(events[0].detail == static_cast<std::uint32_t>(ENOTCONN));
}

TEST_CASE("while the interface is missing the link retries once per interval and never spins") {
  FakeKernel kernel;
  auto sut = openFake(kernel, fastReopenOptions());
  const int handle = sut->waitHandle().fd;
  kernel.closePeer();
  std::array<ReceivedFrame, 4> batch{};
  CHECK(sut->receive(batch) == 0);
  REQUIRE_FALSE(sut->up());
  kernel.failWith = ENODEV;

  for (int attempt = 2; attempt <= 3; ++attempt) {
    REQUIRE(readable(handle, TIMER_WAIT_MS));
    CHECK(sut->receive(batch) == 0);
    CHECK(kernel.opens == attempt);
    CHECK_FALSE(sut->up());
    CHECK_FALSE(readable(handle, 0));  // the expiration was consumed: no busy loop
  }
  kernel.failWith = 0;
  REQUIRE(readable(handle, TIMER_WAIT_MS));
  CHECK(sut->receive(batch) == 0);

  CHECK(sut->up());
  CHECK(sut->stats().reopenings == 1);
}

TEST_CASE("an interface that is down at open gives a link that waits for it") {
  FakeKernel kernel;
  kernel.failWith = ENETDOWN;

  auto sut = openFake(kernel, fastReopenOptions());

  CHECK_FALSE(sut->up());
  auto events = drainEvents(*sut);
  REQUIRE(events.size() == 1);
  CHECK(events[0].kind == BusEventKind::LinkDown);
  CHECK(events[0].detail == static_cast<std::uint32_t>(ENETDOWN));
  kernel.failWith = 0;
  REQUIRE(readable(sut->waitHandle().fd, TIMER_WAIT_MS));
  std::array<ReceivedFrame, 4> batch{};
  CHECK(sut->receive(batch) == 0);
  CHECK(sut->up());
  events = drainEvents(*sut);
  REQUIRE(events.size() == 1);
  CHECK(events[0].kind == BusEventKind::LinkUp);
}

TEST_CASE("open fails with the opener's reason and step, naming the interface") {
  FakeKernel kernel;
  kernel.failWith = ENODEV;
  const auto missing = openSocketCanLinkWith("can9", LinkOptions{}, kernel.opener());
  kernel.failWith = EPERM;
  kernel.failWhat = "cannot enable CAN FD frames (CAN_RAW_FD_FRAMES)";
  const auto refused = openSocketCanLinkWith("can9", LinkOptions{}, kernel.opener());

  REQUIRE_FALSE(missing.ok());
  CHECK(missing.error().message == "socketcan:can9: no such interface (ENODEV)");
  REQUIRE_FALSE(refused.ok());
  CHECK(refused.error().message == "socketcan:can9: cannot enable CAN FD frames (CAN_RAW_FD_FRAMES): " +
                                       std::string(std::strerror(EPERM)) + " (EPERM)");
}
