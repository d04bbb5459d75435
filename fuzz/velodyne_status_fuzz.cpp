// The HDL-64E status cycle (S2.1/S3 packet trailers: a status type and value byte per packet):
// the first byte picks the model, the rest are (type, value) pairs into a StatusDecoder, which
// rebuilds the unit's status, parameters and calibration dump; an accepted dump is then read as
// a calibration.
#include <cstddef>
#include <cstdint>

#include "drivers/velodyne/status.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using stac::velodyne::Model;
  if (size == 0) return 0;
  const Model models[] = {Model::kS2, Model::kS2_1, Model::kS3};
  stac::velodyne::StatusDecoder decoder(models[data[0] % 3]);
  for (std::size_t at = 1; at + 1 < size; at += 2) decoder.add(data[at], data[at + 1]);
  if (decoder.has_calibration()) (void)decoder.calibration();
  (void)stac::velodyne::utc_time_ns(decoder.sensor(), 1'234'567'890u);
  return 0;
}
