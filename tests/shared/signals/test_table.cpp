#include <doctest/doctest.h>
#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "openvcu/signals/table.hpp"
#include "signals_test_support.hpp"

using namespace openvcu::signals;
using namespace std::chrono_literals;
using openvcu::signals::testing::makeCatalog;
using openvcu::signals::testing::makeNumberedCatalog;
using openvcu::signals::testing::ScopedInstance;

namespace {

constexpr SignalIndex SOC = 0;
constexpr SignalIndex VOLTAGE = 1;
constexpr SignalIndex START = 2;
constexpr std::int64_t TIME_NS = 1'234'567'890;
constexpr std::uint16_t BATTERY_ADDRESS = 0xF3;
constexpr WriterId FSM_WRITER = 3;
constexpr WriterId HMI_WRITER = 7;

Catalog hheaCatalog() {
  return makeCatalog(
      {"VIC.HVESSD2_PGN61585.HS_FastUpdSOC", "VIC.HVESSD1_PGN61584.HS_Voltage", "internal.operator.start"});
}

SignalTable openTable(const Catalog& catalog, const std::string& instance, OpenMode mode = OpenMode::CreateOrAttach) {
  auto openResult = SignalTable::open(catalog, instance, mode);
  if (!openResult) FAIL(openResult.error().toString());
  return std::move(openResult).value();
}

mode_t fileMode(const std::string& path) {
  struct stat status {};
  REQUIRE(stat(path.c_str(), &status) == 0);
  return status.st_mode & 0777;
}

}  // namespace

TEST_CASE("open creates a table that a second open attaches to") {
  const ScopedInstance instance("attach");
  const Catalog catalog = hheaCatalog();

  SignalTable creator = openTable(catalog, instance.name());
  SignalTable sut = openTable(catalog, instance.name());
  creator.writeBus(SOC, 87.5, TIME_NS, BATTERY_ADDRESS, Quality::Valid);

  CHECK(creator.info().createdByThisProcess);
  CHECK_FALSE(sut.info().createdByThisProcess);
  CHECK(sut.size() == 3);
  CHECK(sut.info().name == "openvcu-" + instance.name());
  CHECK(sut.info().layoutHash == catalog.layoutHash());
  CHECK(sut.info().formatVersion == SIGNAL_TABLE_FORMAT_VERSION);
  CHECK(sut.info().creatorPid == getpid());
  const auto maybeBus = sut.readBus(SOC);
  REQUIRE(maybeBus.has_value());
  CHECK(maybeBus->value == 87.5);
  CHECK(maybeBus->timestampNs == TIME_NS);
  CHECK(maybeBus->source == BATTERY_ADDRESS);
  CHECK(maybeBus->quality == Quality::Valid);
  CHECK(maybeBus->updates == 1);
}

TEST_CASE("a fresh table reads NeverReceived and zero updates everywhere") {
  const ScopedInstance instance("fresh");
  const SignalTable sut = openTable(hheaCatalog(), instance.name());

  for (SignalIndex index = 0; index < sut.size(); ++index) {
    const auto maybeSnapshot = sut.read(index);
    REQUIRE(maybeSnapshot.has_value());
    CHECK(maybeSnapshot->bus.quality == Quality::NeverReceived);
    CHECK(maybeSnapshot->bus.updates == 0);
    CHECK(maybeSnapshot->command.updates == 0);
    CHECK(maybeSnapshot->override.updates == 0);
    CHECK_FALSE(maybeSnapshot->override.active);
    CHECK_FALSE(effectiveCommand(*maybeSnapshot).has_value());
  }
}

TEST_CASE("bus, command and override planes are independent") {
  const ScopedInstance instance("planes");
  SignalTable sut = openTable(hheaCatalog(), instance.name());

  sut.writeBus(VOLTAGE, 650.0, TIME_NS, BATTERY_ADDRESS, Quality::Valid);
  sut.writeCommand(VOLTAGE, 600.0, TIME_NS + 1, FSM_WRITER);
  sut.writeCommand(VOLTAGE, 610.0, TIME_NS + 2, FSM_WRITER);
  sut.setOverride(VOLTAGE, 300.0, TIME_NS + 3, HMI_WRITER);

  const auto maybeSnapshot = sut.read(VOLTAGE);
  REQUIRE(maybeSnapshot.has_value());
  CHECK(maybeSnapshot->bus.value == 650.0);
  CHECK(maybeSnapshot->bus.updates == 1);
  CHECK(maybeSnapshot->command.value == 610.0);
  CHECK(maybeSnapshot->command.timestampNs == TIME_NS + 2);
  CHECK(maybeSnapshot->command.writer == FSM_WRITER);
  CHECK(maybeSnapshot->command.updates == 2);
  CHECK(maybeSnapshot->override.value == 300.0);
  CHECK(maybeSnapshot->override.writer == HMI_WRITER);
  CHECK(maybeSnapshot->override.active);
  CHECK(maybeSnapshot->override.updates == 1);
  const auto maybeOther = sut.read(SOC);
  REQUIRE(maybeOther.has_value());
  CHECK(maybeOther->bus.updates == 0);
  CHECK(maybeOther->command.updates == 0);
}

TEST_CASE("an override wins over the command until it is cleared") {
  const ScopedInstance instance("override");
  SignalTable sut = openTable(hheaCatalog(), instance.name());
  sut.writeCommand(START, 1.0, TIME_NS, FSM_WRITER);

  sut.setOverride(START, 0.0, TIME_NS + 10, HMI_WRITER);
  auto maybeSnapshot = sut.read(START);
  REQUIRE(maybeSnapshot.has_value());
  auto maybeEffective = effectiveCommand(*maybeSnapshot);
  REQUIRE(maybeEffective.has_value());
  CHECK(maybeEffective->value == 0.0);
  CHECK(maybeEffective->writer == HMI_WRITER);
  CHECK(maybeEffective->overridden);

  sut.writeCommand(START, 2.0, TIME_NS + 20, FSM_WRITER);  // still overridden
  maybeSnapshot = sut.read(START);
  REQUIRE(maybeSnapshot.has_value());
  CHECK(effectiveCommand(*maybeSnapshot)->value == 0.0);

  sut.clearOverride(START, TIME_NS + 30, HMI_WRITER);
  maybeSnapshot = sut.read(START);
  REQUIRE(maybeSnapshot.has_value());
  CHECK_FALSE(maybeSnapshot->override.active);
  CHECK(maybeSnapshot->override.timestampNs == TIME_NS + 30);
  maybeEffective = effectiveCommand(*maybeSnapshot);
  REQUIRE(maybeEffective.has_value());
  CHECK(maybeEffective->value == 2.0);
  CHECK(maybeEffective->writer == FSM_WRITER);
  CHECK_FALSE(maybeEffective->overridden);
}

TEST_CASE("an active override is the effective command even without any command") {
  const ScopedInstance instance("override-only");
  SignalTable sut = openTable(hheaCatalog(), instance.name());

  sut.setOverride(START, 1.0, TIME_NS, HMI_WRITER);

  const auto maybeSnapshot = sut.read(START);
  REQUIRE(maybeSnapshot.has_value());
  const auto maybeEffective = effectiveCommand(*maybeSnapshot);
  REQUIRE(maybeEffective.has_value());
  CHECK(maybeEffective->value == 1.0);
  CHECK(maybeEffective->overridden);
}

TEST_CASE("markBusQuality changes only the quality of the visible value") {
  const ScopedInstance instance("quality");
  SignalTable sut = openTable(hheaCatalog(), instance.name());
  sut.writeBus(SOC, 42.0, TIME_NS, BATTERY_ADDRESS, Quality::Valid);

  CHECK(sut.markBusQuality(SOC, Quality::Stale));

  const auto maybeBus = sut.readBus(SOC);
  REQUIRE(maybeBus.has_value());
  CHECK(maybeBus->quality == Quality::Stale);
  CHECK(maybeBus->value == 42.0);
  CHECK(maybeBus->timestampNs == TIME_NS);
  CHECK(maybeBus->source == BATTERY_ADDRESS);
  CHECK(maybeBus->updates == 1);
}

TEST_CASE("a new value after a quality mark carries its own quality") {
  const ScopedInstance instance("quality-new");
  SignalTable sut = openTable(hheaCatalog(), instance.name());
  sut.writeBus(SOC, 42.0, TIME_NS, BATTERY_ADDRESS, Quality::Valid);
  sut.markBusQuality(SOC, Quality::Stale);

  sut.writeBus(SOC, 43.0, TIME_NS + 1, BATTERY_ADDRESS, Quality::OutOfRange);

  const auto maybeBus = sut.readBus(SOC);
  REQUIRE(maybeBus.has_value());
  CHECK(maybeBus->value == 43.0);
  CHECK(maybeBus->quality == Quality::OutOfRange);
}

TEST_CASE("markBusQuality refuses a signal that was never received") {
  const ScopedInstance instance("quality-never");
  SignalTable sut = openTable(hheaCatalog(), instance.name());

  CHECK_FALSE(sut.markBusQuality(SOC, Quality::Stale));

  CHECK(sut.readBus(SOC)->quality == Quality::NeverReceived);
}

TEST_CASE("an index out of range makes writes return false and reads empty") {
  const ScopedInstance instance("range");
  SignalTable sut = openTable(hheaCatalog(), instance.name());
  constexpr SignalIndex OUT_OF_RANGE = 3;

  CHECK_FALSE(sut.writeBus(OUT_OF_RANGE, 1.0, TIME_NS, 0, Quality::Valid));
  CHECK_FALSE(sut.writeCommand(OUT_OF_RANGE, 1.0, TIME_NS, FSM_WRITER));
  CHECK_FALSE(sut.setOverride(OUT_OF_RANGE, 1.0, TIME_NS, HMI_WRITER));
  CHECK_FALSE(sut.clearOverride(OUT_OF_RANGE, TIME_NS, HMI_WRITER));
  CHECK_FALSE(sut.markBusQuality(OUT_OF_RANGE, Quality::Stale));
  CHECK_FALSE(sut.read(OUT_OF_RANGE).has_value());
  CHECK_FALSE(sut.readBus(std::numeric_limits<SignalIndex>::max()).has_value());
}

TEST_CASE("special double values survive a round trip") {
  const ScopedInstance instance("doubles");
  SignalTable sut = openTable(hheaCatalog(), instance.name());

  sut.writeCommand(SOC, -0.0, TIME_NS, FSM_WRITER);
  CHECK(std::signbit(sut.readCommand(SOC)->value));
  sut.writeCommand(SOC, std::numeric_limits<double>::infinity(), TIME_NS, FSM_WRITER);
  CHECK(sut.readCommand(SOC)->value == std::numeric_limits<double>::infinity());
  sut.writeCommand(SOC, std::numeric_limits<double>::quiet_NaN(), -TIME_NS, FSM_WRITER);
  CHECK(std::isnan(sut.readCommand(SOC)->value));
  CHECK(sut.readCommand(SOC)->timestampNs == -TIME_NS);
}

TEST_CASE("values outlive every process detaching") {
  const ScopedInstance instance("persist");
  const Catalog catalog = hheaCatalog();
  {
    SignalTable writer = openTable(catalog, instance.name());
    writer.writeCommand(START, 1.0, TIME_NS, FSM_WRITER);
  }

  const SignalTable sut = openTable(catalog, instance.name());

  CHECK_FALSE(sut.info().createdByThisProcess);
  CHECK(sut.readCommand(START)->value == 1.0);
}

TEST_CASE("open refuses a table of another configuration while a process is attached") {
  const ScopedInstance instance("mismatch");
  const Catalog catalog = hheaCatalog();
  const Catalog otherCatalog = makeNumberedCatalog(5);
  const SignalTable attached = openTable(catalog, instance.name());

  const auto openResult = SignalTable::open(otherCatalog, instance.name());

  REQUIRE_FALSE(openResult.ok());
  char expectedHashes[160];
  std::snprintf(expectedHashes, sizeof expectedHashes, "(layout 0x%016llx, 3 signals; this process: 0x%016llx, 5)",
                static_cast<unsigned long long>(catalog.layoutHash()),
                static_cast<unsigned long long>(otherCatalog.layoutHash()));
  CHECK(openResult.error().message == "table 'openvcu-" + instance.name() +
                                          "' was created from another configuration " + expectedHashes +
                                          ": stop every service of this instance or run `vcu table reset`");
  CHECK(attached.readBus(SOC).has_value());  // the attached process is undisturbed
}

TEST_CASE("AttachOnly refuses a table of another configuration even when nobody is attached") {
  const ScopedInstance instance("mismatch-attach");
  { const SignalTable old = openTable(hheaCatalog(), instance.name()); }

  const auto openResult = SignalTable::open(makeNumberedCatalog(5), instance.name(), OpenMode::AttachOnly);

  REQUIRE_FALSE(openResult.ok());
  CHECK(openResult.error().message.find("was created from another configuration") != std::string::npos);
}

TEST_CASE("open replaces a table of another configuration once nobody is attached") {
  const ScopedInstance instance("replace");
  {
    SignalTable old = openTable(hheaCatalog(), instance.name());
    old.writeBus(SOC, 1.0, TIME_NS, 0, Quality::Valid);
  }
  const Catalog newCatalog = makeNumberedCatalog(5);

  const SignalTable sut = openTable(newCatalog, instance.name());

  CHECK(sut.info().createdByThisProcess);
  CHECK(sut.size() == 5);
  CHECK(sut.info().layoutHash == newCatalog.layoutHash());
  CHECK(sut.readBus(SOC)->updates == 0);
}

TEST_CASE("open re-creates a table left incomplete by a killed creator") {
  const ScopedInstance instance("incomplete");
  const Catalog catalog = hheaCatalog();
  // What a creator killed after ftruncate leaves: the right size, all zero, no magic number.
  const std::string shmName = "/openvcu-" + instance.name();
  const int fd = shm_open(shmName.c_str(), O_RDWR | O_CREAT | O_EXCL, 0600);
  REQUIRE(fd >= 0);
  REQUIRE(ftruncate(fd, 4096) == 0);
  close(fd);
  const int lockFd = ::open(SignalTable::lockPath(instance.name()).c_str(), O_RDONLY | O_CREAT, 0600);
  REQUIRE(lockFd >= 0);
  close(lockFd);

  SUBCASE("AttachOnly reports it") {
    const auto openResult = SignalTable::open(catalog, instance.name(), OpenMode::AttachOnly);
    REQUIRE_FALSE(openResult.ok());
    CHECK(openResult.error().message.find("is incomplete") != std::string::npos);
  }
  SUBCASE("CreateOrAttach re-creates it") {
    const SignalTable sut = openTable(catalog, instance.name());
    CHECK(sut.info().createdByThisProcess);
    CHECK(sut.size() == 3);
  }
}

TEST_CASE("AttachOnly fails clearly when no table exists and creates nothing") {
  const ScopedInstance instance("missing");

  const auto openResult = SignalTable::open(hheaCatalog(), instance.name(), OpenMode::AttachOnly);

  REQUIRE_FALSE(openResult.ok());
  CHECK(openResult.error().message ==
        "no signal table 'openvcu-" + instance.name() + "': no service of this instance has created it yet");
  CHECK(access(SignalTable::segmentPath(instance.name()).c_str(), F_OK) != 0);
  CHECK(access(SignalTable::lockPath(instance.name()).c_str(), F_OK) != 0);
}

TEST_CASE("Recreate gives a fresh table while attached processes keep the old one") {
  const ScopedInstance instance("recreate");
  const Catalog catalog = hheaCatalog();
  SignalTable old = openTable(catalog, instance.name());
  old.writeBus(SOC, 5.0, TIME_NS, 0, Quality::Valid);

  SignalTable sut = openTable(catalog, instance.name(), OpenMode::Recreate);

  CHECK(sut.info().createdByThisProcess);
  CHECK(sut.readBus(SOC)->updates == 0);
  CHECK(old.readBus(SOC)->value == 5.0);
  sut.writeBus(SOC, 6.0, TIME_NS, 0, Quality::Valid);
  CHECK(old.readBus(SOC)->value == 5.0);
  const SignalTable newcomer = openTable(catalog, instance.name());  // finds the fresh one
  CHECK(newcomer.readBus(SOC)->value == 6.0);
}

TEST_CASE("Recreate with nobody attached replaces the table in place") {
  const ScopedInstance instance("recreate-alone");
  const Catalog catalog = hheaCatalog();
  {
    SignalTable old = openTable(catalog, instance.name());
    old.writeBus(SOC, 5.0, TIME_NS, 0, Quality::Valid);
  }

  const SignalTable sut = openTable(catalog, instance.name(), OpenMode::Recreate);

  CHECK(sut.readBus(SOC)->updates == 0);
}

TEST_CASE("instances are isolated from each other") {
  const ScopedInstance first("iso-a");
  const ScopedInstance second("iso-b");
  const Catalog catalog = hheaCatalog();
  SignalTable sut = openTable(catalog, first.name());
  const SignalTable other = openTable(catalog, second.name());

  sut.writeBus(SOC, 11.0, TIME_NS, 0, Quality::Valid);

  CHECK(sut.readBus(SOC)->updates == 1);
  CHECK(other.readBus(SOC)->updates == 0);
}

TEST_CASE("the segment and its lock file are readable by the owner only") {
  const ScopedInstance instance("mode");
  const mode_t oldMask = umask(0);  // the modes must not depend on the umask
  const SignalTable sut = openTable(hheaCatalog(), instance.name());
  umask(oldMask);

  CHECK(fileMode(SignalTable::segmentPath(instance.name())) == 0600);
  CHECK(fileMode(SignalTable::lockPath(instance.name())) == 0600);
}

TEST_CASE("OwnerAndGroup creates the segment and lock file 0660") {
  const ScopedInstance instance("mode-group");
  const mode_t oldMask = umask(077);
  auto openResult =
      SignalTable::open(hheaCatalog(), instance.name(), OpenMode::CreateOrAttach, Permissions::OwnerAndGroup);
  umask(oldMask);
  REQUIRE(openResult.ok());

  CHECK(fileMode(SignalTable::segmentPath(instance.name())) == 0660);
  CHECK(fileMode(SignalTable::lockPath(instance.name())) == 0660);
}

TEST_CASE("invalid instance names are refused before anything is created") {
  const Catalog catalog = hheaCatalog();
  for (const std::string& name :
       std::vector<std::string>{"", "a/b", "../etc", "with space", "dot.ted", std::string(65, 'x')}) {
    CAPTURE(name);
    const auto openResult = SignalTable::open(catalog, name);
    REQUIRE_FALSE(openResult.ok());
    CHECK(openResult.error().message.find("invalid instance name") == 0);
  }
  CHECK(SignalTable::checkInstanceName("hhea-bench_2").ok());
}

TEST_CASE("an empty catalog makes a valid table without slots") {
  const ScopedInstance instance("empty");

  const SignalTable sut = openTable(Catalog{}, instance.name());

  CHECK(sut.size() == 0);
  CHECK_FALSE(sut.read(0).has_value());
}

TEST_CASE("a moved table keeps working and the moved-from one is empty") {
  const ScopedInstance instance("move");
  SignalTable original = openTable(hheaCatalog(), instance.name());

  SignalTable sut = std::move(original);
  sut.writeBus(SOC, 3.0, TIME_NS, 0, Quality::Valid);

  CHECK(sut.readBus(SOC)->value == 3.0);
  CHECK(original.size() == 0);  // NOLINT(bugprone-use-after-move): documented state
  CHECK_FALSE(original.readBus(SOC).has_value());
}

TEST_CASE("every write and quality mark advances the change epoch") {
  const ScopedInstance instance("epoch");
  SignalTable sut = openTable(hheaCatalog(), instance.name());
  const std::uint32_t before = sut.changeEpoch();

  sut.writeBus(SOC, 1.0, TIME_NS, 0, Quality::Valid);
  sut.markBusQuality(SOC, Quality::Stale);
  sut.writeCommand(SOC, 1.0, TIME_NS, FSM_WRITER);
  sut.setOverride(SOC, 1.0, TIME_NS, HMI_WRITER);
  sut.clearOverride(SOC, TIME_NS, HMI_WRITER);

  CHECK(sut.changeEpoch() == before + 5);
}

TEST_CASE("waitForChange returns at once when the epoch already moved") {
  const ScopedInstance instance("wait-now");
  SignalTable sut = openTable(hheaCatalog(), instance.name());
  const std::uint32_t before = sut.changeEpoch();
  sut.writeBus(SOC, 1.0, TIME_NS, 0, Quality::Valid);

  CHECK(sut.waitForChange(before, 10s) == before + 1);
}

TEST_CASE("waitForChange times out when nothing changes") {
  const ScopedInstance instance("wait-timeout");
  const SignalTable sut = openTable(hheaCatalog(), instance.name());
  const std::uint32_t before = sut.changeEpoch();
  const auto start = std::chrono::steady_clock::now();

  CHECK(sut.waitForChange(before, 20ms) == before);

  CHECK(std::chrono::steady_clock::now() - start >= 20ms);
}

TEST_CASE("waitForChange wakes when another thread writes") {
  const ScopedInstance instance("wait-thread");
  SignalTable sut = openTable(hheaCatalog(), instance.name());
  const std::uint32_t before = sut.changeEpoch();

  std::thread writer([&sut] {
    std::this_thread::sleep_for(20ms);  // let the main thread go to sleep first (not needed for correctness)
    sut.writeCommand(START, 1.0, TIME_NS, FSM_WRITER);
  });
  const std::uint32_t after = sut.waitForChange(before, 10s);
  writer.join();

  CHECK(after == before + 1);
  CHECK(sut.readCommand(START)->value == 1.0);
}
