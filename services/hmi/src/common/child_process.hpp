#pragma once
// Children of vcu-hmi start with no signal blocked. vcu-hmi blocks SIGTERM and SIGINT in
// every thread (it reads them through a signalfd), and a child inherits the blocked set
// across fork and exec: a child that does not unblock them itself would ignore a SIGTERM.

#include <signal.h>

#include <QProcess>

namespace openvcu::hmi {

/// Clears the signal mask in `process`'s child between fork and exec (async-signal-safe).
/// Call before start().
inline void startWithNoSignalBlocked(QProcess& process) {
  process.setChildProcessModifier([] {
    sigset_t none;
    sigemptyset(&none);
    ::sigprocmask(SIG_SETMASK, &none, nullptr);
  });
}

}  // namespace openvcu::hmi
