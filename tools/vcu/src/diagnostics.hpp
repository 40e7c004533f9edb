#pragma once
// One diagnostic per line, compiler style, so editors and CI jump to the spot:
//
//   Error{"unknown keyword", Location{"vehicle.dbc", 12, 3}}
//     -> "vehicle.dbc:12:3: error: unknown keyword"
//   Error{"cannot open: No such file or directory", Location{"x.dbc"}}
//     -> "x.dbc: error: cannot open: No such file or directory"
//   Error{"no DBC file given"} -> "vcu: error: no DBC file given"

#include <string>

#include "openvcu/core/error.hpp"
#include "sink.hpp"

namespace openvcu::cli {

/// "location: error|warning|note: message" (location "vcu" when the error has none).
std::string formatDiagnostic(const Error& error);

/// Writes formatDiagnostic(error) and a newline to `err`.
void report(Sink& err, const Error& error);

/// Reports a message without a location: "vcu: error: message".
void reportError(Sink& err, std::string_view message);

}  // namespace openvcu::cli
