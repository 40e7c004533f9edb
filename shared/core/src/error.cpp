#include "openvcu/core/error.hpp"

namespace openvcu {

std::string Location::toString() const {
  std::string out = file;
  if (line > 0) {
    out += ':' + std::to_string(line);
    if (column > 0) out += ':' + std::to_string(column);
  }
  if (!jsonPath.empty()) {
    if (!out.empty()) out += ": ";
    out += jsonPath;
  }
  return out;
}

std::string Error::toString() const {
  std::string out = location.toString();
  if (!out.empty()) out += ": ";
  if (severity == Severity::Warning) out += "warning: ";
  if (severity == Severity::Note) out += "note: ";
  out += message;
  return out;
}

}  // namespace openvcu
