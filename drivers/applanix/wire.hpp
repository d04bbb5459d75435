// Applanix POS LV/MV real-time data wire format (little-endian; REFERENCE §2, the V5 ICD).
// A group: "$GRP" | u16 id | u16 byte count (= total - 8) | time/distance block | data |
// pad to a multiple of 4 | u16 checksum | "$#". A control message: "$MSG" | u16 id | u16 byte
// count | u16 transaction | body | pad | checksum | "$#". The checksum makes the sum of all u16
// words of the whole message, "$GRP"/"$MSG" through "$#", 0 mod 65536.
#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>

namespace stac::applanix {

static_assert(std::endian::native == std::endian::little,
              "the wire structs assume a little-endian host");

inline constexpr std::uint16_t kPortDisplay = 5600;   // UDP broadcast, about 1 Hz
inline constexpr std::uint16_t kPortControl = 5601;   // TCP
inline constexpr std::uint16_t kPortRealTime = 5602;  // TCP (or UDP), Group 1 up to 200 Hz
inline constexpr std::uint16_t kPortLogging = 5603;   // TCP

inline constexpr std::size_t kHeaderBytes = 8;   // "$GRP"/"$MSG", id, byte count
inline constexpr std::size_t kTrailerBytes = 4;  // checksum, "$#"
inline constexpr std::size_t kMaxMessageBytes = 65535 + kHeaderBytes;  // the byte count is a u16

#pragma pack(push, 1)
struct WireHeader {
  char start[4];  // "$GRP" or "$MSG"
  std::uint16_t id;
  std::uint16_t byte_count;  // total length - 8
};
struct WireTimeDistance {
  double time1;                // s (see time types)
  double time2;                // s
  double distance_tag;         // m
  std::uint8_t time_types;     // bits 0-3 time1, bits 4-7 time2 (TimeType)
  std::uint8_t distance_type;  // 0 none, 1 POS, 2 DMI
};
struct WireGroup1 {
  WireHeader header;
  WireTimeDistance time;
  double latitude_deg, longitude_deg, altitude_m;
  float north_velocity_mps, east_velocity_mps, down_velocity_mps;
  double roll_deg, pitch_deg, heading_deg, wander_deg;  // Tate-Bryant
  float track_deg, speed_mps;
  float rate_longitudinal_dps, rate_transverse_dps, rate_down_dps;
  float accel_longitudinal_mps2, accel_transverse_mps2, accel_down_mps2;
  std::uint8_t alignment_status;
  std::uint8_t pad;
  std::uint16_t checksum;
  char end[2];  // "$#"
};
struct WireGroup2Data {       // 12 RMS values
  float position_rms_m[3];    // north, east, down
  float velocity_rms_mps[3];  // north, east, down
  float attitude_rms_deg[3];  // roll, pitch, heading
  float ellipse_major_m, ellipse_minor_m, ellipse_orientation_deg;
};
struct WireGroup3Head {
  std::int8_t solution_status;  // -1 unknown ... 7 narrow-lane RTK
  std::uint8_t sv_count;
  std::uint16_t channel_bytes;  // 20 per channel record
};
struct WireGnssChannel {
  std::uint16_t prn;
  std::uint16_t tracking_status;
  float azimuth_deg, elevation_deg, l1_snr_dbhz, l2_snr_dbhz;
};
struct WireGroup3Tail {
  float hdop, vdop;
  float dgps_latency_s;
  std::uint16_t dgps_reference_id;
  std::uint32_t gps_week;
  double gps_utc_offset_s;  // GPS time - UTC, s
  float message_latency_s;
  float geoid_separation_m;
  std::uint16_t receiver_type;
  std::uint32_t status;
};
#pragma pack(pop)
static_assert(sizeof(WireHeader) == kHeaderBytes);
static_assert(sizeof(WireTimeDistance) == 26);
static_assert(sizeof(WireGroup1) == 140);
static_assert(sizeof(WireGroup2Data) == 48);
static_assert(sizeof(WireGroup3Head) == 4);
static_assert(sizeof(WireGnssChannel) == 20);
static_assert(sizeof(WireGroup3Tail) == 40);

inline constexpr std::size_t kGroup1Bytes = sizeof(WireGroup1);
inline constexpr std::size_t kGroup2Bytes = 88;
inline constexpr std::size_t kGroup3FixedBytes = 84;  // + 20 per channel record
inline constexpr std::size_t kMessageMinBytes = 16;   // header, transaction, checksum, "$#", pad
inline constexpr std::size_t kGroupMinBytes = 40;     // header, time/distance, checksum, "$#", pad

}  // namespace stac::applanix
