#include "sink.hpp"

#include <cerrno>
#include <cstring>

namespace openvcu::cli {

void FileSink::write(std::string_view text) {
  if (m_failed || text.empty()) return;
  errno = 0;
  if (std::fwrite(text.data(), 1, text.size(), m_file) != text.size()) {
    m_failed = true;
    m_errno = errno;
  }
}

bool FileSink::flush() {
  if (m_failed) return false;
  errno = 0;
  if (std::fflush(m_file) != 0) {
    m_failed = true;
    m_errno = errno;
  }
  return !m_failed;
}

std::string FileSink::errorMessage() const {
  if (!m_failed) return {};
  return m_errno != 0 ? std::strerror(m_errno) : "write error";
}

}  // namespace openvcu::cli
