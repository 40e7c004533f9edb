#pragma once
// The J1939 networks as vcu-can-tx sees them (ipc::J1939Network, one per bus on the J1939
// channel), without Qt: the latest view per bus, its freshness, and the rows the Debug tab's
// J1939 page shows (the content of `vcu j1939`). J1939Model (j1939_model.hpp) wraps it.
//
//   J1939Networks sut({"vehicle"}, dbcNodesByAddress(database), 3 s);
//   sut.onNetwork(view, now);  sut.rows(now + 4 s) -> the bus's rows, marked Stale
// @note GUI thread only (not thread-safe); allocates when a view arrives and in rows().

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "common/display_logic.hpp"
#include "openvcu/dbc/model.hpp"
#include "openvcu/ipc/events.hpp"

namespace openvcu::hmi {

/// vcu-can-tx sends each bus's view once a second: a bus not heard for this long is Stale.
inline constexpr std::int64_t J1939_STALE_AFTER_NS = 3'000'000'000;

/// The DBC node name per J1939 source address (its NmStationAddress; the first node of an
/// address); "" where none and at 254 and 255.
using DbcNodeNames = std::array<std::string, 256>;
[[nodiscard]] DbcNodeNames dbcNodesByAddress(const dbc::Database& database);

/// One line of the J1939 page.
struct J1939Row {
  enum class Kind : std::uint8_t {
    Claim,  ///< the bus's first row: the VCU's claim state, address, NAME and the bus's status
    Node,   ///< another node's claim: address, NAME, DBC node
    Dtc,    ///< one of the VCU's DTCs: name, SPN, FMI, occurrences, active
    Lamps,  ///< the DM1 lamps
    Note,   ///< a heading or "none" text in `label`
  };
  Kind kind{Kind::Note};
  std::string bus;
  ValueStatus busStatus{ValueStatus::NotConnected};  ///< Ready, Stale (not heard for 3 s), NotConnected (never)
  std::string address;  ///< "0x21 (33)" (Claim while claimed or claiming, Node)
  std::string name;     ///< NAME "0xB002800000000001" (Claim, Node); the DTC's name (Dtc)
  std::string label;    ///< Claim: claim state; Node: DBC node or ""; Lamps: the lamps; Note: the text
  std::uint32_t spn{};
  std::uint8_t fmi{};
  std::uint8_t occurrences{};
  bool active{};  ///< Dtc: in DM1 (else previously active, DM2)
  bool alert{};   ///< worth a colour: cannot claim, an active DTC, a lamp on
  bool operator==(const J1939Row&) const = default;
};

/// "0x21 (33)".
[[nodiscard]] std::string j1939AddressText(std::uint8_t address);
/// "0xB002800000000001".
[[nodiscard]] std::string j1939NameText(std::uint64_t name);
/// "protect Off, amber warning On, red stop Off, malfunction Off" for DM1 byte 0.
[[nodiscard]] std::string j1939LampsText(std::uint8_t lamps);

class J1939Networks {
 public:
  /// `expected`: buses listed from the start (NotConnected until heard), the configuration's
  /// buses with a "j1939" object; others join when heard.
  J1939Networks(std::vector<std::string> expected, DbcNodeNames dbcNodes, std::int64_t staleAfterNs);

  /// The latest view of its bus replaces the previous one; `receivedMonoNs` on this HMI's
  /// monotonic clock.
  void onNetwork(const ipc::J1939Network& network, std::int64_t receivedMonoNs);
  [[nodiscard]] std::size_t busCount() const noexcept { return m_buses.size(); }
  /// Bus `index`'s status at `nowNs`. @note noexcept, allocation-free.
  [[nodiscard]] ValueStatus statusOf(std::size_t index, std::int64_t nowNs) const noexcept;
  /// All buses: Ready when every bus is heard and fresh, NotConnected when none was heard,
  /// else Stale.
  [[nodiscard]] ValueStatus overall(std::int64_t nowNs) const noexcept;
  /// Per bus in order of appearance: Claim, "other nodes" Note, Node rows (or a "none" Note),
  /// "DTCs" Note, Dtc rows (active first, or a "none" Note), Lamps.
  [[nodiscard]] std::vector<J1939Row> rows(std::int64_t nowNs) const;

 private:
  struct Bus {
    std::string name;
    ipc::J1939Network latest;
    std::int64_t receivedMonoNs{-1};  ///< -1: never heard
  };
  void appendRows(std::vector<J1939Row>& rows, const Bus& bus, ValueStatus status) const;
  std::vector<Bus> m_buses;
  DbcNodeNames m_dbcNodes;
  std::int64_t m_staleAfterNs;
};

}  // namespace openvcu::hmi
