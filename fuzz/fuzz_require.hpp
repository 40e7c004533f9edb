#pragma once
// require(): a broken invariant is a finding; abort so that libFuzzer (and ctest) report it.

#include <cstdlib>

namespace openvcu::fuzz {

inline void require(bool condition) {
  if (!condition) std::abort();
}

}  // namespace openvcu::fuzz
