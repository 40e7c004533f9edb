#include "openvcu/config/faults.hpp"

namespace openvcu::faults {

namespace {

std::string join(std::string_view prefix, std::string_view service) {
  std::string name;
  name.reserve(prefix.size() + service.size());
  name.append(prefix);
  name.append(service);
  return name;
}

}  // namespace

std::string serviceSilent(std::string_view service) {
  return join(SERVICE_SILENT_PREFIX, service);
}

std::string writerLost(std::string_view writer) {
  return join(WRITER_LOST_PREFIX, writer);
}

std::optional<ServiceFault> parseServiceFault(std::string_view name) noexcept {
  ServiceFault fault;
  if (name.starts_with(SERVICE_SILENT_PREFIX)) {
    fault.kind = ServiceFaultKind::ServiceSilent;
    fault.service = name.substr(SERVICE_SILENT_PREFIX.size());
  } else if (name.starts_with(WRITER_LOST_PREFIX)) {
    fault.kind = ServiceFaultKind::WriterLost;
    fault.service = name.substr(WRITER_LOST_PREFIX.size());
  } else {
    return std::nullopt;
  }
  if (fault.service.empty()) return std::nullopt;
  fault.entry = config::findService(fault.service);
  return fault;
}

bool namesKnownService(std::string_view name) noexcept {
  const auto maybeFault = parseServiceFault(name);
  return maybeFault && maybeFault->entry != nullptr;
}

}  // namespace openvcu::faults
