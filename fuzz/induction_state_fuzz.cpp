// The state of `stac induct` and `stac label` (DIR/state.bin, formats/induction_state.hpp), and a
// line of DIR/labels.jsonl as both read it. Half the inputs are parsed as they come (magic,
// version, checksum); the other half get this build's magic, a version it reads and its
// descriptor dimensions written into their header and their checksum recomputed, so that the
// fuzzer explores the body (classes, settings, sources, labels, groups, the model), where a count
// past the bytes left once allocated 1.6 GB before the state was refused (issue 47).
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "formats/induction_state.hpp"
#include "fuzz/binary_file.hpp"
#include "perception/classification/holistic.hpp"
#include "perception/classification/model.hpp"
#include "perception/descriptors/descriptors.hpp"

namespace {

constexpr std::size_t kHeaderBytes = 8 + 3 * 4;

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace stac;
  const std::string text(reinterpret_cast<const char*>(data), size);
  (void)formats::is_answer_line(text);
  (void)formats::is_json_line(text);
  if (size == 0 || (data[0] & 1) == 0) {
    (void)formats::parse_induction_state({data, size}, "fuzz");
    return 0;
  }
  std::vector<std::uint8_t> b(data + 1, data + size);
  if (b.size() < kHeaderBytes + 8) return 0;
  const char magic[8] = {'S', 'T', 'A', 'C', 'I', 'N', 'D', '\0'};  // state.bin's
  std::memcpy(b.data(), magic, sizeof magic);
  std::uint32_t version = 0;
  std::memcpy(&version, b.data() + 8, 4);
  fuzz::put_at(b, 8, static_cast<std::uint32_t>(1 + version % formats::kInductionStateVersion));
  fuzz::put_at(b, 12, static_cast<std::uint32_t>(descriptors::kDimensions));
  fuzz::put_at(b, 16, static_cast<std::uint32_t>(classification::kHolisticDimensions));
  fuzz::recompute_checksum(b);
  (void)formats::parse_induction_state(b, "fuzz");
  return 0;
}
