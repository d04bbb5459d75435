// candump log files as `stac candump` and the simulator's readers read them: the input as a
// log's text (CandumpReader::from_text, the same reader without a file per input), read to its
// end or its first malformed line.
#include <cstddef>
#include <cstdint>
#include <string>

#include "drivers/can/candump.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  auto reader = stac::can::CandumpReader::from_text(
      std::string(reinterpret_cast<const char*>(data), size), "fuzz.log");
  stac::can::Frame frame{};
  for (std::size_t frames = 0; frames <= size; ++frames) {  // a line per frame at least
    auto more = reader.next(frame);
    if (!more || !*more) return 0;
    if (frame.dlc > 8) __builtin_trap();
  }
  __builtin_trap();  // more frames than bytes: the reader does not advance
}
