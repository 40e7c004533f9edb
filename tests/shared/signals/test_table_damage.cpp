// Issue 18: a signal table whose segment is truncated or overwritten under attached
// processes. Before, every access to a lost page raised SIGBUS and killed the process
// (vcu-can-rx, vcu-can-tx, vcu-fsm and vcu-ecu-sim died when root ran `truncate -s 0` on the
// table). Each case uses its own table name (ScopedInstance), so truncating it touches no
// other test and no running stack.

#include <doctest/doctest.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "fault_guard.hpp"
#include "layout.hpp"
#include "openvcu/signals/table.hpp"
#include "signals_test_support.hpp"

using namespace openvcu::signals;
using namespace std::chrono_literals;
using openvcu::signals::testing::makeNumberedCatalog;
using openvcu::signals::testing::ScopedInstance;

namespace {

constexpr std::size_t SIGNALS = 40;  // 40 slots: the table spans several pages
constexpr SignalIndex FIRST = 0;
constexpr SignalIndex LAST = SIGNALS - 1;
constexpr std::int64_t TIME_NS = 1'000;
constexpr std::uint16_t SOURCE = 0xF3;
constexpr WriterId WRITER = 3;
constexpr off_t FIRST_PAGE_BYTES = 4096;
constexpr int CHILD_OK = 0;
constexpr int CHILD_NOT_DAMAGED = 3;
constexpr int CHILD_NO_VALUE = 4;

SignalTable openTable(const Catalog& catalog, const std::string& instance) {
  auto openResult = SignalTable::open(catalog, instance);
  if (!openResult) FAIL(openResult.error().toString());
  return std::move(openResult).value();
}

off_t sizeOf(const std::string& path) {
  struct stat status {};
  REQUIRE(stat(path.c_str(), &status) == 0);
  return status.st_size;
}

void truncateTo(const std::string& path, off_t bytes) {
  REQUIRE(::truncate(path.c_str(), bytes) == 0);
}

}  // namespace

TEST_CASE("a table truncated to 0 bytes under an attached process is read and written without SIGBUS and reports damage") {
  const ScopedInstance instance("trunc0");
  const Catalog catalog = makeNumberedCatalog(SIGNALS);
  SignalTable sut = openTable(catalog, instance.name());
  const std::string path = SignalTable::segmentPath(instance.name());
  const off_t tableBytes = sizeOf(path);
  REQUIRE(sut.writeBus(LAST, 1.5, TIME_NS, SOURCE, Quality::Valid));
  CHECK_FALSE(sut.damaged());
  CHECK_FALSE(sut.checkAndRepair().has_value());
  const std::uint64_t damageBefore = sut.damageCount();

  truncateTo(path, 0);  // what `truncate -s 0 /dev/shm/openvcu-<instance>` does
  const auto maybeLost = sut.readBus(LAST);  // was SIGBUS
  REQUIRE(maybeLost.has_value());
  CHECK(maybeLost->updates == 0);  // the value is gone with its page
  CHECK(maybeLost->quality == Quality::NeverReceived);
  CHECK(sut.writeBus(LAST, 2.5, TIME_NS, SOURCE, Quality::Valid));
  CHECK(sut.writeCommand(FIRST, 7.0, TIME_NS, WRITER));

  CHECK(sut.damaged());
  CHECK(sut.damageCount() > damageBefore);
  CHECK(sizeOf(path) == tableBytes);  // restored for every process that maps it
  const auto maybeBus = sut.readBus(LAST);
  REQUIRE(maybeBus.has_value());
  CHECK(maybeBus->value == 2.5);

  const auto maybeDamage = sut.checkAndRepair();
  REQUIRE(maybeDamage.has_value());
  CHECK(maybeDamage->busErrors >= 1);
  CHECK(maybeDamage->foundBytes == 0);
  CHECK(maybeDamage->tableBytes == static_cast<std::size_t>(tableBytes));
  CHECK(maybeDamage->sizeRestored);
  CHECK(maybeDamage->headerRestored);
  CHECK_FALSE(maybeDamage->privatePages);
  const std::string line = maybeDamage->describe(sut.info().name);
  MESSAGE(line);
  CHECK(line.find("signal table 'openvcu-" + instance.name() + "' was damaged (truncated to 0 of " +
                  std::to_string(tableBytes) + " bytes") == 0);
  CHECK(line.find('\n') == std::string::npos);
  CHECK_FALSE(sut.damaged());
  CHECK_FALSE(sut.checkAndRepair().has_value());  // reported once

  // The restored header lets a new process attach to the same (restored) table.
  SignalTable newcomer = openTable(catalog, instance.name());
  CHECK_FALSE(newcomer.info().createdByThisProcess);
  const auto maybeSeen = newcomer.readCommand(FIRST);
  REQUIRE(maybeSeen.has_value());
  CHECK(maybeSeen->value == 7.0);
}

TEST_CASE("a second mapping of a truncated table learns from the new generation that another one restored it") {
  const ScopedInstance instance("elsewhere");
  const Catalog catalog = makeNumberedCatalog(SIGNALS);
  SignalTable restorer = openTable(catalog, instance.name());
  SignalTable sut = openTable(catalog, instance.name());
  REQUIRE(sut.writeBus(LAST, 1.0, TIME_NS, SOURCE, Quality::Valid));
  const std::uint64_t damageBefore = sut.damageCount();

  truncateTo(SignalTable::segmentPath(instance.name()), 0);
  REQUIRE(restorer.writeBus(FIRST, 4.0, TIME_NS, SOURCE, Quality::Valid));  // faults and restores

  CHECK(sut.damaged());
  CHECK(sut.damageCount() > damageBefore);
  const auto maybeBus = sut.readBus(FIRST);  // the same shared segment again
  REQUIRE(maybeBus.has_value());
  CHECK(maybeBus->value == 4.0);
  const auto maybeDamage = sut.checkAndRepair();
  REQUIRE(maybeDamage.has_value());
  CHECK(maybeDamage->restoredElsewhere);
  CHECK_FALSE(maybeDamage->sizeRestored);
  CHECK(maybeDamage->busErrors == 0);
  CHECK(restorer.checkAndRepair().has_value());
}

TEST_CASE("a table cut to its first page keeps its header and gets a new generation") {
  const ScopedInstance instance("partial");
  const Catalog catalog = makeNumberedCatalog(SIGNALS);
  SignalTable other = openTable(catalog, instance.name());
  SignalTable sut = openTable(catalog, instance.name());
  const std::int64_t createdNs = sut.info().createdRealtimeNs;
  const std::uint64_t otherDamage = other.damageCount();

  truncateTo(SignalTable::segmentPath(instance.name()), FIRST_PAGE_BYTES);
  CHECK(sut.writeCommand(LAST, 9.0, TIME_NS, WRITER));  // the last slot lies beyond the first page

  const auto maybeDamage = sut.checkAndRepair();
  REQUIRE(maybeDamage.has_value());
  CHECK(maybeDamage->foundBytes == FIRST_PAGE_BYTES);
  CHECK(maybeDamage->sizeRestored);
  CHECK_FALSE(maybeDamage->headerRestored);
  CHECK(sut.info().createdRealtimeNs == createdNs);
  CHECK(other.damageCount() > otherDamage);  // its values were lost too: it must learn of it
}

TEST_CASE("a table header overwritten with zeros is written again and reported") {
  const ScopedInstance instance("header");
  const Catalog catalog = makeNumberedCatalog(SIGNALS);
  SignalTable sut = openTable(catalog, instance.name());
  const std::string path = SignalTable::segmentPath(instance.name());
  const int fd = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
  REQUIRE(fd >= 0);
  const std::vector<char> zeros(sizeof(detail::TableHeader), 0);
  REQUIRE(pwrite(fd, zeros.data(), zeros.size(), 0) == static_cast<ssize_t>(zeros.size()));
  ::close(fd);

  CHECK(sut.damaged());  // found by the header check, no fault involved
  const auto maybeDamage = sut.checkAndRepair();
  REQUIRE(maybeDamage.has_value());
  CHECK(maybeDamage->headerRestored);
  CHECK(maybeDamage->busErrors == 0);
  CHECK(maybeDamage->foundBytes == -1);
  SignalTable newcomer = openTable(catalog, instance.name());  // attaches: the header is whole
  CHECK(newcomer.info().layoutHash == catalog.layoutHash());
}

TEST_CASE("a service process keeps running through a truncation of its table by another process") {
  const ScopedInstance instance("process");
  const Catalog catalog = makeNumberedCatalog(SIGNALS);
  SignalTable sut = openTable(catalog, instance.name());  // keeps the table alive meanwhile
  int toChild[2];
  int fromChild[2];
  REQUIRE(pipe(toChild) == 0);
  REQUIRE(pipe(fromChild) == 0);
  const pid_t child = fork();
  REQUIRE(child >= 0);
  if (child == 0) {
    auto openResult = SignalTable::open(catalog, instance.name());
    if (!openResult) _exit(1);
    SignalTable table = std::move(openResult).value();
    table.writeBus(LAST, 1.0, TIME_NS, SOURCE, Quality::Valid);
    char go = 0;
    if (write(fromChild[1], "r", 1) != 1 || read(toChild[0], &go, 1) != 1) _exit(2);
    // after the truncation: the same calls a service makes in its loop
    table.writeBus(LAST, 2.0, TIME_NS, SOURCE, Quality::Valid);
    const auto maybeBus = table.readBus(LAST);
    if (!maybeBus || maybeBus->value != 2.0) _exit(CHILD_NO_VALUE);
    const auto maybeDamage = table.checkAndRepair();
    _exit(maybeDamage.has_value() && maybeDamage->busErrors > 0 ? CHILD_OK : CHILD_NOT_DAMAGED);
  }
  char ready = 0;
  REQUIRE(read(fromChild[0], &ready, 1) == 1);
  truncateTo(SignalTable::segmentPath(instance.name()), 0);
  REQUIRE(write(toChild[1], "g", 1) == 1);
  int status = 0;
  REQUIRE(waitpid(child, &status, 0) == child);
  CHECK_FALSE(WIFSIGNALED(status));
  if (WIFSIGNALED(status)) MESSAGE("child killed by signal " << WTERMSIG(status));
  REQUIRE(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == CHILD_OK);
  for (const int fd : {toChild[0], toChild[1], fromChild[0], fromChild[1]}) ::close(fd);
  CHECK(sut.readBus(LAST).value_or(BusValue{}).value == 2.0);  // the child's write, shared again
}

TEST_CASE("a SIGBUS outside every table still ends the process with SIGBUS") {
  const ScopedInstance instance("foreign");
  const Catalog catalog = makeNumberedCatalog(SIGNALS);
  const pid_t child = fork();
  REQUIRE(child >= 0);
  if (child == 0) {
    signal(SIGBUS, SIG_DFL);  // the test framework's own handler would report, not die
    auto openResult = SignalTable::open(catalog, instance.name());  // installs the table's handler
    if (!openResult) _exit(1);
    const int fd = memfd_create("not-a-table", MFD_CLOEXEC);
    if (fd < 0 || ftruncate(fd, FIRST_PAGE_BYTES) != 0) _exit(2);
    auto* bytes = static_cast<volatile char*>(mmap(nullptr, FIRST_PAGE_BYTES, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0));
    if (bytes == MAP_FAILED || ftruncate(fd, 0) != 0) _exit(3);
    bytes[0] = 1;  // SIGBUS: not in a table
    _exit(4);
  }
  int status = 0;
  REQUIRE(waitpid(child, &status, 0) == child);
  REQUIRE(WIFSIGNALED(status));
  CHECK(WTERMSIG(status) == SIGBUS);
}

TEST_CASE("a fault on a page that cannot be restored is backed by a private zero page until checkAndRepair maps the segment again") {
  // A guarded mapping without a descriptor stands for a segment whose size cannot be
  // restored (tmpfs full): the handler retries once, then maps a private page.
  const int fd = memfd_create("guarded", MFD_CLOEXEC);
  REQUIRE(fd >= 0);
  REQUIRE(ftruncate(fd, 2 * FIRST_PAGE_BYTES) == 0);
  void* base = mmap(nullptr, 2 * FIRST_PAGE_BYTES, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
  REQUIRE(base != MAP_FAILED);
  const ScopedInstance instance("private");
  const Catalog catalog = makeNumberedCatalog(SIGNALS);
  SignalTable table = openTable(catalog, instance.name());  // (re)installs the handler in this test case
  detail::GuardEntry* sut = detail::guardMapping(base, 2 * FIRST_PAGE_BYTES, -1, nullptr);
  REQUIRE(sut != nullptr);
  REQUIRE(ftruncate(fd, 0) == 0);

  auto* bytes = static_cast<volatile unsigned char*>(base);
  bytes[FIRST_PAGE_BYTES + 1] = 42;  // was SIGBUS
  CHECK(bytes[FIRST_PAGE_BYTES + 1] == 42);
  CHECK(bytes[0] == 0);
  CHECK(sut->detached.load());
  CHECK(sut->faults.load() >= 3);  // two pages: the second faulted twice (retry, then private page)
  detail::unguardMapping(sut);
  munmap(base, 2 * FIRST_PAGE_BYTES);
  ::close(fd);
}
