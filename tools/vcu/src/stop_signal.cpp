#include "stop_signal.hpp"

namespace openvcu::cli {
namespace {

volatile std::sig_atomic_t g_stop = 0;

void onStopSignal(int /*signal*/) { g_stop = 1; }

}  // namespace

StopSignalScope::StopSignalScope() {
  g_stop = 0;
  struct sigaction action {};
  action.sa_handler = onStopSignal;
  sigemptyset(&action.sa_mask);
  ::sigaction(SIGINT, &action, &m_previousInt);
  ::sigaction(SIGTERM, &action, &m_previousTerm);
}

StopSignalScope::~StopSignalScope() {
  ::sigaction(SIGINT, &m_previousInt, nullptr);
  ::sigaction(SIGTERM, &m_previousTerm, nullptr);
}

bool stopRequested() noexcept { return g_stop != 0; }

}  // namespace openvcu::cli
