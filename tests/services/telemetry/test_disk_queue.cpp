// The store-and-forward queue (services/telemetry/src/disk_queue.hpp): records come back in
// order until acked (also a batch split over segments), survive a reopen and a SIGKILL, the
// byte limit drops the oldest and says so, and a damaged folder is recovered up to its last
// good record.
#include <doctest/doctest.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "disk_queue.hpp"

namespace {

using namespace openvcu;
using telemetry::DiskQueue;
using telemetry::DiskQueueOptions;

constexpr std::uint64_t SMALL_SEGMENT = 64 * 1024;
constexpr std::uint64_t SMALL_LIMIT = 4 * SMALL_SEGMENT;

/// A fresh folder under the temporary directory, removed at the end of the case.
struct TempFolder {
  std::string path;
  TempFolder() {
    std::string pattern = (std::filesystem::temp_directory_path() / "openvcu-queue-XXXXXX").string();
    REQUIRE(::mkdtemp(pattern.data()) != nullptr);
    path = pattern;
  }
  ~TempFolder() { std::filesystem::remove_all(path); }
};

/// The payload every test writes for a sequence number, so a reader can check it.
std::string payloadFor(std::uint64_t sequence, std::size_t size = 100) {
  std::string text = "record " + std::to_string(sequence) + " ";
  while (text.size() < size) text += static_cast<char>('a' + sequence % 26);
  return text;
}

Result<DiskQueue> openQueue(const std::string& folder, std::vector<Error>* warnings = nullptr,
                            std::uint64_t maxBytes = SMALL_LIMIT) {
  return DiskQueue::open({.folder = folder, .maxBytes = maxBytes, .segmentBytes = SMALL_SEGMENT}, warnings);
}

void appendRange(DiskQueue& queue, std::uint64_t first, std::uint64_t count, std::size_t size = 100) {
  std::vector<std::string> payloads;
  for (std::uint64_t s = first; s < first + count; ++s) payloads.push_back(payloadFor(s, size));
  std::vector<std::string_view> views(payloads.begin(), payloads.end());
  auto appended = queue.appendBatch(views);
  REQUIRE(appended);
  REQUIRE(*appended == first);
}

std::vector<telemetry::QueueRecord> peekAll(DiskQueue& queue) {
  auto records = queue.peek(SIZE_MAX);
  REQUIRE(records);
  return *records;
}

/// Every record is the one written for its sequence number, and the numbers run first, first+1, ...
void checkContiguous(const std::vector<telemetry::QueueRecord>& records, std::uint64_t first) {
  for (std::size_t i = 0; i < records.size(); ++i) {
    REQUIRE(records[i].sequence == first + i);
    REQUIRE(records[i].payload.substr(0, records[i].payload.find(' ', 7)) == "record " + std::to_string(first + i));
  }
}

std::string newestSegment(const std::string& folder) {
  std::string newest;
  for (const auto& entry : std::filesystem::directory_iterator(folder)) {
    const std::string name = entry.path().filename().string();
    if (name.starts_with("seg-") && entry.path().string() > newest) newest = entry.path().string();
  }
  return newest;
}

}  // namespace

TEST_CASE("crc32c gives the standard check value") { CHECK(telemetry::crc32c("123456789") == 0xE3069283u); }

TEST_CASE("records come back in order with consecutive sequence numbers until they are acked") {
  TempFolder folder;
  auto sut = openQueue(folder.path);
  REQUIRE(sut);
  appendRange(*sut, 1, 5);
  appendRange(*sut, 6, 5);
  const auto firstThree = sut->peek(3);
  REQUIRE(firstThree);
  REQUIRE(firstThree->size() == 3);
  checkContiguous(*firstThree, 1);
  CHECK(peekAll(*sut).size() == 10);  // peeking removes nothing

  REQUIRE(sut->ack(4));
  const auto rest = peekAll(*sut);
  REQUIRE(rest.size() == 6);
  checkContiguous(rest, 5);
  CHECK(sut->stats().pendingRecords == 6);
  CHECK(sut->stats().ackedSequence == 4);
  CHECK(sut->ack(2));  // an older ack changes nothing
  CHECK(peekAll(*sut).size() == 6);
  const auto neverGiven = sut->ack(11);
  REQUIRE_FALSE(neverGiven);
  CHECK(neverGiven.error().message.find("never given out") != std::string::npos);
}

TEST_CASE("peek stops at the byte budget but always returns at least one record") {
  TempFolder folder;
  auto sut = openQueue(folder.path);
  REQUIRE(sut);
  appendRange(*sut, 1, 4, 1000);
  auto two = sut->peek(10, 2500);
  REQUIRE(two);
  CHECK(two->size() == 2);
  auto one = sut->peek(10, 10);
  REQUIRE(one);
  CHECK(one->size() == 1);
}

TEST_CASE("a reopened queue keeps the unacked records, the acks and the numbering") {
  TempFolder folder;
  {
    auto sut = openQueue(folder.path);
    REQUIRE(sut);
    appendRange(*sut, 1, 20);
    REQUIRE(sut->ack(12));
  }
  std::vector<Error> warnings;
  auto sut = openQueue(folder.path, &warnings);
  REQUIRE(sut);
  CHECK(warnings.empty());
  const auto records = peekAll(*sut);
  REQUIRE(records.size() == 8);
  checkContiguous(records, 13);
  appendRange(*sut, 21, 1);
  CHECK(sut->stats().nextSequence == 22);
}

TEST_CASE("sequence numbers keep counting after every record was acked and the files were deleted") {
  TempFolder folder;
  {
    auto sut = openQueue(folder.path);
    REQUIRE(sut);
    for (std::uint64_t batch = 0; batch < 30; ++batch) appendRange(*sut, 1 + batch * 10, 10, 1000);
    REQUIRE(sut->ack(300));
    CHECK(sut->stats().segments == 1);  // fully acked segments are gone; the one being written stays
  }
  auto sut = openQueue(folder.path);
  REQUIRE(sut);
  CHECK(sut->stats().pendingRecords == 0);
  CHECK(peekAll(*sut).empty());
  appendRange(*sut, 301, 1);
}

TEST_CASE("a second process on the same folder is refused") {
  TempFolder folder;
  auto first = openQueue(folder.path);
  REQUIRE(first);
  auto second = openQueue(folder.path);
  REQUIRE_FALSE(second);
  CHECK(second.error().message.find("in use by another process") != std::string::npos);
}

TEST_CASE("limits below four segments, records larger than a segment and batches beyond the limit are refused") {
  TempFolder folder;
  CHECK_FALSE(DiskQueue::open({.folder = folder.path, .maxBytes = SMALL_SEGMENT, .segmentBytes = SMALL_SEGMENT}));
  auto sut = openQueue(folder.path);
  REQUIRE(sut);
  appendRange(*sut, 1, 3);
  const auto before = sut->stats();
  const std::string huge(SMALL_SEGMENT, 'x');  // with its 20-byte header one segment is too small
  const auto alone = sut->append(huge);
  REQUIRE_FALSE(alone);
  CHECK(alone.error().message.find("larger than a segment") != std::string::npos);
  // in the middle of a batch: nothing of the batch is stored, not even the records before it
  const std::string small = payloadFor(4);
  const std::vector<std::string_view> mixed{small, small, huge, small};
  const auto inBatch = sut->appendBatch(mixed);
  REQUIRE_FALSE(inBatch);
  CHECK(inBatch.error().message.find("record 3 of a batch of 4") != std::string::npos);
  // many small records together larger than the whole limit
  std::vector<std::string> payloads(SMALL_LIMIT / 1000 + 1, std::string(1000, 'y'));
  std::vector<std::string_view> views(payloads.begin(), payloads.end());
  const auto tooMany = sut->appendBatch(views);
  REQUIRE_FALSE(tooMany);
  CHECK(tooMany.error().message.find("larger than the queue limit") != std::string::npos);
  const auto after = sut->stats();
  CHECK(after.nextSequence == before.nextSequence);
  CHECK(after.diskBytes == before.diskBytes);
  CHECK(after.segments == before.segments);
  appendRange(*sut, 4, 1);  // the numbering goes on where it was
  checkContiguous(peekAll(*sut), 1);
}

TEST_CASE("a batch of three segments' worth is split over segments between records and read back in order") {
  TempFolder folder;
  constexpr std::size_t RECORD_BYTES = 1000;  // 1020 on disk: 64 in a segment
  constexpr std::uint64_t BIG = 3 * SMALL_SEGMENT / (RECORD_BYTES + 20) + 1;  // 193 records, 196,860 bytes
  {
    auto sut = openQueue(folder.path, nullptr, 1ull << 20);
    REQUIRE(sut);
    appendRange(*sut, 1, 5, RECORD_BYTES);  // the segment being written is not empty: the batch starts a new one
    appendRange(*sut, 6, BIG, RECORD_BYTES);
    appendRange(*sut, 6 + BIG, 5, RECORD_BYTES);  // fits the last segment of the split batch
    const auto stats = sut->stats();
    CHECK(stats.segments == 5);  // 5 records | 64 | 64 | 64 | 1 + 5
    CHECK(stats.pendingRecords == BIG + 10);
    CHECK(stats.diskBytes == (BIG + 10) * (RECORD_BYTES + 20));
    const auto records = peekAll(*sut);
    REQUIRE(records.size() == BIG + 10);
    checkContiguous(records, 1);
    for (const auto& record : records) REQUIRE(record.payload == payloadFor(record.sequence, RECORD_BYTES));
  }
  std::vector<std::string> segments;
  for (const auto& entry : std::filesystem::directory_iterator(folder.path)) {
    if (entry.path().filename().string().starts_with("seg-")) {
      segments.push_back(entry.path().filename().string());
      CHECK(std::filesystem::file_size(entry.path()) <= SMALL_SEGMENT);
    }
  }
  std::sort(segments.begin(), segments.end());
  CHECK(segments == std::vector<std::string>{"seg-00000000000000000001.q", "seg-00000000000000000006.q",
                                             "seg-00000000000000000070.q", "seg-00000000000000000134.q",
                                             "seg-00000000000000000198.q"});
  std::vector<Error> warnings;
  auto sut = openQueue(folder.path, &warnings, 1ull << 20);
  REQUIRE(sut);
  CHECK(warnings.empty());
  checkContiguous(peekAll(*sut), 1);
  REQUIRE(sut->ack(150));  // across the split: the three fully acked segments go
  CHECK(sut->stats().segments == 2);
  const auto rest = peekAll(*sut);
  REQUIRE(rest.size() == BIG + 10 - 150);
  checkContiguous(rest, 151);
}

TEST_CASE("at its byte limit the queue drops the oldest records first and reports them once") {
  TempFolder folder;
  auto sut = openQueue(folder.path);
  REQUIRE(sut);
  constexpr std::uint64_t RECORD_BYTES = 1000;
  constexpr std::uint64_t RECORDS = 600;  // ~600 kB into a 256 KiB queue
  constexpr std::uint64_t BATCH = 10;
  for (std::uint64_t s = 1; s <= RECORDS; s += BATCH) appendRange(*sut, s, BATCH, RECORD_BYTES);
  const auto stats = sut->stats();
  CHECK(stats.diskBytes <= SMALL_LIMIT);
  CHECK(stats.droppedRecords > 0);
  CHECK(stats.droppedRecords + stats.pendingRecords == RECORDS);
  const auto drops = sut->takeDrops();
  REQUIRE(drops.size() == 1);  // consecutive segments merge into one range
  CHECK(drops[0].firstSequence == 1);
  CHECK(drops[0].records == stats.droppedRecords);
  CHECK(drops[0].lastSequence == stats.droppedRecords);
  CHECK(sut->takeDrops().empty());
  const auto records = peekAll(*sut);
  REQUIRE(records.size() == stats.pendingRecords);
  checkContiguous(records, stats.droppedRecords + 1);  // the newest survive, in order
  CHECK(records.back().sequence == RECORDS);
}

TEST_CASE("at its byte limit batches split over segments drop the oldest records first and report them once") {
  TempFolder folder;
  auto sut = openQueue(folder.path);  // 256 KiB in segments of 64 KiB
  REQUIRE(sut);
  constexpr std::size_t RECORD_BYTES = 1000;
  constexpr std::uint64_t BATCH = 100;  // 102,000 bytes: one and a half segments
  constexpr std::uint64_t BATCHES = 10;
  for (std::uint64_t b = 0; b < BATCHES; ++b) {
    appendRange(*sut, 1 + b * BATCH, BATCH, RECORD_BYTES);
    REQUIRE(sut->stats().diskBytes <= SMALL_LIMIT);
  }
  const auto stats = sut->stats();
  CHECK(stats.droppedRecords > 0);
  CHECK(stats.droppedRecords + stats.pendingRecords == BATCHES * BATCH);
  CHECK(stats.pendingRecords >= BATCH);  // the newest batch is whole
  const auto drops = sut->takeDrops();
  REQUIRE(drops.size() == 1);
  CHECK(drops[0].firstSequence == 1);
  CHECK(drops[0].lastSequence == stats.droppedRecords);
  CHECK(drops[0].records == stats.droppedRecords);
  const auto records = peekAll(*sut);
  REQUIRE(records.size() == stats.pendingRecords);
  checkContiguous(records, stats.droppedRecords + 1);
  CHECK(records.back().sequence == BATCHES * BATCH);
}

TEST_CASE("acked records dropped at the limit are not counted as lost") {
  TempFolder folder;
  auto sut = openQueue(folder.path);
  REQUIRE(sut);
  for (std::uint64_t s = 1; s <= 600; s += 10) {
    appendRange(*sut, s, 10, 1000);
    REQUIRE(sut->ack(s + 9));
  }
  CHECK(sut->stats().droppedRecords == 0);
  CHECK(sut->takeDrops().empty());
}

TEST_CASE("a smaller limit after a restart keeps the records until room is needed, then drops the oldest") {
  TempFolder folder;
  constexpr std::size_t LARGE_RECORD = 100 * 1024;  // larger than a segment of the smaller limit
  {
    auto sut = DiskQueue::open({.folder = folder.path, .maxBytes = 64ull << 20});
    REQUIRE(sut);
    for (std::uint64_t s = 1; s <= 3; ++s) appendRange(*sut, s, 1, LARGE_RECORD);
  }
  std::vector<Error> warnings;
  auto sut = openQueue(folder.path, &warnings);
  REQUIRE(sut);
  CHECK(warnings.empty());
  const auto kept = peekAll(*sut);
  REQUIRE(kept.size() == 3);
  checkContiguous(kept, 1);
  appendRange(*sut, 4, 1);  // 300 KiB on disk, 256 KiB allowed: the old segment goes
  const auto drops = sut->takeDrops();
  REQUIRE(drops.size() == 1);
  CHECK(drops[0].firstSequence == 1);
  CHECK(drops[0].lastSequence == 3);
  const auto records = peekAll(*sut);
  REQUIRE(records.size() == 1);
  CHECK(records[0].sequence == 4);
}

TEST_CASE("a truncated last record is cut off on open and named with its file and offset") {
  TempFolder folder;
  std::string segment;
  {
    auto sut = openQueue(folder.path);
    REQUIRE(sut);
    appendRange(*sut, 1, 10);
    segment = newestSegment(folder.path);
  }
  const auto size = std::filesystem::file_size(segment);
  std::filesystem::resize_file(segment, size - 30);  // a power cut inside the last record
  std::vector<Error> warnings;
  auto sut = openQueue(folder.path, &warnings);
  REQUIRE(sut);
  REQUIRE(warnings.size() == 1);
  const std::string warning = warnings[0].toString();
  CHECK(warning.find(segment) != std::string::npos);
  CHECK(warning.find("byte offset " + std::to_string(size / 10 * 9)) != std::string::npos);
  CHECK(warning.find("truncated") != std::string::npos);
  const auto records = peekAll(*sut);
  REQUIRE(records.size() == 9);
  checkContiguous(records, 1);
  appendRange(*sut, 10, 1);  // the lost record's number is given again: it was never sent
}

TEST_CASE("a corrupt record stops its segment there and later segments are kept") {
  TempFolder folder;
  {
    auto sut = openQueue(folder.path);
    REQUIRE(sut);
    for (std::uint64_t s = 1; s <= 100; s += 10) appendRange(*sut, s, 10, 1000);  // two segments
    REQUIRE(sut->stats().segments == 2);
  }
  std::vector<std::string> segments;
  for (const auto& entry : std::filesystem::directory_iterator(folder.path)) {
    if (entry.path().filename().string().starts_with("seg-")) segments.push_back(entry.path().string());
  }
  std::sort(segments.begin(), segments.end());
  REQUIRE(segments.size() == 2);
  {
    std::fstream file(segments[0], std::ios::in | std::ios::out | std::ios::binary);
    file.seekp(10 * 1020 + 500);  // inside the 11th record's payload
    file.put('#');
  }
  std::vector<Error> warnings;
  auto sut = openQueue(folder.path, &warnings);
  REQUIRE(sut);
  REQUIRE(warnings.size() == 1);
  CHECK(warnings[0].toString().find("byte offset 10200: CRC mismatch; recovered 10 records") != std::string::npos);
  const auto records = peekAll(*sut);
  REQUIRE(records.size() > 10);
  checkContiguous({records.begin(), records.begin() + 10}, 1);
  CHECK(records[10].sequence > 11);  // a gap the consumer sees
  checkContiguous({records.begin() + 10, records.end()}, records[10].sequence);
  CHECK(records.back().sequence == 100);
}

TEST_CASE("garbage files and a damaged ack state never stop the queue from opening") {
  TempFolder folder;
  {
    std::ofstream garbage(folder.path + "/seg-00000000000000000001.q", std::ios::binary);
    for (int i = 0; i < 5000; ++i) garbage.put(static_cast<char>(i * 7919 % 251));
    std::ofstream ack(folder.path + "/ack.state", std::ios::binary);
    ack << "not an ack state at all, definitely not";
  }
  std::vector<Error> warnings;
  auto sut = openQueue(folder.path, &warnings);
  REQUIRE(sut);
  CHECK(warnings.size() == 2);
  CHECK(peekAll(*sut).empty());
  appendRange(*sut, 1, 3);
  CHECK(peekAll(*sut).size() == 3);
}

TEST_CASE("a writer killed with SIGKILL loses nothing it reported as synced, duplicates nothing, at most one batch") {
  TempFolder folder;
  constexpr std::uint64_t BATCH = 8;
  constexpr int ROUNDS = 3;
  std::uint64_t reportedLast = 0;
  std::uint64_t reportedAcked = 0;
  for (int round = 0; round < ROUNDS; ++round) {
    int report[2];
    REQUIRE(::pipe(report) == 0);
    const pid_t child = ::fork();
    REQUIRE(child >= 0);
    if (child == 0) {
      // the writer: appends batches for ever, acks all but the last few, reports (last, acked)
      ::close(report[0]);
      auto queue = openQueue(folder.path, nullptr, 1ull << 20);
      if (!queue) ::_exit(2);
      for (;;) {
        const std::uint64_t first = queue->stats().nextSequence;
        std::vector<std::string> payloads;
        for (std::uint64_t s = first; s < first + BATCH; ++s) payloads.push_back(payloadFor(s, 300));
        std::vector<std::string_view> views(payloads.begin(), payloads.end());
        if (!queue->appendBatch(views)) ::_exit(3);
        const std::uint64_t last = first + BATCH - 1;
        const std::uint64_t acked = last > 3 * BATCH ? last - 3 * BATCH : 0;
        if (acked > 0 && !queue->ack(acked)) ::_exit(4);
        const std::uint64_t message[2] = {last, acked};
        if (::write(report[1], message, sizeof message) != sizeof message) ::_exit(5);
      }
    }
    ::close(report[1]);
    const int reportsBeforeKill = 20 + 15 * round;
    std::uint64_t message[2];
    for (int i = 0; i < reportsBeforeKill; ++i) {
      REQUIRE(::read(report[0], message, sizeof message) == static_cast<ssize_t>(sizeof message));
      reportedLast = message[0];
      reportedAcked = message[1];
    }
    REQUIRE(::kill(child, SIGKILL) == 0);
    int status = 0;
    REQUIRE(::waitpid(child, &status, 0) == child);
    REQUIRE(WIFSIGNALED(status));
    while (::read(report[0], message, sizeof message) == static_cast<ssize_t>(sizeof message)) {
      reportedLast = message[0];
      reportedAcked = message[1];
    }
    ::close(report[0]);

    std::vector<Error> warnings;
    auto sut = openQueue(folder.path, &warnings, 1ull << 20);
    REQUIRE(sut);
    const auto stats = sut->stats();
    const auto records = peekAll(*sut);
    INFO("round " << round << ", reported last " << reportedLast << " acked " << reportedAcked);
    CHECK(stats.droppedRecords == 0);
    CHECK(stats.ackedSequence >= reportedAcked);
    REQUIRE_FALSE(records.empty());
    CHECK(records.front().sequence == stats.ackedSequence + 1);  // nothing unacked missing at the front
    checkContiguous(records, records.front().sequence);         // in order, no duplicates, no gaps
    CHECK(records.back().sequence >= reportedLast);              // nothing reported as synced is lost
    CHECK(records.back().sequence <= reportedLast + BATCH);      // at most the batch being written beyond
    CHECK(records.back().sequence + 1 == stats.nextSequence);
  }
}

TEST_CASE("a writer killed with SIGKILL inside batches split over segments leaves whole records, in order, no hole") {
  TempFolder folder;
  constexpr std::size_t RECORD_BYTES = 1000;
  constexpr std::uint64_t BATCH = 3 * SMALL_SEGMENT / (RECORD_BYTES + 20) + 1;  // three segments and a record
  constexpr std::uint64_t LIMIT = 4ull << 20;  // never reached: nothing is dropped
  constexpr int ROUNDS = 4;
  int cutInsideBatch = 0;  // rounds whose recovered queue ends inside a batch
  std::uint64_t reportedLast = 0;
  for (int round = 0; round < ROUNDS; ++round) {
    int report[2];
    REQUIRE(::pipe(report) == 0);
    const pid_t child = ::fork();
    REQUIRE(child >= 0);
    if (child == 0) {
      // the writer: appends split batches for ever, acks all but the last two, reports the last synced
      ::close(report[0]);
      auto queue = openQueue(folder.path, nullptr, LIMIT);
      if (!queue) ::_exit(2);
      std::vector<std::string> payloads;
      for (;;) {
        const std::uint64_t first = queue->stats().nextSequence;
        payloads.clear();
        for (std::uint64_t s = first; s < first + BATCH; ++s) payloads.push_back(payloadFor(s, RECORD_BYTES));
        std::vector<std::string_view> views(payloads.begin(), payloads.end());
        if (!queue->appendBatch(views)) ::_exit(3);
        const std::uint64_t last = first + BATCH - 1;
        if (last > 2 * BATCH && !queue->ack(last - 2 * BATCH)) ::_exit(4);
        if (::write(report[1], &last, sizeof last) != sizeof last) ::_exit(5);
      }
    }
    ::close(report[1]);
    std::uint64_t last = 0;
    for (int i = 0; i < 3 + round; ++i) {
      REQUIRE(::read(report[0], &last, sizeof last) == static_cast<ssize_t>(sizeof last));
      reportedLast = last;
    }
    ::usleep(static_cast<useconds_t>(round * 700));  // a different point of the next batch each round
    REQUIRE(::kill(child, SIGKILL) == 0);
    int status = 0;
    REQUIRE(::waitpid(child, &status, 0) == child);
    REQUIRE(WIFSIGNALED(status));
    while (::read(report[0], &last, sizeof last) == static_cast<ssize_t>(sizeof last)) reportedLast = last;
    ::close(report[0]);

    std::vector<Error> warnings;
    auto sut = openQueue(folder.path, &warnings, LIMIT);
    REQUIRE(sut);
    for (const Error& warning : warnings) CHECK(warning.message.find("truncated") != std::string::npos);
    const auto stats = sut->stats();
    const auto records = peekAll(*sut);
    INFO("round " << round << ", reported last " << reportedLast);
    REQUIRE_FALSE(records.empty());
    CHECK(records.front().sequence == stats.ackedSequence + 1);
    checkContiguous(records, records.front().sequence);
    for (const auto& record : records) REQUIRE(record.payload == payloadFor(record.sequence, RECORD_BYTES));
    CHECK(records.back().sequence >= reportedLast);
    CHECK(records.back().sequence <= reportedLast + BATCH);  // at most the batch being written beyond
    CHECK(records.back().sequence + 1 == stats.nextSequence);
    if (records.back().sequence > reportedLast && records.back().sequence < reportedLast + BATCH) ++cutInsideBatch;
  }
  MESSAGE(cutInsideBatch << " of " << ROUNDS << " kills left part of a split batch (whole records)");
}
