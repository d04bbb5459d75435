#include "drivers/can/gs_usb.hpp"

#include <cmath>
#include <cstddef>
#include <cstring>

namespace stac::can::gs_usb {
namespace {

std::uint32_t load_u32(const std::uint8_t* p) noexcept {
  return static_cast<std::uint32_t>(p[0]) | static_cast<std::uint32_t>(p[1]) << 8 |
         static_cast<std::uint32_t>(p[2]) << 16 | static_cast<std::uint32_t>(p[3]) << 24;
}
void store_u32(std::uint32_t v, std::uint8_t* p) noexcept {
  for (int i = 0; i < 4; ++i, v >>= 8) p[i] = static_cast<std::uint8_t>(v);
}

}  // namespace

DecodedFrame decode_frame(std::span<const std::uint8_t> bytes, bool hw_timestamp) noexcept {
  DecodedFrame d;
  const std::size_t need = hw_timestamp ? sizeof(HostFrameTs) : sizeof(HostFrame);
  if (bytes.size() < need) return d;  // kTruncated
  const std::uint8_t* p = bytes.data();
  d.echo_id = load_u32(p + offsetof(HostFrame, echo_id));
  from_socketcan_id(load_u32(p + offsetof(HostFrame, can_id)), d.frame);
  const std::uint8_t dlc = p[offsetof(HostFrame, can_dlc)];
  d.channel = p[offsetof(HostFrame, channel)];
  const std::uint8_t flags = p[offsetof(HostFrame, flags)];
  d.overflow = (flags & kFrameFlagOverflow) != 0;
  if ((flags & kFrameFlagFd) != 0) {
    d.status = DecodeStatus::kCanFd;
    return d;
  }
  d.frame.dlc = dlc > kMaxDataBytes ? kMaxDataBytes : dlc;
  std::memcpy(d.frame.data.data(), p + offsetof(HostFrame, data), kMaxDataBytes);
  if (hw_timestamp) {
    d.has_timestamp = true;
    d.timestamp_us = load_u32(p + offsetof(HostFrameTs, timestamp_us));
  }
  d.status = d.echo_id == kEchoIdReceived ? DecodeStatus::kReceived : DecodeStatus::kEcho;
  return d;
}

std::size_t encode_frame(const Frame& frame, std::uint32_t echo_id, std::uint8_t channel,
                         bool hw_timestamp, std::span<std::uint8_t> out) noexcept {
  const std::size_t size = hw_timestamp ? sizeof(HostFrameTs) : sizeof(HostFrame);
  if (out.size() < size) return 0;
  std::uint8_t* p = out.data();
  std::memset(p, 0, size);
  store_u32(echo_id, p + offsetof(HostFrame, echo_id));
  store_u32(to_socketcan_id(frame), p + offsetof(HostFrame, can_id));
  p[offsetof(HostFrame, can_dlc)] = frame.dlc > kMaxDataBytes ? kMaxDataBytes : frame.dlc;
  p[offsetof(HostFrame, channel)] = channel;
  std::memcpy(p + offsetof(HostFrame, data), frame.data.data(), kMaxDataBytes);
  return size;
}

bool compute_bit_timing(const BtConst& c, std::uint32_t bitrate_bps, BitTiming& out) noexcept {
  if (bitrate_bps == 0 || c.fclk_can == 0 || c.brp_min == 0) return false;
  const std::uint32_t inc = c.brp_inc == 0 ? 1 : c.brp_inc;
  double best_error = 1.0;
  bool found = false;
  // 64-bit: a prescaler step never wraps around (the adapter's limits are its word, unchecked);
  // past fclk / bitrate no prescaler leaves a whole quantum per bit.
  for (std::uint64_t brp = c.brp_min; brp <= c.brp_max; brp += inc) {
    const std::uint64_t per_bit = brp * bitrate_bps;
    if (per_bit > c.fclk_can) break;
    if (c.fclk_can % per_bit != 0) continue;
    const std::uint64_t tq = c.fclk_can / per_bit;  // time quanta per bit = 1 + tseg1 + tseg2
    for (std::uint64_t tseg2 = c.tseg2_min; tseg2 <= c.tseg2_max; ++tseg2) {
      if (tq < 1 + tseg2) break;
      const std::uint64_t tseg1 = tq - 1 - tseg2;
      if (tseg1 < c.tseg1_min || tseg1 > c.tseg1_max || tseg1 < 1) continue;
      const double sample = static_cast<double>(1 + tseg1) / static_cast<double>(tq);
      const double error = std::abs(sample - 0.875);
      if (error < best_error - 1e-12) {
        best_error = error;
        found = true;
        out.brp = static_cast<std::uint32_t>(brp);
        out.prop_seg = 1;
        out.phase_seg1 = static_cast<std::uint32_t>(tseg1 - 1);
        out.phase_seg2 = static_cast<std::uint32_t>(tseg2);
        out.sjw = c.sjw_max < out.phase_seg2 ? (c.sjw_max == 0 ? 1 : c.sjw_max) : out.phase_seg2;
        if (out.sjw == 0) out.sjw = 1;
      }
    }
  }
  return found;
}

}  // namespace stac::can::gs_usb
