// HDL-64E data packet wire format (UDP payload, little-endian). REFERENCE §1.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>

namespace stac::velodyne {

inline constexpr std::size_t kPacketSize = 1206;
inline constexpr int kBlocksPerPacket = 12;
inline constexpr int kLasersPerBlock = 32;
inline constexpr std::uint16_t kUpperBank = 0xEEFF;     // lasers 0-31 (bytes FF EE on the wire)
inline constexpr std::uint16_t kLowerBank = 0xDDFF;     // lasers 32-63
inline constexpr std::uint16_t kRotationUnits = 36000;  // rotation in 0.01 deg, 0..35999
inline constexpr std::uint16_t kPortData = 2368;

#pragma pack(push, 1)
struct RawReturn {
  std::uint16_t distance;  // 2 mm units (distance_resolution); 0 = no return
  std::uint8_t intensity;
};
struct RawBlock {
  std::uint16_t bank;      // kUpperBank or kLowerBank
  std::uint16_t rotation;  // 0.01 deg
  RawReturn returns[kLasersPerBlock];
};
struct RawPacket {
  RawBlock blocks[kBlocksPerPacket];
  std::uint8_t trailer[6];
};
#pragma pack(pop)
static_assert(sizeof(RawReturn) == 3);
static_assert(sizeof(RawBlock) == 100);
static_assert(sizeof(RawPacket) == kPacketSize);

// Trailer of S2.1 (firmware 4.x) and S3: GPS time and one byte of the status cycle.
struct GpsTrailer {
  std::uint32_t usec_past_hour;
  std::uint8_t status_type;
  std::uint8_t status_value;
};
// Trailer of early S2 firmware: a spin counter and 4 bytes of temperature or "vXXX" version.
struct SpinTrailer {
  std::uint16_t spin_count;
  std::uint8_t info[4];
};

inline std::uint16_t load_u16(const std::uint8_t* p) noexcept {
  return static_cast<std::uint16_t>(p[0] | (p[1] << 8));
}
inline std::uint32_t load_u32(const std::uint8_t* p) noexcept {
  return static_cast<std::uint32_t>(p[0]) | (static_cast<std::uint32_t>(p[1]) << 8) |
         (static_cast<std::uint32_t>(p[2]) << 16) | (static_cast<std::uint32_t>(p[3]) << 24);
}
inline void store_u16(std::uint8_t* p, std::uint16_t v) noexcept {
  p[0] = static_cast<std::uint8_t>(v & 0xFF);
  p[1] = static_cast<std::uint8_t>(v >> 8);
}
inline void store_u32(std::uint8_t* p, std::uint32_t v) noexcept {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<std::uint8_t>((v >> (8 * i)) & 0xFF);
}

// The trailer's GPS time of a UTC instant: microseconds past the top of its hour.
inline std::uint32_t usec_past_hour(std::int64_t utc_ns) noexcept {
  const std::int64_t usec = (utc_ns / 1000) % 3'600'000'000LL;
  return static_cast<std::uint32_t>(usec < 0 ? usec + 3'600'000'000LL : usec);
}

inline GpsTrailer read_gps_trailer(const RawPacket& packet) noexcept {
  return {load_u32(packet.trailer), packet.trailer[4], packet.trailer[5]};
}
inline SpinTrailer read_spin_trailer(const RawPacket& packet) noexcept {
  SpinTrailer t{load_u16(packet.trailer), {}};
  std::memcpy(t.info, packet.trailer + 2, 4);
  return t;
}

// Dual return. HDL-64E S3: blocks come as [upper-strongest, lower-strongest, upper-last,
// lower-last] sharing one rotation; the packet carries no flag (valgur/velodyne_decoder).
// HDL-32E / VLP: the return-mode byte says so (0x39), and pairs of blocks share a rotation.
inline bool is_dual_return(const RawPacket& packet, bool model_supports_dual,
                           bool factory_trailer = false) noexcept {
  if (!model_supports_dual) return false;
  if (factory_trailer) {
    const bool pairs = packet.blocks[0].rotation == packet.blocks[1].rotation &&
                       packet.blocks[2].rotation == packet.blocks[3].rotation &&
                       packet.blocks[4].rotation == packet.blocks[5].rotation;
    // A zero mode byte (HDL-32E firmware before 2.2.20): the shared azimuths say it (VeloView).
    return pairs && (packet.trailer[4] == 0x39 || packet.trailer[4] == 0);
  }
  return packet.blocks[0].rotation == packet.blocks[2].rotation &&
         packet.blocks[1].rotation == packet.blocks[3].rotation;
}

// Views a payload as a packet when it has exactly the packet size; nullptr otherwise.
inline const RawPacket* as_packet(std::span<const std::uint8_t> payload) noexcept {
  if (payload.size() != kPacketSize) return nullptr;
  return reinterpret_cast<const RawPacket*>(payload.data());
}

}  // namespace stac::velodyne
