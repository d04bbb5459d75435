// The Applanix $GRP stream parser: the input fed in chunks whose sizes the input's bytes choose
// (a TCP stream cut anywhere), every message taken, then the end of the stream.
#include <algorithm>
#include <cstddef>
#include <cstdint>

#include "drivers/applanix/stream_parser.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  stac::applanix::StreamParser parser;
  stac::applanix::Parsed m;
  std::size_t at = 0;
  while (at < size) {
    const std::size_t n = std::min<std::size_t>(1 + data[at] * 4u, size - at);
    parser.feed({data + at, n});
    while (parser.next(m)) {
    }
    at += n;
  }
  parser.end_of_stream();
  while (parser.next(m)) {
  }
  return 0;
}
