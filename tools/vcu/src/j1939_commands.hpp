#pragma once
// `vcu j1939`: the J1939 networks of a running stack (issue 24).
//
//   vcu j1939                       vcu-can-tx's view of each bus (LCM OPENVCU_<INSTANCE>_J1939):
//   bus vehicle: claimed, address 0x27 (39), NAME 0xA00082001F400001
//     ...  the NAME's fields (j1939::Name), the other nodes (with their DBC node), the VCU's DTCs and lamps
//
//   vcu j1939 request 65242 --to 0x21   a J1939 Request through can-tx ("send" stream), the
//   PGN 0x0FEDA (65242) from 0x21 (33) BMS, 9 bytes: 02 31 2E 30 ...  answer from can-rx's "rx"
//     software identification: "1.0", "2.0"                             stream, decoded
//
// README.md and each command's --help say the rest.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "cli.hpp"
#include "stack_access.hpp"

namespace openvcu::cli {

inline constexpr double DEFAULT_J1939_SHOW_TIMEOUT_SECONDS = 3.0;
inline constexpr double DEFAULT_J1939_REQUEST_TIMEOUT_SECONDS = 2.0;

struct J1939ShowOptions {
  StackOptions stack;
  std::string bus;  ///< only this bus; empty: every bus heard
  bool json{};
  double timeoutSeconds{DEFAULT_J1939_SHOW_TIMEOUT_SECONDS};
};

struct J1939RequestOptions {
  StackOptions stack;
  std::string pgn;   ///< decimal or 0x hex
  std::string to;    ///< destination address, decimal or 0x hex; 255 = global
  std::string bus;   ///< empty: the configuration's only bus
  std::string from;  ///< source address; empty: the VCU's (J1939 view, else the DBC node's)
  double timeoutSeconds{DEFAULT_J1939_REQUEST_TIMEOUT_SECONDS};
};

/// A PGN, decimal ("65242") or hex ("0xFEDA"), 0..0x3FFFF (18 bits); else empty.
[[nodiscard]] std::optional<std::uint32_t> parsePgn(std::string_view text) noexcept;
/// A J1939 address, decimal ("33") or hex ("0x21"), 0..255; else empty.
[[nodiscard]] std::optional<std::uint8_t> parseJ1939Address(std::string_view text) noexcept;

/// "0x21 (33)".
[[nodiscard]] std::string formatJ1939Address(std::uint8_t address);
/// The DBC node whose NmStationAddress is `address`, or empty.
[[nodiscard]] std::string dbcNodeAt(const config::VehicleConfig& config, std::uint8_t address);
/// The bus named `name`, or nullptr after reporting it with a "did you mean".
const config::BusConfig* findJ1939Bus(const config::VehicleConfig& config, const std::string& name, Sink& err);

ExitCode runJ1939Show(const J1939ShowOptions& options, Streams streams);
ExitCode runJ1939Request(const J1939RequestOptions& options, Streams streams);

/// Adds `request` to the `j1939` command (j1939_request.cpp).
void addJ1939Request(CLI::App& j1939, CommandContext& context);

/// Adds `j1939` (with `show` and `request`) to `app`.
void registerJ1939Commands(CLI::App& app, CommandContext& context);

}  // namespace openvcu::cli
