#include <doctest/doctest.h>

#include <string>

#include "openvcu/config/faults.hpp"
#include "openvcu/config/services.hpp"

using namespace openvcu;

TEST_CASE("a silent service's fault is service_silent.<service>") {
  CHECK(faults::serviceSilent("fsm") == "service_silent.fsm");
  CHECK(faults::serviceSilent("can-rx") == "service_silent.can-rx");
}

TEST_CASE("a lost writer's fault is writer_lost.<writer>") {
  CHECK(faults::writerLost("fsm") == "writer_lost.fsm");
  CHECK(faults::writerLost("hmi") == "writer_lost.hmi");
}

TEST_CASE("the built names start with the prefixes parsers match on") {
  CHECK(faults::serviceSilent("gpio").starts_with(faults::SERVICE_SILENT_PREFIX));
  CHECK(faults::writerLost("gpio").starts_with(faults::WRITER_LOST_PREFIX));
}

TEST_CASE("every service of config::SERVICES has fault names that parse back to its entry") {
  for (const config::ServiceEntry& service : config::SERVICES) {
    CAPTURE(service.name);
    const std::string silent = faults::serviceSilent(service.name);
    const auto maybeSilent = faults::parseServiceFault(silent);
    REQUIRE(maybeSilent.has_value());
    CHECK(maybeSilent->kind == faults::ServiceFaultKind::ServiceSilent);
    CHECK(maybeSilent->service == service.name);
    CHECK(maybeSilent->entry == &service);

    const std::string lost = faults::writerLost(service.name);
    const auto maybeLost = faults::parseServiceFault(lost);
    REQUIRE(maybeLost.has_value());
    CHECK(maybeLost->kind == faults::ServiceFaultKind::WriterLost);
    CHECK(maybeLost->service == service.name);
    CHECK(maybeLost->entry == &service);
  }
}

TEST_CASE("a fault name for a service outside config::SERVICES parses without an entry") {
  const auto sut = faults::parseServiceFault("service_silent.fixture");
  REQUIRE(sut.has_value());
  CHECK(sut->service == "fixture");
  CHECK(sut->entry == nullptr);
  CHECK_FALSE(faults::namesKnownService("service_silent.fixture"));
  CHECK_FALSE(faults::namesKnownService("writer_lost.brake"));
  CHECK(faults::namesKnownService("writer_lost.fsm"));
}

TEST_CASE("other fault names and a prefix without a service do not parse") {
  CHECK_FALSE(faults::parseServiceFault("service_silent.").has_value());
  CHECK_FALSE(faults::parseServiceFault("writer_lost.").has_value());
  CHECK_FALSE(faults::parseServiceFault("service_silent").has_value());
  CHECK_FALSE(faults::parseServiceFault("rx_timeout.vehicle.BMS_1").has_value());
  CHECK_FALSE(faults::parseServiceFault("hv_lost").has_value());
  CHECK_FALSE(faults::parseServiceFault("").has_value());
  CHECK_FALSE(faults::namesKnownService("hv_lost"));
}
