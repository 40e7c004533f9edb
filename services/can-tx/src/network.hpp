#pragma once
// The VCU as a J1939 network citizen (issue 24), on vcu-can-tx's transmit thread:
//   - J1939-81 address claim per bus with a "j1939" object in vehicle.json: claims at
//     start, defends, moves within its range or sends Cannot Claim (j1939::AddressClaimer);
//     while it may not transmit on a bus, nothing else leaves on that bus;
//   - the schedule follows the claimed address: every frame whose source address is the
//     preferred address leaves with the claimed one, except the J1939-76 safety pairs
//     (SHM and the SDMs of holdSafetyMessages()), which leave only from the preferred one;
//   - a lost address (a higher-priority NAME claimed it) is reported once per loss
//     (takeAddressLosses(): bus, address, the claimant's NAME, where the VCU went), which
//     the app raises as the fault j1939_address_lost.<bus>;
//   - its own diagnostics (J1939-73, diagnostics.json): DM1 once per dm1 period and on
//     change (by BAM above one DTC), DM2 on request, DM3 and DM11 by policy, occurrence
//     counts handed to the service to persist;
//   - identification answers (SOFT 65242 with the build version, ECUID 64965, CI 65259);
//   - transport-protocol sending for every answer longer than 8 bytes: BAM to global,
//     RTS/CTS to a requester (j1939::TpSender).
// It sits between the Scheduler and the links as a TxPort, so the scheduler stays unaware
// of addresses. Frames from the "net" stream (claims, TP answers) come in through onFrame().
//
//   auto networkResult = cantx::Network::create(vehicle, diagnostics, fsmStates, catalog, table, port, version);
//   scheduler uses *networkResult as its TxPort; the transmit thread calls
//   network.start(now) once, then run(now) whenever it wakes, and sleeps no later than
//   network.nextDeadlineNs().

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "openvcu/can/frame.hpp"
#include "openvcu/config/diagnostics.hpp"
#include "openvcu/config/vehicle.hpp"
#include "openvcu/core/result.hpp"
#include "openvcu/ipc/events.hpp"
#include "openvcu/j1939/request.hpp"
#include "openvcu/signals/catalog.hpp"
#include "openvcu/signals/table.hpp"
#include "scheduler.hpp"

namespace openvcu::cantx {

/// Counters for the heartbeat (written on the transmit thread, read anywhere).
struct NetworkCounters {
  std::atomic<std::uint64_t> claimsSent{};
  std::atomic<std::uint64_t> contestsWon{};
  std::atomic<std::uint64_t> contestsLost{};
  std::atomic<std::uint64_t> cannotClaim{};        ///< Cannot Claim frames sent
  std::atomic<std::uint64_t> framesHeldByClaim{};  ///< frames not sent: no address on their bus
  std::atomic<std::uint64_t> dm1Sent{};            ///< DM1s that left, one per bus (none while a bus has no address)
  std::atomic<std::uint64_t> tpStarted{};
  std::atomic<std::uint64_t> tpCompleted{};
  std::atomic<std::uint64_t> tpFailed{};          ///< aborted, timed out, ended by an address change
  std::atomic<std::uint64_t> tpRefused{};         ///< TpSender refused (queue full, no address)
  std::atomic<std::uint64_t> requestsAnswered{};  ///< requests this component answered
  std::atomic<std::uint64_t> clearsAccepted{};    ///< DM3/DM11
  std::atomic<std::uint64_t> clearsRefused{};
  std::atomic<std::uint64_t> addressesLost{};     ///< a higher-priority NAME took our address
  std::atomic<std::uint64_t> safetyFramesHeld{};  ///< SHM/SDM not sent: the bus' address is not the preferred one
};

/// One lost address: a higher-priority NAME claimed the address the VCU held (or its
/// preferred address at start), and what the VCU did (J1939-81).
struct AddressLoss {
  std::string bus;
  std::uint8_t lostAddress{};
  std::uint64_t claimant{};   ///< the claimant's NAME
  std::uint64_t ourName{};    ///< the VCU's NAME on that bus
  std::uint8_t newAddress{};  ///< where the VCU went; NULL_ADDRESS (254): Cannot Claim, silent on the bus
  bool safetyPairsHeld{};     ///< the VCU moved and its J1939-76 pairs on that bus are not sent

  /// "bus 'vehicle': address 0x21 (33) taken by NAME 0x3002800000000000, which has priority
  /// over this VCU's NAME 0x3002800000000001; the VCU sent Cannot Claim and sends nothing
  /// more on this bus (J1939-81) until vcu-can-tx restarts".
  [[nodiscard]] std::string describe() const;
  /// Critical when the VCU has no address or its safety pairs are held, else a warning.
  [[nodiscard]] bool critical() const noexcept;
};

struct NetworkBus;
struct NetworkImpl;

/// @note restricted thread-safe: create() and the snapshot/counts calls from any thread;
///       everything else from the transmit thread (noexcept, no allocation after create()).
class Network final : public TxPort {
 public:
  /// `out` is where frames finally go (the links). `fsmStates`: the FSM's state names in
  /// file order (internal.fsm.state holds the index). `version`: appended to SOFT.
  static Result<std::unique_ptr<Network>> create(const config::VehicleConfig& vehicle,
                                                 const config::DiagnosticsConfig& diagnostics,
                                                 const std::vector<std::string>& fsmStates,
                                                 const signals::Catalog& catalog, signals::SignalTable& table,
                                                 TxPort& out, const std::string& version);
  ~Network() override;
  Network(const Network&) = delete;
  Network& operator=(const Network&) = delete;

  /// The J1939-76 SDMs the schedule sends (their CAN IDs from the preferred address),
  /// before start(). They and every SHM (PGN 0x0E00) leave only from the preferred
  /// address: while the VCU holds another one on their bus they are not sent (Down,
  /// counted in safetyFramesHeld), as a J1939-76 receiver expects its pairs from a fixed SA.
  void holdSafetyMessages(std::span<const std::uint32_t> sdmCanIds);
  /// Restores occurrence counts read at start (before start()).
  void restoreCounts(std::span<const j1939::Dtc> counts) noexcept;
  /// Sends the first claims.
  void start(std::int64_t nowNs) noexcept;
  /// Claim and transport deadlines, the DTC evaluation and the DM1.
  void run(std::int64_t nowNs) noexcept;
  /// When run() must be called next (INT64_MAX: never).
  [[nodiscard]] std::int64_t nextDeadlineNs() const noexcept;
  /// A frame of bus `bus`'s "net" stream (Address Claimed, TP.CM to us).
  void onFrame(std::size_t bus, const can::Frame& frame, std::int64_t nowNs) noexcept;
  /// Answers the requests this component owns (Address Claimed, DM1, DM2, DM3, DM11,
  /// identification); false for any other PGN (the scheduler answers it).
  bool answerRequest(std::size_t bus, const j1939::Request& request, std::int64_t nowNs) noexcept;

  /// The transmit thread's time before it runs the scheduler and applies commands: the
  /// time send() gives a transport session it starts.
  void setNow(std::int64_t nowNs) noexcept;
  /// TxPort: a frame of the scheduler. Not sent (Down) while the VCU has no address on
  /// the bus; a frame from the preferred address leaves from the claimed one. A J1939
  /// message longer than 8 bytes on a classic bus with a "j1939" object leaves by the
  /// transport protocol (BAM to global, RTS/CTS to its destination); Busy when its
  /// destination's transfer queue is full.
  can::SendStatus send(std::size_t bus, const can::Frame& frame) noexcept override;

  /// The current view of every bus with a J1939 address, for OPENVCU_<I>_J1939 (copies
  /// under a lock; the transmit thread only try-locks). Empty when nothing is configured.
  [[nodiscard]] std::vector<ipc::J1939Network> snapshot() const;
  /// true (once) when the view changed since the last call.
  [[nodiscard]] bool takeChanged() noexcept;
  /// The occurrence counts to persist when they changed since the last call, else empty.
  [[nodiscard]] std::optional<std::vector<j1939::Dtc>> takeCountsToSave();
  /// Lines for the log since the last call (claims won and lost, DM3/DM11), oldest first.
  [[nodiscard]] std::vector<std::string> takeLog();
  /// The addresses lost since the last call, one entry per bus that lost one (its latest
  /// loss). Loop thread; never misses a loss (per-bus atomics, no try-lock).
  [[nodiscard]] std::vector<AddressLoss> takeAddressLosses();

  [[nodiscard]] const NetworkCounters& counters() const noexcept;
  /// true when a bus claims an address or diagnostics are configured.
  [[nodiscard]] bool active() const noexcept;

 private:
  explicit Network(std::unique_ptr<NetworkImpl> impl) noexcept;
  can::SendStatus sendLong(NetworkBus& bus, const can::Frame& frame) noexcept;
  std::unique_ptr<NetworkImpl> m_impl;
};

}  // namespace openvcu::cantx
