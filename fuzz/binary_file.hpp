// What the harnesses of STAC's checksummed binary files share (dataset_file_fuzz,
// induction_state_fuzz): header fields forced to what the reader wants, and the checksum made
// right again, so that the fuzzer explores the body instead of guessing hashes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <vector>

#include "perception/classification/grid_classifier.hpp"

namespace stac::fuzz {

// `v`'s bytes written over b[at, at + sizeof v).
template <class T>
void put_at(std::vector<std::uint8_t>& b, std::size_t at, T v) {
  std::memcpy(b.data() + at, &v, sizeof v);
}

// The last 8 bytes of `b` made the checksum (FNV-1a 64) of the rest, as STAC's binary files end.
inline void recompute_checksum(std::vector<std::uint8_t>& b) {
  put_at(b, b.size() - 8,
         classification::fnv1a64(std::span<const std::uint8_t>(b).first(b.size() - 8)));
}

}  // namespace stac::fuzz
