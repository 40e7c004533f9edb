#pragma once
// The thread that reads and checks reload files (docs/fsm.md "Reload"), so that neither the
// command path nor the engine ever waits for a file system or a 4 MiB parse.
//
//   fsm::ReloadWorker worker([&](const std::string& path) { return loadReloadMachine(...); },
//                            [&] { wake the loop thread });
//   worker.start("/etc/openvcu/hhea/fsm-v2.json");   // returns at once
//   ... `finished` was called (on the worker thread) ...
//   if (auto maybeLoaded = worker.take()) use(*maybeLoaded);   // on the caller's thread
//
// One job at a time: the caller starts the next one only after it took the result.

#include <condition_variable>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "openvcu/core/result.hpp"
#include "openvcu/fsm/machine.hpp"

namespace openvcu::fsm {

/// @note thread-safe: start() and take() from one thread (the service's loop), `load` and
///       `finished` run on the worker thread. The destructor waits for a job in progress
///       (a bounded read and check of a regular file).
class ReloadWorker {
 public:
  using Load = std::function<Result<Machine>(const std::string& path)>;

  ReloadWorker(Load load, std::function<void()> finished);
  ~ReloadWorker();
  ReloadWorker(const ReloadWorker&) = delete;
  ReloadWorker& operator=(const ReloadWorker&) = delete;

  /// Hands `path` to the worker thread. Precondition: no job running or untaken.
  void start(std::string path);
  /// The finished job's result, once.
  [[nodiscard]] std::optional<Result<Machine>> take();

 private:
  void run();

  Load m_load;
  std::function<void()> m_finished;
  std::mutex m_mutex;
  std::condition_variable m_wake;
  bool m_stop{};
  std::optional<std::string> m_job;
  std::optional<Result<Machine>> m_result;
  std::thread m_thread;  ///< last: started once everything it uses exists
};

}  // namespace openvcu::fsm
