#pragma once
// Helpers for the signal table tests: catalogs from key lists and per-test instance names
// that never collide (the pid is in the name, so parallel ctest runs and other users of
// this machine's /dev/shm are safe) and are removed when the test ends.

#include <doctest/doctest.h>
#include <unistd.h>

#include <atomic>
#include <string>
#include <vector>

#include "openvcu/signals/catalog.hpp"
#include "openvcu/signals/table.hpp"

namespace openvcu::signals::testing {

inline Catalog makeCatalog(const std::vector<std::string>& keys, SignalKind kind = SignalKind::Bus) {
  std::vector<SignalInfo> infos;
  for (const std::string& key : keys) {
    SignalInfo info;
    info.key = key;
    info.kind = kind;
    infos.push_back(std::move(info));
  }
  auto catalogResult = Catalog::create(std::move(infos));
  REQUIRE(catalogResult.ok());
  return std::move(catalogResult).value();
}

/// A catalog of `count` signals "test.signal<i>".
inline Catalog makeNumberedCatalog(std::size_t count) {
  std::vector<std::string> keys;
  for (std::size_t i = 0; i < count; ++i) keys.push_back("test.signal" + std::to_string(i));
  return makeCatalog(keys);
}

/// "t-<purpose>-<pid>-<n>"; the table and its lock file are removed on destruction.
class ScopedInstance {
 public:
  explicit ScopedInstance(const std::string& purpose) {
    static std::atomic<int> counter{0};
    m_name = "t-" + purpose + "-" + std::to_string(getpid()) + "-" + std::to_string(counter.fetch_add(1));
    (void)SignalTable::remove(m_name);
  }
  ScopedInstance(const ScopedInstance&) = delete;
  ScopedInstance& operator=(const ScopedInstance&) = delete;
  ~ScopedInstance() { (void)SignalTable::remove(m_name); }

  [[nodiscard]] const std::string& name() const { return m_name; }

 private:
  std::string m_name;
};

}  // namespace openvcu::signals::testing
