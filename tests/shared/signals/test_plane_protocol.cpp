// White-box tests of one plane's write/read protocol (src/layout.hpp): a write is driven
// word by word, so a "writer killed after k words" or "writer delayed past a lap" is an
// exact, repeatable situation instead of a lucky timing.

#include <doctest/doctest.h>

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "layout.hpp"

using namespace openvcu::signals::detail;

namespace {

/// A payload whose three fields are derived from `n`, so a mixed triple is recognisable.
Payload payloadFor(std::uint64_t n) {
  return Payload{n * 0x9E3779B97F4A7C15ULL, static_cast<std::int64_t>(n * 1000 + 7),
                 static_cast<std::uint32_t>(n ^ 0xA5A5u)};
}

bool isPayloadOf(const Payload& payload, std::uint64_t n) {
  const Payload expected = payloadFor(n);
  return payload.valueBits == expected.valueBits && payload.timestampNs == expected.timestampNs &&
         payload.aux == expected.aux;
}

/// A plane as the creator leaves it: all zero.
std::unique_ptr<Plane> freshPlane() {
  return std::make_unique<Plane>();
}

/// Stores the first `words` words of a write of payloadFor(n); returns its ticket.
std::uint64_t partialWrite(Plane& plane, std::uint64_t n, std::size_t words) {
  const std::uint64_t ticket = claimTicket(plane);
  const auto chunks = chunksOf(payloadFor(n));
  for (std::size_t i = 0; i < words; ++i) storeWord(plane, ticket, i, chunks[i]);
  return ticket;
}

}  // namespace

TEST_CASE("a plane never written reads as ticket 0 with zero payload") {
  const auto sut = freshPlane();
  Record record;

  REQUIRE(readPlane(*sut, record));

  CHECK(record.ticket == 0);
  CHECK(record.payload.valueBits == 0);
  CHECK(record.payload.timestampNs == 0);
  CHECK(record.payload.aux == 0);
}

TEST_CASE("a reader gets the newest complete write with its ticket") {
  const auto sut = freshPlane();
  constexpr std::uint64_t WRITES = 10;
  for (std::uint64_t n = 1; n <= WRITES; ++n) writePlane(*sut, payloadFor(n));
  Record record;

  REQUIRE(readPlane(*sut, record));

  CHECK(record.ticket == WRITES);
  CHECK(isPayloadOf(record.payload, WRITES));
}

TEST_CASE("a writer killed after any number of words leaves the previous write readable") {
  for (std::size_t words = 0; words <= ENTRY_WORDS; ++words) {
    CAPTURE(words);
    const auto sut = freshPlane();
    // Fill the ring so the dead write overwrites a complete older entry.
    for (std::uint64_t n = 1; n <= RING_SIZE; ++n) writePlane(*sut, payloadFor(n));
    constexpr std::uint64_t DEAD_WRITE = 100;
    partialWrite(*sut, DEAD_WRITE, words);
    Record record;

    REQUIRE(readPlane(*sut, record));

    if (words == ENTRY_WORDS) {
      CHECK(isPayloadOf(record.payload, DEAD_WRITE));  // it finished its last store: a complete write
    } else {
      CHECK(record.ticket == RING_SIZE);
      CHECK(isPayloadOf(record.payload, RING_SIZE));
    }
  }
}

TEST_CASE("a restarted writer continues after a dead one and the dead entry is reused") {
  const auto sut = freshPlane();
  writePlane(*sut, payloadFor(1));
  partialWrite(*sut, 2, 3);  // killed after three words
  Record record;

  for (std::uint64_t n = 3; n < 3 + 2 * RING_SIZE; ++n) {
    writePlane(*sut, payloadFor(n));
    REQUIRE(readPlane(*sut, record));
    CHECK(isPayloadOf(record.payload, n));
    CHECK(record.ticket == n);
  }
}

TEST_CASE("a writer delayed past a full lap cannot damage the newer entry") {
  const auto sut = freshPlane();
  constexpr std::uint64_t STALE = 1;
  const std::uint64_t staleTicket = claimTicket(*sut);  // took its ticket, then was preempted
  for (std::uint64_t n = 2; n <= 1 + RING_SIZE; ++n) writePlane(*sut, payloadFor(n));  // the last lands on its entry
  const auto staleChunks = chunksOf(payloadFor(STALE));

  for (std::size_t i = 0; i < ENTRY_WORDS; ++i) CHECK_FALSE(storeWord(*sut, staleTicket, i, staleChunks[i]));
  Record record;

  REQUIRE(readPlane(*sut, record));
  CHECK(record.ticket == 1 + RING_SIZE);
  CHECK(isPayloadOf(record.payload, 1 + RING_SIZE));
}

// Two writers on one entry (tickets t and t + RING_SIZE) in every interleaving of their
// word stores; after every single step a reader must see some complete write, never a mix.
// Each intermediate state is also what a writer killed at that step leaves behind.
TEST_CASE("interleaved writers on one entry never produce a mixed triple") {
  constexpr std::size_t STEPS = 2 * ENTRY_WORDS;
  int interleavings = 0;
  for (unsigned order = 0; order < (1u << STEPS); ++order) {
    if (__builtin_popcount(order) != static_cast<int>(ENTRY_WORDS)) continue;
    ++interleavings;
    const auto sut = freshPlane();
    // Tickets 1..RING_SIZE-1 complete, ticket RING_SIZE (older writer A) and
    // 2*RING_SIZE (newer writer B) share entry 0.
    for (std::uint64_t n = 1; n < RING_SIZE; ++n) writePlane(*sut, payloadFor(n));
    const std::uint64_t ticketA = claimTicket(*sut);
    for (std::uint64_t n = RING_SIZE + 1; n < 2 * RING_SIZE; ++n) writePlane(*sut, payloadFor(n));
    const std::uint64_t ticketB = claimTicket(*sut);
    REQUIRE(ticketA % RING_SIZE == ticketB % RING_SIZE);
    const auto chunksA = chunksOf(payloadFor(ticketA));
    const auto chunksB = chunksOf(payloadFor(ticketB));
    std::size_t nextA = 0;
    std::size_t nextB = 0;
    bool stoppedA = false;
    for (std::size_t step = 0; step < STEPS; ++step) {
      if ((order >> step) & 1u) {
        if (!stoppedA && !storeWord(*sut, ticketA, nextA, chunksA[nextA])) stoppedA = true;
        ++nextA;
      } else {
        storeWord(*sut, ticketB, nextB, chunksB[nextB]);
        ++nextB;
      }
      Record record;
      REQUIRE(readPlane(*sut, record));
      CAPTURE(order);
      CAPTURE(step);
      CHECK(isPayloadOf(record.payload, record.ticket));
    }
    Record last;
    REQUIRE(readPlane(*sut, last));
    CHECK(last.ticket == ticketB);  // the newer ticket wins, whatever the order
  }
  CHECK(interleavings == 252);
}

TEST_CASE("a read fails instead of spinning when every entry of the window is unfinished") {
  const auto sut = freshPlane();
  writePlane(*sut, payloadFor(1));
  for (std::size_t i = 0; i < RING_SIZE; ++i) partialWrite(*sut, 50 + i, 2);  // four writers died
  Record record;

  CHECK_FALSE(readPlane(*sut, record));

  writePlane(*sut, payloadFor(99));  // a live writer repairs the plane with its next write
  REQUIRE(readPlane(*sut, record));
  CHECK(isPayloadOf(record.payload, 99));
}

TEST_CASE("tags keep working across the 32-bit wrap of the ticket") {
  const auto sut = freshPlane();
  constexpr std::uint64_t BEFORE_WRAP = (std::uint64_t{1} << 32) - RING_SIZE - 1;
  // The plane as it is after BEFORE_WRAP writes: each entry holds one of the last four.
  for (std::uint64_t ticket = BEFORE_WRAP - RING_SIZE + 1; ticket <= BEFORE_WRAP; ++ticket) {
    const auto chunks = chunksOf(payloadFor(ticket));
    for (std::size_t i = 0; i < ENTRY_WORDS; ++i) {
      sut->ring[ticket % RING_SIZE].words[i].store(std::uint64_t{tagOf(ticket)} << 32 | chunks[i]);
    }
  }
  sut->head.store(BEFORE_WRAP);
  for (std::uint64_t n = 0; n < 3 * RING_SIZE; ++n) {
    writePlane(*sut, payloadFor(n));
    Record record;
    REQUIRE(readPlane(*sut, record));
    CHECK(record.ticket == BEFORE_WRAP + n + 1);
    CHECK(isPayloadOf(record.payload, n));
  }
}

TEST_CASE("a quality mark applies only to the write it was made for") {
  const auto sut = freshPlane();
  writePlane(*sut, payloadFor(1));
  constexpr std::uint8_t STALE = 2;
  std::uint8_t quality{};

  markQuality(*sut, 1, STALE);

  CHECK(markedQuality(*sut, 1, quality));
  CHECK(quality == STALE);
  CHECK_FALSE(markedQuality(*sut, 2, quality));
  markQuality(*sut, 0, 1);  // an older mark never replaces a newer one
  CHECK(markedQuality(*sut, 1, quality));
  CHECK(quality == STALE);
}
