// Track classifier model bytes (what a model file holds), as every reader of a model takes them.
#include <cstddef>
#include <cstdint>

#include "perception/classification/model.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  (void)stac::classification::deserialize({data, size});
  return 0;
}
