#pragma once
// Reading the file of a reload command (`vcu fsm reload PATH`, docs/fsm.md "Reload"): the
// path comes from the command socket and vcu-fsm may run as root, so only a regular file
// of bounded size inside the configuration's folders is read, and a refusal says why
// without ever quoting the file.
//
//   auto textResult = fsm::readReloadFile("/etc/openvcu/hhea/fsm-v2.json",
//                                         {"/etc/openvcu/hhea"}, fsm::RELOAD_MAX_BYTES);
//   -> the text, or Error{"/etc/shadow: outside the folders a reload may read (/etc/openvcu/hhea)"}
//
// The rules, in order (each refusal: "PATH: reason", the path as requested):
//   1. the path is absolute; `..` is resolved in the text first (lexically), so it cannot
//      climb out of a folder through a symlinked directory;
//   2. that path lies inside an allowed folder (as configured, or after resolving its
//      symlinks); nothing outside is touched at all, so its existence is not revealed;
//   3. the path's symlinks resolved (realpath), it still lies inside an allowed folder
//      (canonical form); a missing file is reported as missing only when the folder it
//      would be in is itself inside;
//   4. it is a regular file (lstat: a FIFO, device, socket or directory is never opened);
//   5. it is opened O_RDONLY|O_NONBLOCK|O_NOFOLLOW|O_NOCTTY|O_CLOEXEC (a FIFO swapped in
//      cannot block, a symlink swapped in is not followed), and the OPENED file is checked
//      again: fstat says regular, /proc/self/fd says it lies inside an allowed folder;
//   6. its size (fstat, then what is really read) is at most `maxBytes`.

#include <cstddef>
#include <string>
#include <vector>

#include "openvcu/config/vehicle.hpp"
#include "openvcu/core/result.hpp"
#include "openvcu/fsm/machine.hpp"
#include "openvcu/signals/catalog.hpp"

namespace openvcu::fsm {

/// The largest FSM file a reload reads (HHEA's is about 20 KiB).
inline constexpr std::size_t RELOAD_MAX_BYTES = 4 * 1024 * 1024;

/// The folders a reload may read from: the configured FSM file's folder and the vehicle
/// configuration's folder (absolute, as configured; readReloadFile also resolves them).
[[nodiscard]] std::vector<std::string> reloadFolders(const config::VehicleConfig& vehicle);

/// The content of `path` when the rules above allow it; otherwise an Error whose message is
/// "PATH: reason" and never contains the file's content.
/// @note thread-safe; blocks only on the file system (never on a FIFO or a device).
Result<std::string> readReloadFile(const std::string& path, const std::vector<std::string>& allowedFolders,
                                   std::size_t maxBytes);

/// readReloadFile, then the complete check (parseMachine). Refused: readReloadFile's error,
/// or "PATH: N errors (the first at line L); details in vcu-fsm's log or from `vcu fsm check
/// PATH`", which never quotes the file; the diagnostics themselves (they do quote it) are
/// appended to *diagnostics, for a log that stays on this machine.
/// @note thread-safe (the configuration and the catalog are only read).
Result<Machine> loadReloadMachine(const std::string& path, const std::vector<std::string>& allowedFolders,
                                  const config::VehicleConfig& vehicle, const signals::Catalog& catalog,
                                  std::vector<Error>* diagnostics);

}  // namespace openvcu::fsm
