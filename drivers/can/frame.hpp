// One classic CAN frame (no CAN FD) as every STAC CAN transport hands it on: SocketCAN raw
// sockets, gs_usb adapters and candump logs.
#pragma once

#include <array>
#include <cstdint>

namespace stac::can {

inline constexpr std::uint32_t kStandardIdMask = 0x7FFu;       // 11-bit identifier
inline constexpr std::uint32_t kExtendedIdMask = 0x1FFFFFFFu;  // 29-bit identifier
inline constexpr std::uint8_t kMaxDataBytes = 8;

struct Frame {
  std::int64_t stamp_ns = 0;  // receive time, ns since the Unix epoch (kernel, adapter or log)
  std::uint32_t id = 0;       // 11 or 29 bits, no flag bits
  bool extended = false;      // 29-bit identifier
  bool remote = false;        // remote transmission request (no data)
  bool error = false;         // error frame (id holds the SocketCAN error class bits)
  std::uint8_t dlc = 0;       // 0..8 data bytes
  std::array<std::uint8_t, kMaxDataBytes> data{};
};

// SocketCAN's can_id flag bits (linux/can.h), also used by gs_usb and candump's 8-digit ids.
inline constexpr std::uint32_t kSocketCanEffFlag = 0x80000000u;
inline constexpr std::uint32_t kSocketCanRtrFlag = 0x40000000u;
inline constexpr std::uint32_t kSocketCanErrFlag = 0x20000000u;

// Frame id and flags <-> a SocketCAN can_id word.
// An error frame's id is its error class bits (up to 29), whether or not the EFF flag is set.
constexpr std::uint32_t to_socketcan_id(const Frame& f) noexcept {
  return (f.extended || f.error ? f.id & kExtendedIdMask : f.id & kStandardIdMask) |
         (f.extended ? kSocketCanEffFlag : 0u) | (f.remote ? kSocketCanRtrFlag : 0u) |
         (f.error ? kSocketCanErrFlag : 0u);
}
constexpr void from_socketcan_id(std::uint32_t can_id, Frame& f) noexcept {
  f.extended = (can_id & kSocketCanEffFlag) != 0;
  f.remote = (can_id & kSocketCanRtrFlag) != 0;
  f.error = (can_id & kSocketCanErrFlag) != 0;
  f.id = can_id & (f.extended || f.error ? kExtendedIdMask : kStandardIdMask);
}

}  // namespace stac::can
