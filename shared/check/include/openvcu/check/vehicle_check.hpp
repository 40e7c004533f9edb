#pragma once
// The whole-vehicle checks: the files of one vehicle folder checked together, where each
// file's own loader sees only itself. `vcu check` reports them after the per-file checks;
// service::Service::open runs them at start (errors refuse, warnings are logged once).
// Reference: docs/config.md, "Whole-vehicle checks".
//
//   auto diagnostics = check::checkVehicle(vehicle, catalog);
//   -> {"vehicle.json: /buses/0: warning: bus 'vehicle': the cyclic frames expected on it take 79.6 % ...",
//       "fsm.json: /states/1/transitions/0/condition/all/2: warning: the condition reads internal.mode.Eco,
//        which nobody writes: ..."}
//
// What is checked (each diagnostic names the file and the JSON path or DBC line):
//   - unused signals: per bus one warning counting the received DBC signals no file of the
//     vehicle reads (FSM conditions and copies, dashboard, schedule, receive forwarding and
//     J1939-76 checks, simulation, diagnostics), naming the first messages none of whose
//     signals is read;
//   - FSM conditions on signals nobody writes (catalog ownership, FSM actions, GPIO inputs,
//     operator switches, the schedule, can-rx's DM1 decoding): a warning per signal;
//   - expected bus load per bus: the schedule's cyclic frames plus every other node's cyclic
//     DBC messages (GenMsgCycleTime), exact wire time: above BUS_LOAD_WARNING a warning,
//     above BUS_LOAD_ERROR an error, naming the load and the heaviest messages;
//   - address collisions on a bus: two nodes declaring one NmStationAddress is an error; a
//     node sending J1939 messages with an address another node holds (by its
//     NmStationAddress or its messages' SA; the VCU's from its scheduled IDs) is a warning;
//     two DBC messages with one ID on one bus, or a scheduled ID equal to another DBC
//     message's, is an error; two J1939 messages with one PGN, destination and source are
//     an error from two nodes and a warning from one (priority-only twins; the VCU's own
//     are can-tx's safety-identity warnings);
//   - a simulation J1939-76 check on a message no configured bus carries: an error;
//   - a simulation "wakeSignal" that is not a catalog key: an error at /wakeSignal;
//   - an arbitrary-address-capable NAME claiming on a bus where the schedule sends J1939-76
//     pairs: a warning at /buses/<i>/j1939/name/arbitraryAddressCapable (j1939_checks.hpp);
//   - diagnostics.json: its loader's errors and warnings with the FSM's state names (a DTC's
//     "fsmState" must name one) and the catalog (DM3/DM11 "accept": a warning), and a
//     warning per FSM state whose entry raises a fault that no DTC maps.
// Messages the schedule, receive or simulation file names that are not in the DBC are the
// loaders' errors (with file and JSON path); these checks do not repeat them. A file that
// does not load is left out of the checks that need it, with one note saying so.

#include <string>
#include <vector>

#include "openvcu/config/vehicle.hpp"
#include "openvcu/core/error.hpp"
#include "openvcu/signals/catalog.hpp"

namespace openvcu::check {

/// Above this share of a bus' time (0.70 = 70 %) the expected load is a warning: J1939
/// networks are laid out to stay under 70-80 % so that error frames, retransmissions and
/// event-driven frames (requests, transport sessions, DM1 on change) still fit.
inline constexpr double BUS_LOAD_WARNING = 0.70;
/// Above this the cyclic frames alone cannot all be sent: an error.
inline constexpr double BUS_LOAD_ERROR = 1.00;
/// How many names a summary diagnostic lists before "and N more".
inline constexpr std::size_t NAMES_SHOWN = 5;

/// Every whole-vehicle diagnostic of a loaded configuration and its catalog (see the file
/// comment), errors and warnings in the order above. Reads the FSM, schedule, receive,
/// simulation and dashboard files with their own loaders. Never throws.
/// @note allocates and reads files: for start-up and tools, not for a per-frame path.
std::vector<Error> checkVehicle(const config::VehicleConfig& vehicle, const signals::Catalog& catalog);

}  // namespace openvcu::check
