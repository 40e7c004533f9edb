// The process search of vcu-watchdog on the real /proc: a sibling (same parent) whose
// executable is named as asked, nothing else.

#include <doctest/doctest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <string>

#include "openvcu/core/clock.hpp"
#include "process_finder.hpp"

using openvcu::watchdog::executableName;
using openvcu::watchdog::ProcessFinder;

namespace {

/// A child running `sleep 30` (its executable: coreutils' sleep), stopped at the end.
struct SleepingChild {
  pid_t pid{-1};
  SleepingChild() {
    pid = ::fork();
    REQUIRE(pid >= 0);
    if (pid == 0) {
      ::execlp("sleep", "sleep", "30", static_cast<char*>(nullptr));
      ::_exit(127);
    }
  }
  ~SleepingChild() {
    ::kill(pid, SIGKILL);
    ::waitpid(pid, nullptr, 0);
  }
};

/// Waits (at most 2 s, 10 ms steps) until the child's exe is no longer this test's (exec done).
bool waitForExec(pid_t pid, const ProcessFinder& finder) {
  for (int i = 0; i < 200; ++i) {
    if (!finder.find("sleep", ::getpid(), -1).processes.empty()) return true;
    ::usleep(10'000);
  }
  (void)pid;
  return false;
}

}  // namespace

TEST_CASE("the executable's name drops the folder and a ' (deleted)' suffix") {
  CHECK(executableName("/usr/bin/vcu-fsm") == "vcu-fsm");
  CHECK(executableName("/work/build/bin/vcu-fsm (deleted)") == "vcu-fsm");
  CHECK(executableName("vcu-fsm") == "vcu-fsm");
}

TEST_CASE("a child of the given parent is found by its executable's name, with its start time") {
  const ProcessFinder sut;
  const std::int64_t before = openvcu::clock::monotonicNs();
  SleepingChild child;
  REQUIRE(waitForExec(child.pid, sut));
  const auto found = sut.find("sleep", ::getpid(), -1);
  REQUIRE(found.processes.size() == 1);
  CHECK(found.processes[0].pid == child.pid);
  // /proc's start time has clock-tick (10 ms) resolution
  CHECK(found.processes[0].startNs >= before - 20'000'000);
  CHECK(found.processes[0].startNs <= openvcu::clock::monotonicNs());
}

TEST_CASE("a process of another parent or another executable is never found") {
  const ProcessFinder sut;
  SleepingChild child;
  REQUIRE(waitForExec(child.pid, sut));
  CHECK(sut.find("sleep", ::getppid(), -1).processes.empty());        // not our parent's child
  CHECK(sut.find("vcu-fsm", ::getpid(), -1).processes.empty());       // another name
  CHECK(sut.find("sleep", ::getpid(), child.pid).processes.empty());  // excluded as "self"
}

TEST_CASE("a stopped child is found in state T") {
  const ProcessFinder sut;
  SleepingChild child;
  REQUIRE(waitForExec(child.pid, sut));
  REQUIRE(::kill(child.pid, SIGSTOP) == 0);
  int status = 0;
  REQUIRE(::waitpid(child.pid, &status, WUNTRACED) == child.pid);
  const auto found = sut.find("sleep", ::getpid(), -1);
  REQUIRE(found.processes.size() == 1);
  CHECK(found.processes[0].state == 'T');
}
