#pragma once
// `vcu init`: what the generator reads from the DBC files before it writes anything (the
// plan), and the writers of each file of the vehicle folder (init_vehicle.cpp,
// init_schedule.cpp, init_fsm.cpp). Every writer returns its file as JSON; init_command.cpp stages,
// checks and renames them (all or nothing).
//
//   vcu init tractor --dbc tractor.dbc --node VCU
//   -> tractor/{vehicle,schedule,receive,fsm,dashboard,gpio,simulation}.json + tractor.dbc

#include <cstddef>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "openvcu/dbc/model.hpp"

namespace openvcu::cli::init {

/// JSON written in the order the keys were added (a generated file reads top-down).
using OrderedJson = nlohmann::ordered_json;

/// Receive timeout = this factor x GenMsgCycleTime (can-rx's own default, written out).
inline constexpr std::uint32_t TIMEOUT_FACTOR = 3;
/// ...but at least this long (guessed): 3 x 10 ms = 30 ms faulted the generated machine on a
/// loaded 2-core host when one frame came late; set the real figure from the node's spec.
inline constexpr std::uint32_t MIN_TIMEOUT_MS = 100;
/// The generator keeps each bus' cyclic load under this, a margin below can-tx's 50 %
/// refusal (config::MAX_CYCLIC_BUS_LOAD) so a later small edit does not tip it over.
inline constexpr double TARGET_BUS_LOAD = 0.45;
/// J1939-76 SHM -> SDM delay written for a marked SDM (guessed; the original HHEA VCU used
/// 0.292-2 ms). Must stay below the SDM's cycle.
inline constexpr std::uint32_t SAFETY_DELTA_US = 1000;
/// The simulated receiver's J1939-76 limits for a marked SDM (guessed): SHM -> SDM within
/// this safety reaction time (SRVT), ms, and SHMs at most this many cycles apart (SCT).
inline constexpr std::uint32_t SAFETY_SRVT_MS = 10;
inline constexpr std::uint32_t SAFETY_SCT_CYCLES = 3;
/// The dashboard lists at most this many received signals per node.
inline constexpr std::size_t DASHBOARD_SIGNALS_PER_NODE = 6;

/// One bus of the generated vehicle: one per DBC file (a DBC describes one network).
struct PlannedBus {
  std::string name;     ///< "vehicle" for a single file, else the file's stem
  std::string dbcName;  ///< the copied file's name in DIR
  std::uint32_t bitrate{500000};
  std::optional<std::uint32_t> dataBitrate;
  bool fd{};
  bool allMessages{};                 ///< one file: "messages": "all"
  std::vector<std::string> messages;  ///< else the file's frame message names
  std::string comment;                ///< where bitrate and type came from
};

/// A message the node transmits, as the schedule will carry it.
struct PlannedTx {
  std::size_t message{};                        ///< index into the database
  std::optional<std::uint32_t> cycleMs;         ///< the DBC's GenMsgCycleTime; none: on request
  std::optional<std::uint32_t> lengthenedToMs;  ///< set when the bus-load budget lengthened it
  bool safety{};                                ///< a J1939-76 SDM (marked in the DBC comment)
  std::size_t bus{};
};

/// Everything the writers need.
struct Plan {
  std::string node;
  std::string instance;
  dbc::Database database;
  std::vector<PlannedBus> buses;
  std::vector<PlannedTx> transmitted;     ///< the node's messages, DBC order, no SHMs
  std::vector<std::size_t> shms;          ///< the node's J1939-76 safety headers (never scheduled)
  std::vector<std::size_t> received;      ///< frame messages other nodes send (with signals)
  std::vector<std::string> busLoadNotes;  ///< one line per bus: the load before and after
};

/// True when the message is a J1939-76 Safety Header Message (PGN 0x0E00 = 3584).
bool isSafetyHeader(const dbc::Message& message) noexcept;

/// True when the DBC marks the message as a J1939-76 Safety Data Message: its CM_ BO_
/// comment contains "J1939-76 SDM" (case-insensitive) and it is an 8-byte J1939 frame.
/// DBC has no standard attribute for this (none of the corpus files marks one); the
/// comment is what config/hhea/hhea.dbc does.
bool markedAsSdm(const dbc::Message& message) noexcept;

/// The bus index of a database message, or the first bus.
std::size_t busOf(const Plan& plan, const std::string& messageName) noexcept;

/// True when can-rx times the received message out: it has a GenMsgCycleTime and a
/// transmitter (a Vector__XXX message has nobody to simulate it, so it gets no timeout).
bool timesOut(const dbc::Message& message) noexcept;

/// The first decodable signal's catalog key of a received message, or empty.
std::string firstSignalKey(const dbc::Message& message);

/// The writers: each returns the file's JSON.
OrderedJson vehicleJson(const Plan& plan);
OrderedJson gpioJson(const Plan& plan);
OrderedJson simulationJson(const Plan& plan);
OrderedJson scheduleJson(const Plan& plan);
OrderedJson receiveJson(const Plan& plan);
OrderedJson fsmJson(const Plan& plan);
OrderedJson dashboardJson(const Plan& plan);

/// Lengthens the heaviest cyclic messages of each bus until the bus' cyclic load is at most
/// TARGET_BUS_LOAD (doubling a cycle at a time), and records the loads in busLoadNotes.
void fitBusLoad(Plan& plan);

}  // namespace openvcu::cli::init
