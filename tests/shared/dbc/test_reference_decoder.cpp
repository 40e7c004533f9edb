// The fast codec against a deliberately naive reference that walks DBC bit numbering one
// bit at a time (STYLE.md 12, dbcppp's DecodingTest): every width 1..64, every start
// position that fits in 8- and 64-byte frames, both byte orders, signed and unsigned,
// random payloads from a fixed seed. Also encodeRaw(x) read back by the reference == x,
// with every bit outside the signal untouched.

#include "dbc_test_support.hpp"

#include <doctest/doctest.h>

#include <random>
#include <sstream>
#include <string>
#include <vector>

using namespace openvcu;
using namespace openvcu::dbc;
using namespace openvcu::dbc::test;

namespace {

constexpr std::uint64_t SEED = 0x0CEFF321;
constexpr std::uint32_t MAX_WIDTH = 64;
constexpr std::uint32_t CLASSIC_ROUNDS = 8;  // random payloads per layout in 8-byte frames
constexpr std::uint32_t FD_ROUNDS = 2;       // ... and in 64-byte frames
constexpr std::uint64_t MINIMUM_COMPARISONS = 200000;

// ------------------------------------------------------------------ the naive reference

/// (byte, bit) of the k-th bit counted from the MSB (Motorola) or LSB (Intel).
struct BitWalk {
  std::uint32_t byte;
  std::uint32_t bit;
};

/// Every bit position of a signal, LSB first, by walking the DBC numbering one bit at a time.
/// Intel: start is the LSB, bits count up through the bytes. Motorola: start is the MSB;
/// walk down within the byte, and after bit 0 continue at bit 7 of the next byte.
std::vector<BitWalk> walk(std::uint32_t startBit, std::uint32_t size, ByteOrder order) {
  std::vector<BitWalk> lsbFirst(size);
  if (order == ByteOrder::LittleEndian) {
    for (std::uint32_t k = 0; k < size; ++k) lsbFirst[k] = {(startBit + k) / 8, (startBit + k) % 8};
    return lsbFirst;
  }
  std::uint32_t byte = startBit / 8;
  std::uint32_t bit = startBit % 8;
  for (std::uint32_t k = 0; k < size; ++k) {
    lsbFirst[size - 1 - k] = {byte, bit};  // k counts from the MSB
    if (bit == 0) {
      bit = 7;
      ++byte;
    } else {
      --bit;
    }
  }
  return lsbFirst;
}

std::uint64_t naiveBits(std::span<const std::uint8_t> payload, const std::vector<BitWalk>& bits) {
  std::uint64_t value = 0;
  for (std::size_t k = 0; k < bits.size(); ++k) {
    const std::uint64_t bit = (payload[bits[k].byte] >> bits[k].bit) & 1u;
    value |= bit << k;
  }
  return value;
}

/// Sign extension by OR-ing ones above the field (the codec uses xor/subtract instead).
std::int64_t naiveSigned(std::uint64_t bits, std::uint32_t size) {
  if (size < 64 && ((bits >> (size - 1)) & 1u) != 0) bits |= ~std::uint64_t{0} << size;
  return static_cast<std::int64_t>(bits);
}

// ------------------------------------------------------------------ layouts under test

/// Start bits of every placement of a `size`-bit signal inside `frameBytes`.
std::vector<std::uint32_t> startPositions(std::uint32_t size, std::uint32_t frameBytes, ByteOrder order) {
  std::vector<std::uint32_t> starts;
  const std::uint32_t frameBits = frameBytes * 8;
  for (std::uint32_t first = 0; first + size <= frameBits; ++first) {
    if (order == ByteOrder::LittleEndian) {
      starts.push_back(first);
    } else {
      // `first` counts MSB-first from byte 0 bit 7; the DBC start bit is that bit's number.
      starts.push_back((first / 8) * 8 + (7 - first % 8));
    }
  }
  return starts;
}

/// One message holding a signal at every position (so one compile covers them all).
Database layoutDatabase(std::uint32_t size, std::uint32_t frameBytes, ByteOrder order, bool isSigned) {
  Database db;
  Message message;
  message.name = "Layouts";
  message.id = 1;
  message.declaredId = 1;
  message.length = frameBytes;
  for (const std::uint32_t start : startPositions(size, frameBytes, order)) {
    Signal signal;
    signal.name = std::to_string(start);
    signal.name.insert(0, 1, 'S');
    signal.startBit = start;
    signal.size = size;
    signal.byteOrder = order;
    signal.isSigned = isSigned;
    message.signals.push_back(std::move(signal));
  }
  db.messages.push_back(std::move(message));
  db.reindex();
  return db;
}

std::string describeLayout(const Signal& signal, std::uint32_t frameBytes) {
  std::ostringstream out;
  out << "start " << signal.startBit << " size " << signal.size << " @"
      << (signal.byteOrder == ByteOrder::LittleEndian ? "1" : "0") << (signal.isSigned ? "-" : "+") << " in "
      << frameBytes << " bytes";
  return out.str();
}

struct Tally {
  std::uint64_t comparisons{};
  std::uint64_t mismatches{};
  std::string firstMismatch;

  void record(bool same, const std::string& what) {
    ++comparisons;
    if (same) return;
    if (mismatches++ == 0) firstMismatch = what;
  }
};

void compareDecode(const Database& db, std::uint32_t frameBytes, std::uint32_t rounds, std::mt19937_64& random,
                   Tally& tally) {
  const Message& message = db.messages[0];
  const MessageCodec sut = MessageCodec::compile(db, message);
  REQUIRE(sut.skippedSignals().empty());
  std::vector<std::vector<BitWalk>> walks;
  for (const Signal& signal : message.signals) walks.push_back(walk(signal.startBit, signal.size, signal.byteOrder));
  std::vector<std::uint8_t> payload(frameBytes);
  for (std::uint32_t round = 0; round < rounds; ++round) {
    for (auto& byte : payload) byte = round == 0 ? 0xFF : static_cast<std::uint8_t>(random());
    const DecodeSummary summary = sut.decode(payload, [&](std::uint32_t index, const DecodedValue& value) {
      const Signal& signal = message.signals[index];
      const std::uint64_t expected = naiveBits(payload, walks[index]);
      bool same = false;
      if (signal.isSigned) {
        const std::int64_t expectedSigned = naiveSigned(expected, signal.size);
        same = value.kind == RawKind::Signed && value.rawSigned == expectedSigned &&
               value.physical == static_cast<double>(expectedSigned);
      } else {
        same = value.kind == RawKind::Unsigned && value.rawUnsigned == expected &&
               value.physical == static_cast<double>(expected);
      }
      tally.record(same, describeLayout(signal, frameBytes));
    });
    tally.record(summary.decoded == message.signals.size() && summary.missing == 0, "decode summary");
  }
}

void compareEncode(const Database& db, std::uint32_t frameBytes, std::mt19937_64& random, Tally& tally) {
  const Message& message = db.messages[0];
  const MessageCodec sut = MessageCodec::compile(db, message);
  std::vector<std::uint8_t> background(frameBytes);
  for (auto& byte : background) byte = static_cast<std::uint8_t>(random());
  std::vector<std::uint8_t> buffer(frameBytes);
  for (std::uint32_t index = 0; index < message.signals.size(); ++index) {
    const Signal& signal = message.signals[index];
    const std::vector<BitWalk> bits = walk(signal.startBit, signal.size, signal.byteOrder);
    const std::uint64_t mask = signal.size == 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << signal.size) - 1;
    const std::uint64_t pattern = random() & mask;
    DecodedValue raw;
    raw.kind = signal.isSigned ? RawKind::Signed : RawKind::Unsigned;
    if (signal.isSigned) {
      raw.rawSigned = naiveSigned(pattern, signal.size);
    } else {
      raw.rawUnsigned = pattern;
    }
    buffer = background;

    const EncodeStatus status = sut.encodeRaw(index, raw, buffer);

    bool same = status == EncodeStatus::Ok && naiveBits(buffer, bits) == pattern;
    // Every bit the signal does not own keeps the background's value.
    std::vector<std::uint8_t> owned(frameBytes, 0);
    for (const BitWalk& b : bits) owned[b.byte] = static_cast<std::uint8_t>(owned[b.byte] | (1u << b.bit));
    for (std::uint32_t i = 0; i < frameBytes && same; ++i) {
      same = (buffer[i] & ~owned[i] & 0xFF) == (background[i] & ~owned[i] & 0xFF);
    }
    tally.record(same, "encode " + describeLayout(signal, frameBytes));
  }
}

}  // namespace

TEST_CASE("reference walk reads Motorola start 7 size 16 as bytes 0 and 1 big-endian") {
  const std::vector<std::uint8_t> payload = hexBytes("12 34 00 00 00 00 00 00");

  CHECK(naiveBits(payload, walk(7, 16, ByteOrder::BigEndian)) == 0x1234u);
  CHECK(naiveBits(payload, walk(0, 16, ByteOrder::LittleEndian)) == 0x3412u);
  CHECK(naiveSigned(0xFF, 8) == -1);
}

TEST_CASE("codec decode equals the bit-by-bit reference for every width, position and byte order") {
  std::mt19937_64 random(SEED);
  Tally tally;
  for (const std::uint32_t frameBytes : {std::uint32_t{8}, std::uint32_t{64}}) {
    const std::uint32_t rounds = frameBytes == 8 ? CLASSIC_ROUNDS : FD_ROUNDS;
    for (const ByteOrder order : {ByteOrder::LittleEndian, ByteOrder::BigEndian}) {
      for (const bool isSigned : {false, true}) {
        for (std::uint32_t size = 1; size <= MAX_WIDTH; ++size) {
          const Database db = layoutDatabase(size, frameBytes, order, isSigned);
          compareDecode(db, frameBytes, rounds, random, tally);
        }
      }
    }
  }

  INFO("first mismatch: " << tally.firstMismatch);
  CHECK(tally.mismatches == 0);
  CHECK(tally.comparisons >= MINIMUM_COMPARISONS);
  MESSAGE("decode comparisons against the reference: " << tally.comparisons);
}

TEST_CASE("codec encodeRaw read back by the bit-by-bit reference gives the value and keeps other bits") {
  std::mt19937_64 random(SEED + 1);
  Tally tally;
  for (const std::uint32_t frameBytes : {std::uint32_t{8}, std::uint32_t{64}}) {
    for (const ByteOrder order : {ByteOrder::LittleEndian, ByteOrder::BigEndian}) {
      for (const bool isSigned : {false, true}) {
        for (std::uint32_t size = 1; size <= MAX_WIDTH; ++size) {
          const Database db = layoutDatabase(size, frameBytes, order, isSigned);
          compareEncode(db, frameBytes, random, tally);
        }
      }
    }
  }

  INFO("first mismatch: " << tally.firstMismatch);
  CHECK(tally.mismatches == 0);
  MESSAGE("encode round trips against the reference: " << tally.comparisons);
}
