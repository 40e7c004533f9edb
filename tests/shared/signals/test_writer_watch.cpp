// signals::WriterWatch with a set clock: when a watched writer (vcu-fsm) counts as lost, and
// that a signal table that lost its values (issue 18: the heartbeat slot reads as never
// written until the writer's next beat) is not taken for a lost writer.

#include <doctest/doctest.h>

#include <optional>

#include "openvcu/signals/writer_watch.hpp"

using namespace openvcu;
using signals::WriterChange;

namespace {

constexpr std::int64_t MS = 1'000'000;
constexpr std::int64_t START = 5'000 * MS;
constexpr std::int64_t TIMEOUT = 3'000 * MS;  // HHEA: {"service": "fsm", "timeoutMs": 3000}
constexpr std::uint64_t NO_DAMAGE = 0;
constexpr std::uint64_t DAMAGED = 1;

std::optional<signals::BusValue> beatAt(std::int64_t timestampNs, std::uint64_t updates) {
  return signals::BusValue{static_cast<double>(updates), timestampNs, 3, signals::Quality::Valid, updates};
}

/// What a wiped slot reads as.
std::optional<signals::BusValue> neverWritten() {
  return signals::BusValue{};
}

}  // namespace

TEST_CASE("a writer is lost when no heartbeat came for longer than the timeout and back with the next one") {
  signals::WriterWatch sut(TIMEOUT, START);
  CHECK(sut.update(beatAt(START + 500 * MS, 1), NO_DAMAGE, START + 500 * MS) == WriterChange::None);
  CHECK(sut.lostAtNs() == START + 3'500 * MS + 1);  // a watcher may sleep until then
  CHECK(sut.update(beatAt(START + 500 * MS, 1), NO_DAMAGE, START + 3'500 * MS) == WriterChange::None);
  CHECK(sut.update(beatAt(START + 500 * MS, 1), NO_DAMAGE, START + 3'501 * MS) == WriterChange::Lost);
  CHECK(sut.lost());
  CHECK(sut.update(beatAt(START + 3'600 * MS, 2), NO_DAMAGE, START + 3'600 * MS) == WriterChange::Back);
  CHECK_FALSE(sut.lost());
}

TEST_CASE("a writer that never beat counts from the watcher's start") {
  signals::WriterWatch sut(TIMEOUT, START);
  CHECK(sut.update(neverWritten(), NO_DAMAGE, START + TIMEOUT) == WriterChange::None);
  CHECK(sut.update(neverWritten(), NO_DAMAGE, START + TIMEOUT + MS) == WriterChange::Lost);
}

TEST_CASE("a heartbeat wiped with the table is no lost writer: it gets its timeout from the damage to come again") {
  signals::WriterWatch sut(TIMEOUT, START);
  const std::int64_t lastBeat = START + 10'000 * MS;
  CHECK(sut.update(beatAt(lastBeat, 10), NO_DAMAGE, lastBeat) == WriterChange::None);
  const std::int64_t damageNs = lastBeat + 2'900 * MS;  // seen late, e.g. the beat was late too
  CHECK(sut.update(neverWritten(), DAMAGED, damageNs) == WriterChange::None);
  CHECK(sut.sinceNs() == damageNs);
  CHECK(sut.update(neverWritten(), DAMAGED, damageNs + TIMEOUT) == WriterChange::None);
  // The writer never beat again: lost after its normal timeout, counted from the damage.
  CHECK(sut.update(neverWritten(), DAMAGED, damageNs + TIMEOUT + MS) == WriterChange::Lost);
}

TEST_CASE("a heartbeat read as never written keeps the last beat's time even before the damage count moved") {
  // The slot can be read wiped before this process learns of the damage.
  signals::WriterWatch sut(TIMEOUT, START);
  const std::int64_t lastBeat = START + 10'000 * MS;
  CHECK(sut.update(beatAt(lastBeat, 10), NO_DAMAGE, lastBeat) == WriterChange::None);
  CHECK(sut.update(neverWritten(), NO_DAMAGE, lastBeat + 900 * MS) == WriterChange::None);
  CHECK(sut.update(beatAt(lastBeat + 1'000 * MS, 1), DAMAGED, lastBeat + 1'000 * MS) == WriterChange::None);
  CHECK_FALSE(sut.lost());
}

TEST_CASE("damage does not bring back a writer that was lost before it") {
  signals::WriterWatch sut(TIMEOUT, START);
  CHECK(sut.update(neverWritten(), NO_DAMAGE, START + TIMEOUT + MS) == WriterChange::Lost);
  CHECK(sut.update(neverWritten(), DAMAGED, START + TIMEOUT + 100 * MS) == WriterChange::None);
  CHECK(sut.lost());
}
