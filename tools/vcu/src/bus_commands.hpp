#pragma once
// `vcu send` and `vcu dump`: poke a bus of the configuration by hand.
//
//   vcu send vehicle 18FEF121#0102030405060708     through vcu-can-tx (its "send" stream)
//   vcu send --direct vehicle 123#DEADBEEF 123#R   straight onto the bus's link
//
//   vcu dump vehicle                  frames can-rx received, as candump -L lines
//   (1700000000.123456) vehicle 18FEF121#0102030405060708
//
//   vcu dump vehicle --stream wire --decode      a simulated bus itself, with DBC signals
//   (1700000000.123456) vehicle 18FEF221#0102030405060708  Status: SOC=0.5 %, Mode=2 "Fault"
//
// Frames use cansend's syntax (cansend_syntax.hpp). BUS is the logical bus name of the
// configuration (--config / $OPENVCU_CONFIG). Both register with iox-roudi under a name
// unique to the invocation ("vcu-send-<pid>", "vcu-dump-<pid>"). README.md has the details.

#include <cstdint>
#include <string>
#include <vector>

#include "cli.hpp"
#include "stack_access.hpp"

namespace openvcu::cli {

struct SendOptions {
  StackOptions stack;
  std::string bus;                  ///< logical bus name ("vehicle")
  std::vector<std::string> frames;  ///< cansend syntax, sent in this order
  bool direct{};                    ///< true: onto the link; false: to can-tx's "send" stream
  std::uint32_t repeat{1};          ///< the whole list this many times
  double intervalMs{};              ///< pause between two frames
};

struct DumpOptions {
  StackOptions stack;
  std::string bus;
  std::string stream{"rx"};  ///< rx, tx, send, req, wire (sim buses) or all
  bool decode{};             ///< append the DBC message and its signals
  std::uint64_t count{};     ///< stop after this many frames; 0: no limit
  double timeoutSeconds{};   ///< stop after this long without a frame; 0: no limit
};

ExitCode runSend(const SendOptions& options, Streams streams);
ExitCode runDump(const DumpOptions& options, Streams streams);

/// Adds `send` and `dump` to `app`.
void registerBusCommands(CLI::App& app, CommandContext& context);

}  // namespace openvcu::cli
