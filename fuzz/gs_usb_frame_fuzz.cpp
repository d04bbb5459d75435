// The gs_usb (candleLight) USB-CAN adapter's bulk-IN transfers: the first byte says whether the
// mode has hardware timestamps (24-byte frames) or not (20), the rest is cut into transfers (a
// 1-byte length, then that many bytes), each decoded; and the adapter's bit-timing limits
// (BT_CONST, 40 bytes) from the head, for the divider search at the usual bit rates.
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "drivers/can/gs_usb.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  namespace gs = stac::can::gs_usb;
  if (size == 0) return 0;
  const bool hw_timestamp = (data[0] & 1) != 0;
  if (size >= 1 + sizeof(gs::BtConst)) {
    gs::BtConst limits{};
    std::memcpy(&limits, data + 1, sizeof(limits));
    gs::BitTiming timing{};
    for (const std::uint32_t bps : {125'000u, 250'000u, 500'000u, 1'000'000u})
      (void)gs::compute_bit_timing(limits, bps, timing);
  }
  std::size_t at = 1;
  while (at < size) {
    const std::size_t n = std::min<std::size_t>(data[at], size - at - 1);
    ++at;
    const gs::DecodedFrame f = gs::decode_frame({data + at, n}, hw_timestamp);
    if (f.status == gs::DecodeStatus::kReceived && f.frame.dlc > 8) __builtin_trap();
    at += n;
  }
  return 0;
}
