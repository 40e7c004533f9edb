// bench_queue: vcu-telemetry's store-and-forward queue, the segment-file DiskQueue
// (services/telemetry) against a SQLite prototype of the same contract (this file only):
// append batches of records with one fsync per batch, then drain everything (peek up to 100,
// ack the last). Run on the disk the queue will live on:
//   build/bench/bench_queue [--dir DIR] [--batches N] [--records-per-batch R] [--record-bytes B]
// Last line: RESULT file_append_batches_per_s=.. file_append_p99_ms=.. sqlite_append_batches_per_s=..
//   sqlite_append_p99_ms=.. file_drain_records_per_s=.. sqlite_drain_records_per_s=..
#include <sqlite3.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "disk_queue.hpp"

namespace {

using Clock = std::chrono::steady_clock;

struct Measured {
  double appendBatchesPerSecond{};
  double appendP50Ms{};
  double appendP99Ms{};
  double drainRecordsPerSecond{};
  std::size_t drained{};
};

double percentile(std::vector<double> values, double fraction) {
  std::sort(values.begin(), values.end());
  return values[static_cast<std::size_t>(fraction * static_cast<double>(values.size() - 1))];
}

double seconds(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

[[noreturn]] void fail(const std::string& what) {
  std::fprintf(stderr, "bench_queue: %s\n", what.c_str());
  std::exit(1);
}

Measured benchFile(const std::string& folder, int batches, int perBatch, const std::string& record) {
  std::filesystem::remove_all(folder);
  auto queue = openvcu::telemetry::DiskQueue::open({.folder = folder, .maxBytes = 1ull << 30});
  if (!queue) fail(queue.error().toString());
  std::vector<std::string_view> batch(static_cast<std::size_t>(perBatch), record);
  std::vector<double> latencies;
  const auto start = Clock::now();
  for (int i = 0; i < batches; ++i) {
    const auto before = Clock::now();
    if (auto appended = queue->appendBatch(batch); !appended) fail(appended.error().toString());
    latencies.push_back(seconds(before) * 1e3);
  }
  Measured result;
  result.appendBatchesPerSecond = batches / seconds(start);
  result.appendP50Ms = percentile(latencies, 0.5);
  result.appendP99Ms = percentile(latencies, 0.99);
  const auto drainStart = Clock::now();
  for (;;) {
    auto records = queue->peek(100);
    if (!records) fail(records.error().toString());
    if (records->empty()) break;
    result.drained += records->size();
    if (auto acked = queue->ack(records->back().sequence); !acked) fail(acked.error().toString());
  }
  result.drainRecordsPerSecond = static_cast<double>(result.drained) / seconds(drainStart);
  return result;
}

void exec(sqlite3* db, const char* sql) {
  char* message = nullptr;
  if (sqlite3_exec(db, sql, nullptr, nullptr, &message) != SQLITE_OK) fail(std::string(sql) + ": " + message);
}

// The SQLite prototype: WAL, synchronous=FULL for appends (the WAL is fsync'ed per commit),
// NORMAL for acks (as the file queue, an ack is not synced on its own).
Measured benchSqlite(const std::string& folder, int batches, int perBatch, const std::string& record) {
  std::filesystem::remove_all(folder);
  std::filesystem::create_directories(folder);
  sqlite3* db = nullptr;
  if (sqlite3_open((folder + "/queue.db").c_str(), &db) != SQLITE_OK) fail("sqlite3_open");
  exec(db, "PRAGMA journal_mode=WAL");
  exec(db, "CREATE TABLE q(seq INTEGER PRIMARY KEY, payload BLOB NOT NULL)");
  sqlite3_stmt* insert = nullptr;
  sqlite3_stmt* select = nullptr;
  sqlite3_stmt* remove = nullptr;
  sqlite3_prepare_v2(db, "INSERT INTO q VALUES(?, ?)", -1, &insert, nullptr);
  sqlite3_prepare_v2(db, "SELECT seq, payload FROM q WHERE seq > ? ORDER BY seq LIMIT 100", -1, &select, nullptr);
  sqlite3_prepare_v2(db, "DELETE FROM q WHERE seq <= ?", -1, &remove, nullptr);
  std::vector<double> latencies;
  sqlite3_int64 sequence = 1;
  exec(db, "PRAGMA synchronous=FULL");
  const auto start = Clock::now();
  for (int i = 0; i < batches; ++i) {
    const auto before = Clock::now();
    exec(db, "BEGIN");
    for (int r = 0; r < perBatch; ++r) {
      sqlite3_bind_int64(insert, 1, sequence++);
      sqlite3_bind_blob(insert, 2, record.data(), static_cast<int>(record.size()), SQLITE_STATIC);
      if (sqlite3_step(insert) != SQLITE_DONE) fail(sqlite3_errmsg(db));
      sqlite3_reset(insert);
    }
    exec(db, "COMMIT");
    latencies.push_back(seconds(before) * 1e3);
  }
  Measured result;
  result.appendBatchesPerSecond = batches / seconds(start);
  result.appendP50Ms = percentile(latencies, 0.5);
  result.appendP99Ms = percentile(latencies, 0.99);
  exec(db, "PRAGMA synchronous=NORMAL");
  sqlite3_int64 acked = 0;
  const auto drainStart = Clock::now();
  for (;;) {
    sqlite3_bind_int64(select, 1, acked);
    std::size_t got = 0;
    std::string payload;
    while (sqlite3_step(select) == SQLITE_ROW) {
      acked = sqlite3_column_int64(select, 0);
      payload.assign(static_cast<const char*>(sqlite3_column_blob(select, 1)),
                     static_cast<std::size_t>(sqlite3_column_bytes(select, 1)));
      ++got;
    }
    sqlite3_reset(select);
    if (got == 0) break;
    result.drained += got;
    sqlite3_bind_int64(remove, 1, acked);
    if (sqlite3_step(remove) != SQLITE_DONE) fail(sqlite3_errmsg(db));
    sqlite3_reset(remove);
  }
  result.drainRecordsPerSecond = static_cast<double>(result.drained) / seconds(drainStart);
  sqlite3_finalize(insert);
  sqlite3_finalize(select);
  sqlite3_finalize(remove);
  sqlite3_close(db);
  return result;
}

}  // namespace

int main(int argc, char** argv) {
  std::string dir = "bench-queue.tmp";
  int batches = 2000;
  int perBatch = 1;
  int recordBytes = 1024;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string_view option = argv[i];
    if (option == "--dir") dir = argv[i + 1];
    else if (option == "--batches") batches = std::atoi(argv[i + 1]);
    else if (option == "--records-per-batch") perBatch = std::atoi(argv[i + 1]);
    else if (option == "--record-bytes") recordBytes = std::atoi(argv[i + 1]);
    else fail("unknown option " + std::string(option) + " (--dir, --batches, --records-per-batch, --record-bytes)");
  }
  if (batches < 1 || perBatch < 1 || recordBytes < 1) fail("counts must be positive");
  std::string record(static_cast<std::size_t>(recordBytes), '\0');
  for (std::size_t i = 0; i < record.size(); ++i) record[i] = static_cast<char>('a' + i % 26);
  std::printf("queue bench: %d batches of %d x %d bytes, fsync per batch, in %s\n", batches, perBatch, recordBytes,
              dir.c_str());
  const Measured file = benchFile(dir + "/file", batches, perBatch, record);
  const Measured sql = benchSqlite(dir + "/sqlite", batches, perBatch, record);
  std::filesystem::remove_all(dir);
  for (const auto& [name, m] : {std::pair{"segment file", file}, std::pair{"sqlite WAL", sql}}) {
    std::printf("%-13s append %.0f batches/s (p50 %.2f ms, p99 %.2f ms), drain %.0f records/s (%zu records)\n", name,
                m.appendBatchesPerSecond, m.appendP50Ms, m.appendP99Ms, m.drainRecordsPerSecond, m.drained);
  }
  std::printf("RESULT file_append_batches_per_s=%.0f file_append_p99_ms=%.2f sqlite_append_batches_per_s=%.0f "
              "sqlite_append_p99_ms=%.2f file_drain_records_per_s=%.0f sqlite_drain_records_per_s=%.0f\n",
              file.appendBatchesPerSecond, file.appendP99Ms, sql.appendBatchesPerSecond, sql.appendP99Ms,
              file.drainRecordsPerSecond, sql.drainRecordsPerSecond);
  return 0;
}
