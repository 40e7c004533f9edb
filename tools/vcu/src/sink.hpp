#pragma once
// Where a command writes: the process's stdout/stderr (FileSink) or a string in tests
// (StringSink). Commands write whole lines or large chunks, so one virtual call per
// write costs nothing next to the formatting.
//
//   FileSink out(stdout);
//   out.write("vehicle.dbc: 42 messages\n");
//   if (!out.flush()) { ... out.errorMessage() ... }
//
// @note not thread-safe; one command writes to a sink at a time.

#include <cstdio>
#include <string>
#include <string_view>

namespace openvcu::cli {

class Sink {
 public:
  Sink() = default;
  Sink(const Sink&) = delete;
  Sink& operator=(const Sink&) = delete;
  virtual ~Sink() = default;

  /// Appends `text`. After a failure further writes are dropped and failed() stays true.
  virtual void write(std::string_view text) = 0;
  /// Pushes buffered bytes to the destination; false once anything failed to arrive.
  virtual bool flush() = 0;
  /// true once a write or flush failed.
  [[nodiscard]] virtual bool failed() const noexcept = 0;
  /// The OS reason of the first failure ("No space left on device"), empty when none.
  [[nodiscard]] virtual std::string errorMessage() const = 0;
};

/// Writes to a C stdio stream it does not own.
class FileSink final : public Sink {
 public:
  explicit FileSink(std::FILE* file) noexcept : m_file(file) {}
  void write(std::string_view text) override;
  bool flush() override;
  [[nodiscard]] bool failed() const noexcept override { return m_failed; }
  [[nodiscard]] std::string errorMessage() const override;

 private:
  std::FILE* m_file;
  int m_errno{};  ///< errno of the first failed write or flush, 0 while none failed
  bool m_failed{};
};

/// Collects everything in memory (tests, and anything that post-processes output).
class StringSink final : public Sink {
 public:
  void write(std::string_view text) override { m_text.append(text); }
  bool flush() override { return true; }
  [[nodiscard]] bool failed() const noexcept override { return false; }
  [[nodiscard]] std::string errorMessage() const override { return {}; }
  [[nodiscard]] const std::string& text() const noexcept { return m_text; }

 private:
  std::string m_text;
};

/// The two outputs every command gets: results on `out`, diagnostics on `err`.
struct Streams {
  Sink& out;
  Sink& err;
};

}  // namespace openvcu::cli
