// The vcu-telemetry load benchmark's helper (docs/benchmarks.md, "Telemetry: CPU, RSS, drain
// and payload"), driven by bench/telemetry/run_telemetry_bench.sh inside the sandbox. One
// program, five modes:
//
//   bench_telemetry_load select --config vehicle.json --count 200 --rate-hz 10
//       prints telemetry.json's "signals" array: the first COUNT DBC signals of the catalog
//       with a range (received first, then transmitted), maxRateHz RATE, deadband 0.
//   bench_telemetry_load write --config vehicle.json --telemetry telemetry.json --write-hz 20
//       writes every configured signal's bus value WRITE_HZ times a second (absolute
//       deadlines), each write a new value (a ramp in steps of 0.05, or 1 for enumerations,
//       inside the DBC range),
//       until SIGTERM; prints "writes N" at the end.
//   bench_telemetry_load watch --port 1883 --out arrivals.txt
//       subscribes to openvcu/# (QoS 1) and writes one line per message, flushed:
//       "<arrival Unix ms> <arrival monotonic ns> <topic suffix> <bytes> <seq|-> <t|-> <samples|-> <binary bytes|->"
//       where the binary bytes are the size of the same signals message in the binary form below;
//       until SIGTERM. Says "subscribed" on stderr when the broker confirmed the subscription.
//   bench_telemetry_load fill --queue DIR --records N --bytes B
//       appends N records "bench\n{"v":1,"seq":S,"t":T,"pad":"xxx..."}" of about B bytes to the
//       queue in DIR (vcu-telemetry's DiskQueue, batches of 100, fdatasync per batch): a backlog
//       for the drain measurement. vcu-telemetry must not run on DIR meanwhile (the queue's lock).
//   bench_telemetry_load encode --config vehicle.json --telemetry telemetry.json --seconds 60
//       in process, on a table of its own (instance "bench-encode"): per simulated second, ten
//       rounds of "write every signal, Engine::sample"; then Engine::tick (the JSON records) and
//       the binary prototype of the same samples; prints the CPU per simulated second of each
//       and the bytes, also after zlib's deflate (level 6) of each signals message.
//
// The binary form (a prototype in this bench only, never sent): little endian,
//   u8 version (1) | u8 kind (1 = signals) | u64 seq | i64 t (Unix ms) | u16 sample count |
//   per sample: u16 signal index (into the birth's "signals" list) | u16 ms before t | f64 value
// i.e. 20 bytes of header and 12 per sample (names are known from the birth).
#include <mosquitto.h>
#include <signal.h>
#include <time.h>
#include <zlib.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "disk_queue.hpp"
#include "engine.hpp"
#include "openvcu/config/catalog.hpp"
#include "openvcu/config/telemetry.hpp"
#include "openvcu/config/vehicle.hpp"
#include "openvcu/core/clock.hpp"
#include "openvcu/signals/table.hpp"

namespace {

using namespace openvcu;
using Json = nlohmann::json;

constexpr std::int64_t NS_PER_S = 1'000'000'000;
constexpr std::size_t BINARY_HEADER_BYTES = 1 + 1 + 8 + 8 + 2;
constexpr std::size_t BINARY_SAMPLE_BYTES = 2 + 2 + 8;
constexpr std::size_t FILL_BATCH = 100;
constexpr std::uint16_t SOURCE = 0xF3;
constexpr double QUANTUM = 0.05;  ///< written values are multiples of this (a typical DBC factor)

std::atomic<bool> g_stop{false};
void onSignal(int /*signal*/) {
  g_stop = true;
}

[[noreturn]] void fail(const std::string& text) {
  std::cerr << "bench_telemetry_load: " << text << "\n";
  std::exit(1);
}

void sleepUntil(std::int64_t deadlineNs) {
  timespec deadline{};
  deadline.tv_sec = static_cast<time_t>(deadlineNs / NS_PER_S);
  deadline.tv_nsec = static_cast<long>(deadlineNs % NS_PER_S);
  while (::clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &deadline, nullptr) != 0 && !g_stop) {
  }
}

std::int64_t threadCpuNs() {
  timespec now{};
  ::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  return static_cast<std::int64_t>(now.tv_sec) * NS_PER_S + now.tv_nsec;
}

struct Vehicle {
  config::VehicleConfig config;
  signals::Catalog catalog;
};

Vehicle loadVehicle(const std::string& path) {
  auto vehicle = config::loadVehicleConfig(path);
  if (!vehicle) fail(vehicle.error().toString());
  auto catalog = config::buildCatalog(*vehicle);
  if (!catalog) fail(catalog.error().toString());
  return Vehicle{std::move(*vehicle), std::move(*catalog)};
}

/// The configured signals' catalog indices, in telemetry.json's order.
std::vector<signals::SignalIndex> configuredSignals(const signals::Catalog& catalog,
                                                    const config::TelemetryConfig& settings) {
  std::vector<signals::SignalIndex> out;
  for (const config::TelemetrySignal& signal : settings.signals) {
    const auto index = catalog.indexOf(signal.name);
    if (!index) fail(signal.name + ": not in the catalog");
    out.push_back(*index);
  }
  return out;
}

/// The value of signal `i` at write `step`: a ramp through its DBC range, a new value each step
/// (steps of QUANTUM, of 1 for a signal with a value table or a range up to 3).
double valueAt(const signals::SignalInfo& info, std::size_t i, std::uint64_t step) {
  const double span = info.maximum - info.minimum;
  const double quantum = !info.valueTexts.empty() || span <= 3 ? 1.0 : QUANTUM;
  const auto steps = static_cast<std::uint64_t>(std::max(2.0, std::floor(span / quantum) + 1));
  const std::uint64_t position = (step + i * 7) % steps;
  return info.minimum + static_cast<double>(position) * quantum;
}

int select(const std::string& vehiclePath, int count, double rateHz) {
  const Vehicle vehicle = loadVehicle(vehiclePath);
  Json list = Json::array();
  for (const signals::SignalInfo& info : vehicle.catalog.signals()) {
    if (static_cast<int>(list.size()) == count) break;
    if (info.kind != signals::SignalKind::Bus || info.direction != signals::SignalDirection::Received) continue;
    if (info.maximum <= info.minimum) continue;
    list.push_back({{"name", info.key}, {"maxRateHz", rateHz}, {"deadband", 0}});
  }
  // then the transmitted ones (their bus plane is shown once written, as a received signal's)
  for (const signals::SignalInfo& info : vehicle.catalog.signals()) {
    if (static_cast<int>(list.size()) == count) break;
    if (info.kind != signals::SignalKind::Bus || info.direction == signals::SignalDirection::Received) continue;
    if (info.maximum <= info.minimum) continue;
    list.push_back({{"name", info.key}, {"maxRateHz", rateHz}, {"deadband", 0}});
  }
  if (static_cast<int>(list.size()) < count)
    fail("the catalog has only " + std::to_string(list.size()) + " suitable signals");
  std::cout << list.dump() << "\n";
  return 0;
}

int write(const std::string& vehiclePath, const std::string& telemetryPath, double writeHz) {
  const Vehicle vehicle = loadVehicle(vehiclePath);
  auto settings = config::loadTelemetryConfig(telemetryPath);
  if (!settings) fail(settings.error().toString());
  const auto indices = configuredSignals(vehicle.catalog, *settings);
  auto table = signals::SignalTable::open(vehicle.catalog, vehicle.config.instance);
  if (!table) fail(table.error().toString());
  const auto periodNs = static_cast<std::int64_t>(1e9 / writeHz);
  std::int64_t deadline = clock::monotonicNs();
  std::uint64_t writes = 0;
  for (std::uint64_t step = 0; !g_stop; ++step) {
    const std::int64_t now = clock::monotonicNs();
    for (std::size_t i = 0; i < indices.size(); ++i) {
      table->writeBus(indices[i], valueAt(vehicle.catalog[indices[i]], i, step), now, SOURCE, signals::Quality::Valid);
      ++writes;
    }
    deadline += periodNs;
    sleepUntil(deadline);
  }
  std::cout << "writes " << writes << "\n";
  return 0;
}

/// The binary form's size of a signals message (see the top of this file).
std::size_t binaryBytes(std::size_t samples) {
  return BINARY_HEADER_BYTES + samples * BINARY_SAMPLE_BYTES;
}

struct Watcher {
  std::FILE* out{};
  std::mutex mutex;
};

int watch(int port, const std::string& outPath) {
  Watcher watcher;
  watcher.out = std::fopen(outPath.c_str(), "w");
  if (watcher.out == nullptr) fail(outPath + ": " + std::strerror(errno));
  mosquitto_lib_init();
  mosquitto* mosq = mosquitto_new("bench-telemetry-watch", true, &watcher);
  if (mosq == nullptr) fail("mosquitto_new");
  mosquitto_reconnect_delay_set(mosq, 1, 1, false);
  mosquitto_connect_callback_set(mosq, [](mosquitto* client, void*, int rc) {
    if (rc == 0) mosquitto_subscribe(client, nullptr, "openvcu/#", 1);
  });
  mosquitto_subscribe_callback_set(
      mosq, [](mosquitto*, void*, int, int, const int*) { std::cerr << "subscribed" << std::endl; });
  mosquitto_message_callback_set(mosq, [](mosquitto*, void* self, const mosquitto_message* message) {
    auto& w = *static_cast<Watcher*>(self);
    const std::int64_t mono = clock::monotonicNs();
    const std::int64_t real = clock::realtimeNs() / 1'000'000;
    const std::string_view topic(message->topic);
    const std::string_view suffix = topic.substr(topic.rfind('/') + 1);
    const std::string_view text(static_cast<const char*>(message->payload),
                                static_cast<std::size_t>(message->payloadlen));
    std::string seq = "-", t = "-", samples = "-", binary = "-";
    if (!text.empty() && text.front() == '{') {
      const Json body = Json::parse(text, nullptr, false);
      if (body.is_object() && body.contains("seq")) {
        seq = std::to_string(body["seq"].get<std::uint64_t>());
        t = std::to_string(body["t"].get<std::int64_t>());
      }
      if (body.is_object() && suffix == "signals" && body.contains("samples")) {
        samples = std::to_string(body["samples"].size());
        binary = std::to_string(binaryBytes(body["samples"].size()));
      }
    }
    const std::lock_guard lock(w.mutex);
    std::fprintf(w.out, "%lld %lld %.*s %d %s %s %s %s\n", static_cast<long long>(real), static_cast<long long>(mono),
                 static_cast<int>(suffix.size()), suffix.data(), message->payloadlen, seq.c_str(), t.c_str(),
                 samples.c_str(), binary.c_str());
    std::fflush(w.out);
  });
  // the broker may not listen yet: retry for 10 s
  int rc = MOSQ_ERR_UNKNOWN;
  for (int attempt = 0; attempt < 200 && !g_stop; ++attempt) {
    if ((rc = mosquitto_connect(mosq, "127.0.0.1", port, 10)) == MOSQ_ERR_SUCCESS) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  if (rc != MOSQ_ERR_SUCCESS) fail(std::string("connect: ") + mosquitto_strerror(rc));
  if (mosquitto_loop_start(mosq) != MOSQ_ERR_SUCCESS) fail("mosquitto_loop_start");
  std::cerr << "watching\n";
  while (!g_stop) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  mosquitto_disconnect(mosq);
  mosquitto_loop_stop(mosq, true);
  mosquitto_destroy(mosq);
  std::fclose(watcher.out);
  return 0;
}

int fill(const std::string& folder, std::uint64_t records, std::size_t bytes) {
  auto queue = telemetry::DiskQueue::open({.folder = folder, .maxBytes = 4096ull << 20});
  if (!queue) fail(queue.error().toString());
  const std::int64_t t = clock::realtimeNs() / 1'000'000;
  std::vector<std::string> batch;
  std::uint64_t written = 0;
  while (written < records) {
    batch.clear();
    std::uint64_t sequence = queue->stats().nextSequence;
    for (std::size_t i = 0; i < FILL_BATCH && written + batch.size() < records; ++i) {
      std::string record =
          "bench\n{\"v\":1,\"seq\":" + std::to_string(sequence++) + ",\"t\":" + std::to_string(t) + ",\"pad\":\"";
      record.append(bytes > record.size() + 2 ? bytes - record.size() - 2 : 0, 'x');
      record += "\"}";
      batch.push_back(std::move(record));
    }
    std::vector<std::string_view> views(batch.begin(), batch.end());
    if (auto appended = queue->appendBatch(views); !appended) fail(appended.error().toString());
    written += batch.size();
  }
  const auto stats = queue->stats();
  std::cout << "filled " << written << " records, pending " << stats.pendingRecords << ", last seq "
            << stats.nextSequence - 1 << ", " << stats.diskBytes << " bytes on disk\n";
  return 0;
}

/// The binary prototype: encodes the samples of one tick into `out` (see the top of this file).
void encodeBinary(std::string& out, std::uint64_t sequence, std::int64_t unixMs,
                  const std::vector<std::tuple<std::uint16_t, std::int64_t, double>>& samples) {
  out.clear();
  const auto put = [&out](const auto value) {
    char bytes[sizeof(value)];
    std::memcpy(bytes, &value, sizeof(value));  // little endian: x86-64 and arm64 as built here
    out.append(bytes, sizeof(value));
  };
  put(std::uint8_t{1});
  put(std::uint8_t{1});
  put(sequence);
  put(unixMs);
  put(static_cast<std::uint16_t>(samples.size()));
  for (const auto& [index, sampleMs, value] : samples) {
    put(index);
    put(static_cast<std::uint16_t>(std::clamp<std::int64_t>(unixMs - sampleMs, 0, UINT16_MAX)));
    put(value);
  }
}

/// zlib's deflate (level 6) of `text`: its size (the bytes a compressed payload would take).
std::size_t deflatedBytes(std::string_view text, std::string& buffer) {
  uLongf size = compressBound(static_cast<uLong>(text.size()));
  buffer.resize(size);
  if (compress2(reinterpret_cast<Bytef*>(buffer.data()), &size, reinterpret_cast<const Bytef*>(text.data()),
                static_cast<uLong>(text.size()), 6) != Z_OK) {
    fail("zlib compress2 failed");
  }
  return size;
}

int encode(const std::string& vehiclePath, const std::string& telemetryPath, int seconds) {
  const Vehicle vehicle = loadVehicle(vehiclePath);
  auto settings = config::loadTelemetryConfig(telemetryPath);
  if (!settings) fail(settings.error().toString());
  const auto indices = configuredSignals(vehicle.catalog, *settings);
  auto table = signals::SignalTable::open(vehicle.catalog, "bench-encode");
  if (!table) fail(table.error().toString());
  auto engine = telemetry::Engine::create(*settings, vehicle.catalog, *table);
  if (!engine) fail(engine.error().message);

  constexpr int ROUNDS_PER_SECOND = 10;
  const std::int64_t start = clock::monotonicNs();
  const std::int64_t startUnixMs = clock::realtimeNs() / 1'000'000;
  std::int64_t sampleCpu = 0, jsonCpu = 0, binaryCpu = 0;
  std::uint64_t jsonBytes = 0, binaryBytesTotal = 0, samples = 0, jsonRecords = 0, sequence = 1;
  std::string binary, deflateBuffer;
  std::int64_t deflateCpu = 0;
  std::uint64_t jsonDeflated = 0, binaryDeflated = 0;
  std::vector<std::tuple<std::uint16_t, std::int64_t, double>> tickSamples;
  std::uint64_t step = 0;
  for (int second = 0; second < seconds; ++second) {
    tickSamples.clear();
    for (int round = 0; round < ROUNDS_PER_SECOND; ++round, ++step) {
      // simulated time: 100 ms per round, so every signal's 10 Hz limit lets each round through
      const std::int64_t now =
          start + (static_cast<std::int64_t>(second) * ROUNDS_PER_SECOND + round + 1) * (NS_PER_S / ROUNDS_PER_SECOND);
      for (std::size_t i = 0; i < indices.size(); ++i) {
        const double value = valueAt(vehicle.catalog[indices[i]], i, step);
        table->writeBus(indices[i], value, now, SOURCE, signals::Quality::Valid);
        tickSamples.emplace_back(static_cast<std::uint16_t>(i), startUnixMs + (now - start) / 1'000'000, value);
      }
      const std::int64_t before = threadCpuNs();
      engine->sample(now);
      sampleCpu += threadCpuNs() - before;
    }
    const std::int64_t tickNow = start + static_cast<std::int64_t>(second + 1) * NS_PER_S;
    const telemetry::TickInputs inputs{
        .clocks = {.monoNs = tickNow, .unixMs = startUnixMs + (tickNow - start) / 1'000'000},
        .queue = {},
        .drops = {},
        .link = {}};
    std::int64_t before = threadCpuNs();
    const std::vector<std::string> records = engine->tick(sequence, inputs);
    jsonCpu += threadCpuNs() - before;
    for (const std::string& record : records) {
      if (record.starts_with("signals\n")) {
        jsonBytes += record.size() - 8;
        ++jsonRecords;
        const std::int64_t deflateStart = threadCpuNs();
        jsonDeflated += deflatedBytes(std::string_view(record).substr(8), deflateBuffer);
        deflateCpu += threadCpuNs() - deflateStart;
      }
    }
    sequence += records.size();
    before = threadCpuNs();
    encodeBinary(binary, sequence, inputs.clocks.unixMs, tickSamples);
    binaryCpu += threadCpuNs() - before;
    binaryBytesTotal += binary.size();
    binaryDeflated += deflatedBytes(binary, deflateBuffer);
    samples += tickSamples.size();
  }
  const auto perSecond = [seconds](std::int64_t ns) { return static_cast<double>(ns) / seconds / 1000.0; };
  std::printf("encode seconds %d signals %zu samples_per_s %.0f\n", seconds, indices.size(),
              static_cast<double>(samples) / seconds);
  std::printf("encode json_deflated_bytes_per_s %.0f deflate_cpu_us_per_s %.1f binary_deflated_bytes_per_s %.0f\n",
              static_cast<double>(jsonDeflated) / seconds, perSecond(deflateCpu),
              static_cast<double>(binaryDeflated) / seconds);
  std::printf("encode sample_cpu_us_per_s %.1f json_tick_cpu_us_per_s %.1f binary_cpu_us_per_s %.1f\n",
              perSecond(sampleCpu), perSecond(jsonCpu), perSecond(binaryCpu));
  std::printf("encode json_bytes_per_s %.0f json_messages_per_s %.2f binary_bytes_per_s %.0f\n",
              static_cast<double>(jsonBytes) / seconds, static_cast<double>(jsonRecords) / seconds,
              static_cast<double>(binaryBytesTotal) / seconds);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"vcu-telemetry load benchmark helper (bench/telemetry/run_telemetry_bench.sh)"};
  app.require_subcommand(1);
  std::string vehiclePath, telemetryPath, outPath, folder;
  int count = 200, port = 1883, seconds = 60;
  double rateHz = 10, writeHz = 20;
  std::uint64_t records = 10000;
  std::size_t bytes = 300;
  auto* selectCmd = app.add_subcommand("select", "print 200 signals for telemetry.json");
  selectCmd->add_option("--config", vehiclePath)->required();
  selectCmd->add_option("--count", count);
  selectCmd->add_option("--rate-hz", rateHz);
  auto* writeCmd = app.add_subcommand("write", "write the configured signals until SIGTERM");
  writeCmd->add_option("--config", vehiclePath)->required();
  writeCmd->add_option("--telemetry", telemetryPath)->required();
  writeCmd->add_option("--write-hz", writeHz);
  auto* watchCmd = app.add_subcommand("watch", "log every message of openvcu/# until SIGTERM");
  watchCmd->add_option("--port", port);
  watchCmd->add_option("--out", outPath)->required();
  auto* fillCmd = app.add_subcommand("fill", "append a backlog to a queue folder");
  fillCmd->add_option("--queue", folder)->required();
  fillCmd->add_option("--records", records);
  fillCmd->add_option("--bytes", bytes);
  auto* encodeCmd = app.add_subcommand("encode", "JSON against the binary prototype, in process");
  encodeCmd->add_option("--config", vehiclePath)->required();
  encodeCmd->add_option("--telemetry", telemetryPath)->required();
  encodeCmd->add_option("--seconds", seconds);
  CLI11_PARSE(app, argc, argv);

  ::signal(SIGTERM, onSignal);
  ::signal(SIGINT, onSignal);
  if (*selectCmd) return select(vehiclePath, count, rateHz);
  if (*writeCmd) return write(vehiclePath, telemetryPath, writeHz);
  if (*watchCmd) return watch(port, outPath);
  if (*fillCmd) return fill(folder, records, bytes);
  return encode(vehiclePath, telemetryPath, seconds);
}
