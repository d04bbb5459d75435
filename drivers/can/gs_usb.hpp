// The gs_usb protocol of candleLight / Geschwister Schneider USB-CAN adapters (the Linux gs_usb
// driver's wire format; candle-usb/candleLight_fw include/gs_usb.h): constants, wire structs,
// the byte-level frame codec and the bit-timing calculation. No USB here (gs_usb_device.hpp).
// All words are little-endian (the host announces its byte order with HOST_FORMAT 0x0000beef).
#pragma once

#include <cstdint>
#include <span>

#include "drivers/can/frame.hpp"

namespace stac::can::gs_usb {

inline constexpr std::uint16_t kVendorId = 0x1d50;
inline constexpr std::uint16_t kProductId = 0x606f;
inline constexpr std::uint8_t kEndpointIn = 0x81;
inline constexpr std::uint8_t kEndpointOut = 0x02;

// Vendor control requests (bRequest).
enum class Request : std::uint8_t {
  kHostFormat = 0,
  kBitTiming = 1,
  kMode = 2,
  kBtConst = 4,
  kDeviceConfig = 5,
  kTimestamp = 6,
};

inline constexpr std::uint32_t kHostFormatLittleEndian = 0x0000beef;
inline constexpr std::uint32_t kEchoIdReceived = 0xFFFFFFFFu;  // echo_id of a received frame

// gs_device_mode.mode and .flags; gs_device_bt_const.feature uses the same flag bits.
inline constexpr std::uint32_t kModeReset = 0;
inline constexpr std::uint32_t kModeStart = 1;
inline constexpr std::uint32_t kFlagListenOnly = 1u << 0;
inline constexpr std::uint32_t kFlagLoopBack = 1u << 1;
inline constexpr std::uint32_t kFlagHwTimestamp = 1u << 4;

// gs_host_frame.flags.
inline constexpr std::uint8_t kFrameFlagOverflow = 1u
                                                   << 0;  // the adapter lost frames before this one
inline constexpr std::uint8_t kFrameFlagFd = 1u << 1;

#pragma pack(push, 1)
struct HostConfig {
  std::uint32_t byte_order;
};
struct DeviceConfig {
  std::uint8_t reserved1, reserved2, reserved3;
  std::uint8_t icount;  // number of CAN channels - 1
  std::uint32_t sw_version, hw_version;
};
struct DeviceMode {
  std::uint32_t mode, flags;
};
struct BitTiming {
  std::uint32_t prop_seg, phase_seg1, phase_seg2, sjw, brp;
};
struct BtConst {
  std::uint32_t feature, fclk_can, tseg1_min, tseg1_max, tseg2_min, tseg2_max, sjw_max, brp_min,
      brp_max, brp_inc;
};
struct HostFrame {
  std::uint32_t echo_id;
  std::uint32_t can_id;  // SocketCAN id with flag bits
  std::uint8_t can_dlc, channel, flags, reserved;
  std::uint8_t data[8];
};
struct HostFrameTs {
  HostFrame frame;
  std::uint32_t timestamp_us;  // adapter clock, wraps every 71.6 minutes
};
#pragma pack(pop)
static_assert(sizeof(HostConfig) == 4 && sizeof(DeviceConfig) == 12 && sizeof(DeviceMode) == 8);
static_assert(sizeof(BitTiming) == 20 && sizeof(BtConst) == 40);
static_assert(sizeof(HostFrame) == 20 && sizeof(HostFrameTs) == 24);

enum class DecodeStatus : std::uint8_t {
  kReceived,   // a frame from the bus
  kEcho,       // the adapter confirming a frame we sent (echo_id as given to encode_frame)
  kTruncated,  // fewer than 20 bytes (24 when hardware timestamps are on)
  kCanFd,      // a CAN FD frame: not supported
};

struct DecodedFrame {
  DecodeStatus status = DecodeStatus::kTruncated;
  Frame frame;  // stamp_ns left 0: the caller stamps it
  std::uint32_t echo_id = 0;
  std::uint8_t channel = 0;
  bool overflow = false;  // kFrameFlagOverflow was set
  bool has_timestamp = false;
  std::uint32_t timestamp_us = 0;
};

// Decodes one bulk-IN transfer. `hw_timestamp`: the mode was started with kFlagHwTimestamp,
// so frames are 24 bytes. No allocation.
DecodedFrame decode_frame(std::span<const std::uint8_t> bytes, bool hw_timestamp) noexcept;
// Encodes a frame for bulk OUT (20 bytes, or 24 with a zero timestamp when hw_timestamp);
// returns the bytes written, 0 when `out` is too small.
std::size_t encode_frame(const Frame& frame, std::uint32_t echo_id, std::uint8_t channel,
                         bool hw_timestamp, std::span<std::uint8_t> out) noexcept;

// Bit timing for `bitrate_bps` from the adapter's limits: the exact divider whose sample point
// is closest to 87.5 % (CiA 301's recommendation). False when no divider gives the exact rate.
bool compute_bit_timing(const BtConst& limits, std::uint32_t bitrate_bps, BitTiming& out) noexcept;

}  // namespace stac::can::gs_usb
