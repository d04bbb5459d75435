// candump log files as `stac candump` and the simulator's readers open them: the input written
// to a file and read to its end (or its first malformed line) with CandumpReader.
#include <cstddef>
#include <cstdint>
#include <filesystem>

#include "drivers/can/candump.hpp"
#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::filesystem::path file = stac::fuzz::as_file(data, size, ".log");
  auto reader = stac::can::CandumpReader::open(file);
  if (!reader) return 0;
  stac::can::Frame frame{};
  for (std::size_t frames = 0; frames <= size; ++frames) {  // a line per frame at least
    auto more = reader->next(frame);
    if (!more || !*more) return 0;
    if (frame.dlc > 8) __builtin_trap();
  }
  __builtin_trap();  // more frames than bytes: the reader does not advance
}
