// Velodyne data packets and scan assembly: the input cut into datagrams (each a 2-byte length,
// then that many bytes), stamped 100 us apart, into a ScanStream with the real S2.1 calibration
// and the shipped configuration; every complete scan taken and released.
#include <cstddef>
#include <cstdint>
#include <optional>

#include "drivers/velodyne/calibration.hpp"
#include "drivers/velodyne/scan_stream.hpp"
#include "fuzz_common.hpp"
#include "settings/settings.hpp"

namespace {
std::optional<stac::velodyne::ScanStream> g_stream;
}

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  auto vs = stac::settings::load_velodyne_settings(stac::fuzz::source_file("config/stac.yaml"));
  auto calibration = stac::velodyne::load_calibration(
      stac::fuzz::source_file("../shared/data/velodyne/calib/rosdrivers_64e_s2.1-sztaki.yaml"));
  if (!vs || !calibration) __builtin_trap();  // the harness cannot start: say so loudly
  static const stac::velodyne::Calibration kept = *calibration;
  g_stream.emplace(kept, vs->assembler, 4);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::int64_t stamp = 1'700'000'000'000'000'000;
  std::size_t at = 0;
  while (at + 2 <= size) {
    const std::size_t n = std::min<std::size_t>(data[at] | data[at + 1] << 8, size - at - 2);
    at += 2;
    (void)g_stream->add_packet({data + at, n}, stamp);
    at += n;
    stamp += 100'000;
    while (g_stream->take() != nullptr) g_stream->release();
  }
  (void)g_stream->finish();
  while (g_stream->take() != nullptr) g_stream->release();
  return 0;
}
