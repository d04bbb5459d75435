// Dataset files (tracks.bin of `stac dataset`, read by train, eval --classes, induct and label).
// Half the inputs are parsed as they come (the header's checks: magic, version, checksum,
// layout); the other half get this build's magic, descriptor dimensions and layout hashes written
// into their header and their checksum recomputed, so that the fuzzer explores the body (class
// list, sources, tracks, descriptors, paths, snapshots) instead of guessing 16 bytes of hash.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "formats/dataset_file.hpp"
#include "fuzz/binary_file.hpp"
#include "perception/classification/holistic.hpp"
#include "perception/classification/model.hpp"
#include "perception/descriptors/descriptors.hpp"

namespace {

constexpr std::size_t kHeaderBytes = 8 + 4 * 4 + 8 * 3;

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace stac;
  if (size == 0 || (data[0] & 1) == 0) {
    (void)formats::parse_dataset({data, size}, "fuzz");
    return 0;
  }
  std::vector<std::uint8_t> b(data + 1, data + size);
  if (b.size() < kHeaderBytes + 8) return 0;
  std::memcpy(b.data(), "STACDSET", 8);
  std::uint32_t version = 0;
  std::memcpy(&version, b.data() + 8, 4);
  if (version < 2 || version > formats::kDatasetFormatVersion)
    fuzz::put_at(b, 8, formats::kDatasetFormatVersion);
  fuzz::put_at(b, 12, static_cast<std::uint32_t>(descriptors::kDimensions));
  fuzz::put_at(b, 16, static_cast<std::uint32_t>(classification::kHolisticDimensions));
  fuzz::put_at(b, 24, classification::layout_hash(classification::segment_layout()));
  fuzz::put_at(b, 32, classification::layout_hash(classification::holistic_layout()));
  fuzz::recompute_checksum(b);
  (void)formats::parse_dataset(b, "fuzz");
  return 0;
}
