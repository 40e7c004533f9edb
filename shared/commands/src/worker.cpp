#include "openvcu/commands/worker.hpp"

#include <pthread.h>

namespace openvcu::commands {

Worker::Worker(std::string name, std::size_t capacity) : m_name(std::move(name)), m_capacity(capacity) {
  m_thread = std::thread([this] { run(); });
  pthread_setname_np(m_thread.native_handle(), m_name.substr(0, 15).c_str());
}

Worker::~Worker() {
  {
    const std::lock_guard lock(m_mutex);
    m_stopping = true;
    m_jobs.clear();
  }
  m_wake.notify_all();
  m_thread.join();
}

bool Worker::submit(std::function<void()> job) {
  {
    const std::lock_guard lock(m_mutex);
    if (m_stopping || m_jobs.size() >= m_capacity) return false;
    m_jobs.push_back(std::move(job));
  }
  m_wake.notify_one();
  return true;
}

void Worker::run() {
  for (;;) {
    std::function<void()> job;
    {
      std::unique_lock lock(m_mutex);
      m_wake.wait(lock, [this] { return m_stopping || !m_jobs.empty(); });
      if (m_stopping) return;
      job = std::move(m_jobs.front());
      m_jobs.pop_front();
    }
    job();
  }
}

}  // namespace openvcu::commands
