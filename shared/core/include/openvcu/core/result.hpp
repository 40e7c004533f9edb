#pragma once
// Result<T>: a value or an Error, the expected-style return of every fallible
// start-up and loading function (C++20 has no std::expected yet).
//
//   Result<Database> loadResult = loadDbc(path);
//   if (!loadResult) { std::cerr << loadResult.error().toString() << '\n'; return 1; }
//   const Database& db = *loadResult;
//
// @note not thread-safe; plain value type.

#include "openvcu/core/error.hpp"

#include <cassert>
#include <utility>
#include <variant>

namespace openvcu {

template <typename T>
class [[nodiscard]] Result {
 public:
  Result(T value) : m_state(std::in_place_index<0>, std::move(value)) {}      // NOLINT
  Result(Error error) : m_state(std::in_place_index<1>, std::move(error)) {}  // NOLINT

  [[nodiscard]] bool ok() const noexcept { return m_state.index() == 0; }
  explicit operator bool() const noexcept { return ok(); }

  T& value() & { assert(ok()); return std::get<0>(m_state); }
  const T& value() const& { assert(ok()); return std::get<0>(m_state); }
  T&& value() && { assert(ok()); return std::get<0>(std::move(m_state)); }
  T& operator*() & { return value(); }
  const T& operator*() const& { return value(); }
  T&& operator*() && { return std::move(*this).value(); }
  T* operator->() { return &value(); }
  const T* operator->() const { return &value(); }

  const Error& error() const { assert(!ok()); return std::get<1>(m_state); }

 private:
  std::variant<T, Error> m_state;
};

/// Result without a value: success or an Error.
template <>
class [[nodiscard]] Result<void> {
 public:
  Result() = default;
  Result(Error error) : m_error(std::move(error)), m_ok(false) {}  // NOLINT

  [[nodiscard]] bool ok() const noexcept { return m_ok; }
  explicit operator bool() const noexcept { return m_ok; }
  const Error& error() const { assert(!m_ok); return m_error; }

 private:
  Error m_error{};
  bool m_ok{true};
};

using Status = Result<void>;

}  // namespace openvcu
