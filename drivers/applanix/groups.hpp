// Decoded Applanix groups 1, 2, 3 and $MSG control messages, with their decoders and encoders.
// Units are in the field names (deg, m, m/s, deg/s, m/s^2, s). Decoders take one whole verified
// message (see StreamParser) and return false when its length does not fit the group's layout.
// Encoders write a complete message (padding, checksum, "$#") and return its length, or 0 when
// `out` is too small. No allocation.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>

#include "drivers/applanix/wire.hpp"

namespace stac::applanix {

enum class TimeType : std::uint8_t { pos = 0, gps = 1, utc = 2, user = 3 };

struct TimeDistance {
  double time1_s = 0.0;  // per time1_type: POS = s since power-on; GPS/UTC = s of the week
  double time2_s = 0.0;  // per time2_type (USER: set by the user)
  double distance_tag_m = 0.0;
  std::uint8_t time_types = 0;     // raw byte: bits 0-3 time1, bits 4-7 time2
  std::uint8_t distance_type = 0;  // 0 none, 1 POS, 2 DMI
  TimeType time1_type() const noexcept { return static_cast<TimeType>(time_types & 0x0F); }
  TimeType time2_type() const noexcept { return static_cast<TimeType>(time_types >> 4); }
};

struct Group1 {  // vehicle navigation solution
  double latitude_deg = 0, longitude_deg = 0, altitude_m = 0;
  float north_velocity_mps = 0, east_velocity_mps = 0, down_velocity_mps = 0;
  double roll_deg = 0, pitch_deg = 0, heading_deg = 0, wander_deg = 0;  // Tate-Bryant
  float track_deg = 0, speed_mps = 0;
  float rate_longitudinal_dps = 0, rate_transverse_dps = 0, rate_down_dps = 0;
  float accel_longitudinal_mps2 = 0, accel_transverse_mps2 = 0, accel_down_mps2 = 0;
  std::uint8_t alignment_status = 0;  // 0 full navigation ... 8 no valid solution
  bool operator==(const Group1&) const = default;
};

struct Group2 {                             // performance metrics, RMS
  std::array<float, 3> position_rms_m{};    // north, east, down
  std::array<float, 3> velocity_rms_mps{};  // north, east, down
  std::array<float, 3> attitude_rms_deg{};  // roll, pitch, heading
  float ellipse_major_m = 0, ellipse_minor_m = 0, ellipse_orientation_deg = 0;
  bool operator==(const Group2&) const = default;
};

struct GnssChannel {
  std::uint16_t prn = 0;
  std::uint16_t tracking_status = 0;
  float azimuth_deg = 0, elevation_deg = 0, l1_snr_dbhz = 0, l2_snr_dbhz = 0;
  bool operator==(const GnssChannel&) const = default;
};

struct Group3 {  // primary GNSS receiver status
  static constexpr std::size_t kMaxChannels = 64;
  std::int8_t solution_status = -1;  // -1 unknown ... 7 narrow-lane RTK
  std::uint8_t sv_count = 0;
  std::array<GnssChannel, kMaxChannels> channels{};
  std::size_t channel_count = 0;     // records kept in `channels`
  std::size_t channels_dropped = 0;  // records beyond kMaxChannels (decoding keeps the rest)
  float hdop = 0, vdop = 0, dgps_latency_s = 0;
  std::uint16_t dgps_reference_id = 0;
  std::uint32_t gps_week = 0;
  double gps_utc_offset_s = 0;  // GPS - UTC
  float message_latency_s = 0, geoid_separation_m = 0;
  std::uint16_t receiver_type = 0;
  std::uint32_t status = 0;
};

// "$MSG" control message. body views the message: everything between the transaction number
// and the checksum, including the 0-3 pad bytes (the wire does not say how many there are).
struct Message {
  std::uint16_t id = 0;  // 0 = acknowledge
  std::uint16_t transaction = 0;
  std::span<const std::uint8_t> body;
};

// Sum of the little-endian u16 words of `bytes` (even length), mod 65536.
std::uint16_t word_sum(std::span<const std::uint8_t> bytes) noexcept;
// True when `m` is one message with "$GRP"/"$MSG", a byte count matching its length, "$#" and a
// zero checksum.
bool is_valid_message(std::span<const std::uint8_t> m) noexcept;

// Decoders: `m` is a whole valid group (or message) of the right id.
bool decode_time_distance(std::span<const std::uint8_t> m, TimeDistance& out) noexcept;
bool decode_group1(std::span<const std::uint8_t> m, Group1& out) noexcept;
// A solution a vehicle can have: finite, on the Earth (|lat| <= 90, |lon| <= 360), altitude
// -1..20 km, under 200 m/s. A corrupted message with a valid checksum fails it.
bool plausible(const Group1& g) noexcept;
bool decode_group2(std::span<const std::uint8_t> m, Group2& out) noexcept;
bool decode_group3(std::span<const std::uint8_t> m, Group3& out) noexcept;
bool decode_message(std::span<const std::uint8_t> m, Message& out) noexcept;

// Encoders.
std::size_t encode_group(std::uint16_t id, const TimeDistance& t,
                         std::span<const std::uint8_t> data, std::span<std::uint8_t> out) noexcept;
std::size_t encode_group1(const Group1& g, const TimeDistance& t,
                          std::span<std::uint8_t> out) noexcept;
std::size_t encode_group2(const Group2& g, const TimeDistance& t,
                          std::span<std::uint8_t> out) noexcept;
std::size_t encode_group3(const Group3& g, const TimeDistance& t,
                          std::span<std::uint8_t> out) noexcept;
std::size_t encode_message(std::uint16_t id, std::uint16_t transaction,
                           std::span<const std::uint8_t> body,
                           std::span<std::uint8_t> out) noexcept;

inline constexpr std::int64_t kSecondsPerWeek = 604'800;
// The last GPS week a time is made for (the year 2171); int64 ns overflow past week 15,250.
inline constexpr std::uint32_t kMaxGpsWeek = 10'000;

// Absolute GPS time (ns since 1980-01-06 00:00:00 GPS) of a GPS or UTC seconds-of-week `time_s`
// in `week`; UTC times are shifted by `gps_utc_offset_s` (carried into the next week when the
// shift crosses Sunday). Empty for POS and USER times, a week past kMaxGpsWeek, and seconds more
// than two weeks from the week's start (garbage, not a receiver's time).
std::optional<std::int64_t> gps_time_ns(TimeType type, double time_s, std::uint32_t week,
                                        double gps_utc_offset_s) noexcept;

}  // namespace stac::applanix
