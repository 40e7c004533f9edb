#pragma once
// Writing a state file so that a crash or power loss leaves either the old or the new
// content, never a mix: a temporary file beside it, fsync, rename over it, fsync of the
// folder. Used for the files services keep across restarts (can-tx's schedule overlay, the
// DTC occurrence counts).
//
//   if (Status saved = output::writeFileAtomically("dtc_counts.json", text, "DTC counts"); !saved) log(saved.error());
//   -> "dtc_counts.json: cannot write the DTC counts: Permission denied"

#include <string>
#include <string_view>

#include "openvcu/core/result.hpp"

namespace openvcu::output {

/// Replaces `path` with `text` atomically. Errors name the file and `what` ("the overlay").
/// @note blocks on disk I/O: not for a real-time thread.
Status writeFileAtomically(const std::string& path, std::string_view text, std::string_view what);

}  // namespace openvcu::output
