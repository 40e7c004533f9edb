#pragma once
// Test helper (#19): a SIGTERM made pending on the calling thread, the way a service holds
// it (blocked, waiting in its signalfd); consumed and the mask restored at scope end.

#include <signal.h>
#include <time.h>

namespace openvcu::test {

class PendingSigterm {
 public:
  PendingSigterm() {
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &set, &m_previous);
    // Directed at this thread (raise() is), so it stays pending here and nowhere else.
    pthread_kill(pthread_self(), SIGTERM);
  }
  PendingSigterm(const PendingSigterm&) = delete;
  PendingSigterm& operator=(const PendingSigterm&) = delete;
  ~PendingSigterm() {
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, SIGTERM);
    const timespec noWait{0, 0};
    while (sigtimedwait(&set, nullptr, &noWait) == SIGTERM) {
    }
    pthread_sigmask(SIG_SETMASK, &m_previous, nullptr);
  }

 private:
  sigset_t m_previous{};
};

}  // namespace openvcu::test
