// The other process of test_harness: speaks the notify protocol the way a service does,
// or misbehaves on purpose.
//   harness_test_peer ready              READY=1, then wait for SIGTERM, STOPPING=1, exit 0
//   harness_test_peer exit CODE          print a line and exit with CODE before any READY=1
//   harness_test_peer silent             never send anything; wait for SIGTERM
//   harness_test_peer ready-from-child   a forked child sends READY=1 (must not count), then silent
//   harness_test_peer echo TEXT          print TEXT on stdout and "err" on stderr, exit 0
#include <signal.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

namespace {

bool notify(const std::string& text) {
  const char* path = std::getenv("NOTIFY_SOCKET");
  if (path == nullptr) return false;
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  std::strncpy(address.sun_path, path, sizeof(address.sun_path) - 1);
  const int fd = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  const bool sent = ::sendto(fd, text.data(), text.size(), 0, reinterpret_cast<const sockaddr*>(&address),
                             sizeof(address)) == static_cast<ssize_t>(text.size());
  ::close(fd);
  return sent;
}

sigset_t termSet() {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGTERM);
  return set;
}

/// SIGTERM is blocked from the start of main (before READY=1, like a real service), so a
/// stop that comes right after READY=1 waits here instead of killing the peer.
int waitForTerm() {
  const sigset_t set = termSet();
  int received = 0;
  ::sigwait(&set, &received);
  return received;
}

}  // namespace

int main(int argc, char** argv) {
  const sigset_t set = termSet();
  ::sigprocmask(SIG_BLOCK, &set, nullptr);
  const std::string mode = argc > 1 ? argv[1] : "";
  if (mode == "ready") {
    std::printf("peer: sending READY=1\n");
    std::fflush(stdout);
    notify("READY=1\nSTATUS=ready");
    waitForTerm();
    notify("STOPPING=1");
    return 0;
  }
  if (mode == "exit" && argc > 2) {
    std::printf("peer: giving up early\n");
    return std::atoi(argv[2]);
  }
  if (mode == "silent") {
    waitForTerm();
    return 0;
  }
  if (mode == "ready-from-child") {
    const pid_t child = ::fork();
    if (child == 0) _exit(notify("READY=1") ? 0 : 1);
    int status = 0;
    ::waitpid(child, &status, 0);
    waitForTerm();
    return 0;
  }
  if (mode == "echo" && argc > 2) {
    std::printf("%s\n", argv[2]);
    std::fprintf(stderr, "err\n");
    return 0;
  }
  std::fprintf(stderr, "usage: harness_test_peer ready|exit CODE|silent|ready-from-child|echo TEXT\n");
  return 2;
}
