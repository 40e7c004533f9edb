// bench_queue: vcu-telemetry's store-and-forward queue, the segment-file DiskQueue
// (services/telemetry) against a SQLite prototype of the same contract (this file only):
// append batches of records with one fsync per batch, then drain everything (peek up to 100,
// ack the last); the two alternate batch by batch so that both meet the same disk. Rates are
// per second of time spent in the queue's own calls. Run on the disk the queue will live on:
//   build/bench/bench_queue [--dir DIR] [--batches N] [--records-per-batch R] [--record-bytes B]
// Last line: RESULT file_append_batches_per_s=.. file_append_p99_ms=.. sqlite_append_batches_per_s=..
//   sqlite_append_p99_ms=.. file_drain_records_per_s=.. sqlite_drain_records_per_s=..
#include <sqlite3.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <optional>
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

/// One queue under test: append a batch (synced), drain a step (read up to 100, ack them).
class BenchQueue {
 public:
  virtual ~BenchQueue() = default;
  virtual void appendBatch(const std::vector<std::string_view>& batch) = 0;
  /// Records read and acked; 0 when empty.
  virtual std::size_t drainStep() = 0;
};

class FileQueue final : public BenchQueue {
 public:
  explicit FileQueue(const std::string& folder) {
    std::filesystem::remove_all(folder);
    auto opened = openvcu::telemetry::DiskQueue::open({.folder = folder, .maxBytes = 1ull << 30});
    if (!opened) fail(opened.error().toString());
    m_queue.emplace(std::move(*opened));
  }
  void appendBatch(const std::vector<std::string_view>& batch) override {
    if (auto appended = m_queue->appendBatch(batch); !appended) fail(appended.error().toString());
  }
  std::size_t drainStep() override {
    auto records = m_queue->peek(100);
    if (!records) fail(records.error().toString());
    if (records->empty()) return 0;
    if (auto acked = m_queue->ack(records->back().sequence); !acked) fail(acked.error().toString());
    return records->size();
  }

 private:
  std::optional<openvcu::telemetry::DiskQueue> m_queue;
};

// The SQLite prototype: WAL, synchronous=FULL for appends (the WAL is fsync'ed per commit),
// NORMAL for acks (as the file queue, an ack is not synced on its own).
class SqliteQueue final : public BenchQueue {
 public:
  explicit SqliteQueue(const std::string& folder) {
    std::filesystem::remove_all(folder);
    std::filesystem::create_directories(folder);
    if (sqlite3_open((folder + "/queue.db").c_str(), &m_db) != SQLITE_OK) fail("sqlite3_open");
    exec("PRAGMA journal_mode=WAL");
    exec("CREATE TABLE q(seq INTEGER PRIMARY KEY, payload BLOB NOT NULL)");
    sqlite3_prepare_v2(m_db, "INSERT INTO q VALUES(?, ?)", -1, &m_insert, nullptr);
    sqlite3_prepare_v2(m_db, "SELECT seq, payload FROM q WHERE seq > ? ORDER BY seq LIMIT 100", -1, &m_select, nullptr);
    sqlite3_prepare_v2(m_db, "DELETE FROM q WHERE seq <= ?", -1, &m_remove, nullptr);
  }
  ~SqliteQueue() override {
    sqlite3_finalize(m_insert);
    sqlite3_finalize(m_select);
    sqlite3_finalize(m_remove);
    sqlite3_close(m_db);
  }
  void appendBatch(const std::vector<std::string_view>& batch) override {
    exec("PRAGMA synchronous=FULL");
    exec("BEGIN");
    for (const std::string_view record : batch) {
      sqlite3_bind_int64(m_insert, 1, m_sequence++);
      sqlite3_bind_blob(m_insert, 2, record.data(), static_cast<int>(record.size()), SQLITE_STATIC);
      if (sqlite3_step(m_insert) != SQLITE_DONE) fail(sqlite3_errmsg(m_db));
      sqlite3_reset(m_insert);
    }
    exec("COMMIT");
  }
  std::size_t drainStep() override {
    exec("PRAGMA synchronous=NORMAL");
    sqlite3_bind_int64(m_select, 1, m_acked);
    std::size_t got = 0;
    std::string payload;
    while (sqlite3_step(m_select) == SQLITE_ROW) {
      m_acked = sqlite3_column_int64(m_select, 0);
      payload.assign(static_cast<const char*>(sqlite3_column_blob(m_select, 1)),
                     static_cast<std::size_t>(sqlite3_column_bytes(m_select, 1)));
      ++got;
    }
    sqlite3_reset(m_select);
    if (got == 0) return 0;
    sqlite3_bind_int64(m_remove, 1, m_acked);
    if (sqlite3_step(m_remove) != SQLITE_DONE) fail(sqlite3_errmsg(m_db));
    sqlite3_reset(m_remove);
    return got;
  }

 private:
  void exec(const char* sql) {
    char* message = nullptr;
    if (sqlite3_exec(m_db, sql, nullptr, nullptr, &message) != SQLITE_OK) fail(std::string(sql) + ": " + message);
  }
  sqlite3* m_db{};
  sqlite3_stmt* m_insert{};
  sqlite3_stmt* m_select{};
  sqlite3_stmt* m_remove{};
  sqlite3_int64 m_sequence{1};
  sqlite3_int64 m_acked{};
};

/// Runs both queues side by side, alternating batch by batch and drain step by drain step, so
/// that both meet the same disk (this VM's fsync time changes by 10x within minutes).
std::vector<Measured> benchSideBySide(std::vector<BenchQueue*> queues, int batches, int perBatch,
                                      const std::string& record) {
  const std::vector<std::string_view> batch(static_cast<std::size_t>(perBatch), record);
  std::vector<std::vector<double>> latencies(queues.size());
  std::vector<Measured> results(queues.size());
  for (int i = 0; i < batches; ++i) {
    for (std::size_t q = 0; q < queues.size(); ++q) {
      const auto before = Clock::now();
      queues[q]->appendBatch(batch);
      latencies[q].push_back(seconds(before) * 1e3);
    }
  }
  std::vector<double> drainSeconds(queues.size());
  std::vector<bool> done(queues.size());
  while (std::find(done.begin(), done.end(), false) != done.end()) {
    for (std::size_t q = 0; q < queues.size(); ++q) {
      if (done[q]) continue;
      const auto before = Clock::now();
      const std::size_t got = queues[q]->drainStep();
      drainSeconds[q] += seconds(before);
      results[q].drained += got;
      done[q] = got == 0;
    }
  }
  for (std::size_t q = 0; q < queues.size(); ++q) {
    double total = 0;
    for (const double ms : latencies[q]) total += ms;
    results[q].appendBatchesPerSecond = batches / (total / 1e3);
    results[q].appendP50Ms = percentile(latencies[q], 0.5);
    results[q].appendP99Ms = percentile(latencies[q], 0.99);
    results[q].drainRecordsPerSecond = static_cast<double>(results[q].drained) / drainSeconds[q];
  }
  return results;
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
  std::vector<Measured> results;
  {
    FileQueue fileQueue(dir + "/file");
    SqliteQueue sqliteQueue(dir + "/sqlite");
    results = benchSideBySide({&fileQueue, &sqliteQueue}, batches, perBatch, record);
  }
  const Measured file = results[0];
  const Measured sql = results[1];
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
