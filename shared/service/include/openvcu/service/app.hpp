#pragma once
// The handle a service's main holds: it owns the service's implementation (`Impl`, defined
// in the service's app .cpp and built as `Impl(service::Service&)` then `Status open()`),
// so that main.cpp and tests see no more than this header.
//
//   // can_rx_app.hpp
//   struct CanRxAppImpl;
//   using CanRxApp = service::App<CanRxAppImpl>;
//   extern template class service::App<CanRxAppImpl>;
//   // can_rx_app.cpp, after CanRxAppImpl: #include "openvcu/service/app_impl.hpp"
//   template class service::App<CanRxAppImpl>;

#include <memory>

#include "openvcu/core/result.hpp"
#include "openvcu/service/service.hpp"

namespace openvcu::service {

/// @note restricted thread-safe: lives on the service's loop thread.
template <typename Impl>
class App {
 public:
  /// Builds the implementation and opens it (configuration, links, streams, registration
  /// with the loop); its error is the service's start-up error.
  static Result<std::unique_ptr<App>> create(Service& runtime);
  ~App();
  App(const App&) = delete;
  App& operator=(const App&) = delete;

 private:
  explicit App(std::unique_ptr<Impl> impl) noexcept;
  std::unique_ptr<Impl> m_impl;
};

}  // namespace openvcu::service
