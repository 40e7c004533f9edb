#include "diagnostics.hpp"

namespace openvcu::cli {

std::string formatDiagnostic(const Error& error) {
  std::string out = error.location.toString();
  if (out.empty()) out = "vcu";
  switch (error.severity) {
    case Severity::Error:
      out += ": error: ";
      break;
    case Severity::Warning:
      out += ": warning: ";
      break;
    case Severity::Note:
      out += ": note: ";
      break;
  }
  out += escapeControlCharacters(error.message);  // a NUL or newline from a file stays visible, one line
  return out;
}

void report(Sink& err, const Error& error) {
  std::string line = formatDiagnostic(error);
  line += '\n';
  err.write(line);
}

void reportError(Sink& err, std::string_view message) {
  report(err, Error{std::string(message)});
}

}  // namespace openvcu::cli
