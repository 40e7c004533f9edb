#pragma once
// A thread for vcu-web's work that blocks (a command waiting for its answer, a password hash,
// an archive, a report), with a bounded queue: the io thread never waits, and a burst of
// requests beyond the queue is refused (503) instead of piling up.
//
//   web::Worker commands("web-commands", 16);
//   if (!commands.submit([=] { respond(sendCommand(request)); })) respond(Response::error(503, "busy"));

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <functional>
#include <mutex>
#include <string>
#include <thread>

namespace openvcu::web {

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

}  // namespace openvcu::web
