// The tracks and truth files' lines (JSON, one scan a line), as `stac eval` reads them.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "evaluation/tracks_jsonl.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view line(reinterpret_cast<const char*>(data), size);
  (void)stac::evaluation::parse_tracks_line(line);
  (void)stac::evaluation::parse_truth_line(line);
  return 0;
}
