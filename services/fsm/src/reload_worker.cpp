#include "reload_worker.hpp"

namespace openvcu::fsm {

ReloadWorker::ReloadWorker(Load load, std::function<void()> finished)
    : m_load(std::move(load)), m_finished(std::move(finished)), m_thread([this] { run(); }) {}

ReloadWorker::~ReloadWorker() {
  {
    std::lock_guard lock(m_mutex);
    m_stop = true;
  }
  m_wake.notify_all();
  m_thread.join();
}

void ReloadWorker::start(std::string path) {
  {
    std::lock_guard lock(m_mutex);
    m_job = std::move(path);
  }
  m_wake.notify_one();
}

std::optional<Result<Machine>> ReloadWorker::take() {
  std::lock_guard lock(m_mutex);
  return std::exchange(m_result, std::nullopt);
}

void ReloadWorker::run() {
  std::unique_lock lock(m_mutex);
  for (;;) {
    m_wake.wait(lock, [this] { return m_stop || m_job.has_value(); });
    if (m_stop) return;
    const std::string path = std::exchange(m_job, std::nullopt).value();
    lock.unlock();
    Result<Machine> loaded = m_load(path);
    lock.lock();
    m_result = std::move(loaded);
    lock.unlock();
    m_finished();
    lock.lock();
  }
}

}  // namespace openvcu::fsm
