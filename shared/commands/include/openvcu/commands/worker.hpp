#pragma once
// A thread for work that blocks (a command waiting for its owner's answer; in vcu-web also a
// password hash, an archive, a report), with a bounded queue: the caller's loop thread never
// waits, and a burst beyond the queue is refused at once (vcu-web: 503, vcu-telemetry: a
// refusal answered) instead of piling up.
//
//   commands::Worker worker("web-commands", 16);
//   if (!worker.submit([=] { respond(sendCommand(instance, request, timeout)); })) respond(busy());

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <functional>
#include <mutex>
#include <string>
#include <thread>

namespace openvcu::commands {

/// @note thread-safe: submit() from any thread; jobs run one at a time on the worker's thread.
class Worker {
 public:
  Worker(std::string name, std::size_t capacity);
  ~Worker();  ///< runs no job that has not started; waits for the running one
  Worker(const Worker&) = delete;
  Worker& operator=(const Worker&) = delete;

  /// Queues `job`; false when `capacity` jobs are already waiting.
  bool submit(std::function<void()> job);

 private:
  void run();
  std::string m_name;
  std::size_t m_capacity;
  std::mutex m_mutex;
  std::condition_variable m_wake;
  std::deque<std::function<void()>> m_jobs;
  bool m_stopping{false};
  std::thread m_thread;
};

}  // namespace openvcu::commands
