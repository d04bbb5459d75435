// The vehicle bus's text formats: the input as a DBC file, and each of its lines as a candump
// log line.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "drivers/can/candump.hpp"
#include "drivers/can/dbc.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  (void)stac::can::parse_dbc(text, "fuzz.dbc");
  stac::can::Frame frame{};
  for (std::size_t start = 0; start <= text.size();) {
    const std::size_t end = std::min(text.find('\n', start), text.size());
    (void)stac::can::parse_candump_line(text.substr(start, end - start), frame);
    start = end + 1;
  }
  return 0;
}
