// Writes HDL-64E data packets byte for byte (tests, the simulator, the demo capture).
#pragma once

#include <array>
#include <cstdint>
#include <cstring>
#include <span>

#include "drivers/velodyne/packet.hpp"

namespace stac::velodyne {

class PacketBuilder {
 public:
  PacketBuilder() noexcept { bytes_.fill(0); }

  void set_block(int block, std::uint16_t bank, std::uint16_t rotation) noexcept {
    std::uint8_t* b = block_ptr(block);
    store_u16(b, bank);
    store_u16(b + 2, rotation);
  }
  // Raw distance in resolution units (2 mm), raw intensity.
  void set_return(int block, int j, std::uint16_t distance, std::uint8_t intensity) noexcept {
    std::uint8_t* r = block_ptr(block) + 4 + 3 * static_cast<std::ptrdiff_t>(j);
    store_u16(r, distance);
    r[2] = intensity;
  }
  void set_gps_trailer(std::uint32_t usec_past_hour, std::uint8_t type,
                       std::uint8_t value) noexcept {
    std::uint8_t* t = bytes_.data() + kPacketSize - 6;
    store_u32(t, usec_past_hour);
    t[4] = type;
    t[5] = value;
  }
  void set_spin_trailer(std::uint16_t spin_count, const char (&info)[5]) noexcept {
    std::uint8_t* t = bytes_.data() + kPacketSize - 6;
    store_u16(t, spin_count);
    std::memcpy(t + 2, info, 4);
  }
  std::span<const std::uint8_t> bytes() const noexcept { return bytes_; }
  std::span<std::uint8_t> mutable_bytes() noexcept { return bytes_; }

 private:
  std::uint8_t* block_ptr(int block) noexcept { return bytes_.data() + sizeof(RawBlock) * block; }
  std::array<std::uint8_t, kPacketSize> bytes_{};
};

}  // namespace stac::velodyne
