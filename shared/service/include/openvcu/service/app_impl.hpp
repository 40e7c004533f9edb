#pragma once
// The members of service::App (app.hpp), included by the one .cpp that defines the Impl and
// instantiates `template class service::App<Impl>;`.

#include <utility>

#include "openvcu/service/app.hpp"

namespace openvcu::service {

template <typename Impl>
Result<std::unique_ptr<App<Impl>>> App<Impl>::create(Service& runtime) {
  auto impl = std::make_unique<Impl>(runtime);
  if (Status opened = impl->open(); !opened) return opened.error();
  return std::unique_ptr<App>(new App(std::move(impl)));
}

template <typename Impl>
App<Impl>::App(std::unique_ptr<Impl> impl) noexcept : m_impl(std::move(impl)) {}

template <typename Impl>
App<Impl>::~App() = default;

}  // namespace openvcu::service
