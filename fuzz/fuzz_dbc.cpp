// libFuzzer target: arbitrary bytes through the DBC parser, the writer, a re-parse and
// the codec. Invariants checked: no crash/hang/UB (sanitizers), write() of a clean parse
// re-parses without errors to an equal model, decoding any payload stays in bounds.
#include "openvcu/dbc/codec.hpp"
#include "openvcu/dbc/parser.hpp"

#include <cstdint>
#include <cstdlib>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace openvcu::dbc;
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  ParseOutput parsed = parse(text, "fuzz.dbc");
  if (!parsed.hasErrors()) {
    const ParseOutput again = parse(write(parsed.database), "rewritten.dbc");
    if (again.hasErrors() || !(again.database == parsed.database)) std::abort();
  }
  std::uint8_t payload[64];
  for (std::size_t i = 0; i < sizeof payload; ++i) payload[i] = static_cast<std::uint8_t>(i * 37u + size);
  double sink = 0;
  for (const Message& message : parsed.database.messages) {
    const MessageCodec codec = MessageCodec::compile(parsed.database, message);
    for (std::size_t length : {std::size_t{0}, std::size_t{3}, std::size_t{8}, std::size_t{64}}) {
      codec.decode(std::span<const std::uint8_t>(payload, length),
                   [&](std::uint32_t, const DecodedValue& value) { sink += value.physical; });
    }
  }
  static volatile double keep;
  keep = sink;
  return 0;
}
