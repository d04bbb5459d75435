#include "drivers/applanix/groups.hpp"

#include <cmath>
#include <cstring>

namespace stac::applanix {
namespace {

constexpr std::size_t kTimeEnd = kHeaderBytes + sizeof(WireTimeDistance);  // group data start

std::uint16_t load16(const std::uint8_t* p) noexcept {
  return static_cast<std::uint16_t>(p[0] | (p[1] << 8));
}
void store16(std::uint8_t* p, std::uint16_t v) noexcept {
  p[0] = static_cast<std::uint8_t>(v & 0xFF);
  p[1] = static_cast<std::uint8_t>(v >> 8);
}

template <class T>
T load(const std::uint8_t* p) noexcept {
  T v{};
  std::memcpy(&v, p, sizeof(T));
  return v;
}

std::size_t padded_total(std::size_t unpadded) noexcept {
  return (unpadded + 3) & ~std::size_t{3};
}

// Writes header, pad, checksum and "$#" around a body already at out[8..8+body) ; returns total.
std::size_t seal(const char* start, std::uint16_t id, std::size_t body,
                 std::span<std::uint8_t> out) noexcept {
  const std::size_t total = padded_total(kHeaderBytes + body + kTrailerBytes);
  std::memcpy(out.data(), start, 4);
  store16(out.data() + 4, id);
  store16(out.data() + 6, static_cast<std::uint16_t>(total - kHeaderBytes));
  std::memset(out.data() + kHeaderBytes + body, 0, total - kHeaderBytes - body - kTrailerBytes);
  out[total - 2] = '$';
  out[total - 1] = '#';
  store16(out.data() + total - 4, 0);
  const std::uint16_t sum = word_sum(out.first(total));
  store16(out.data() + total - 4, static_cast<std::uint16_t>(0x10000u - sum));
  return total;
}

bool fits(std::size_t body, std::span<std::uint8_t> out) noexcept {
  const std::size_t total = padded_total(kHeaderBytes + body + kTrailerBytes);
  return total <= kMaxMessageBytes && out.size() >= total;
}

void put_time(const TimeDistance& t, std::uint8_t* p) noexcept {
  const WireTimeDistance w{t.time1_s, t.time2_s, t.distance_tag_m, t.time_types, t.distance_type};
  std::memcpy(p, &w, sizeof(w));
}

}  // namespace

std::uint16_t word_sum(std::span<const std::uint8_t> bytes) noexcept {
  std::uint32_t sum = 0;
  for (std::size_t i = 0; i + 1 < bytes.size(); i += 2) sum += load16(bytes.data() + i);
  return static_cast<std::uint16_t>(sum);
}

bool is_valid_message(std::span<const std::uint8_t> m) noexcept {
  if (m.size() < kMessageMinBytes || m.size() % 4 != 0) return false;
  if (std::memcmp(m.data(), "$GRP", 4) != 0 && std::memcmp(m.data(), "$MSG", 4) != 0) return false;
  return load16(m.data() + 6) + kHeaderBytes == m.size() && m[m.size() - 2] == '$' &&
         m[m.size() - 1] == '#' && word_sum(m) == 0;
}

bool decode_time_distance(std::span<const std::uint8_t> m, TimeDistance& out) noexcept {
  if (m.size() < kTimeEnd) return false;
  const auto w = load<WireTimeDistance>(m.data() + kHeaderBytes);
  out = TimeDistance{w.time1, w.time2, w.distance_tag, w.time_types, w.distance_type};
  return true;
}

bool decode_group1(std::span<const std::uint8_t> m, Group1& out) noexcept {
  if (m.size() != kGroup1Bytes) return false;
  const auto w = load<WireGroup1>(m.data());
  out = Group1{
      w.latitude_deg,          w.longitude_deg,       w.altitude_m,      w.north_velocity_mps,
      w.east_velocity_mps,     w.down_velocity_mps,   w.roll_deg,        w.pitch_deg,
      w.heading_deg,           w.wander_deg,          w.track_deg,       w.speed_mps,
      w.rate_longitudinal_dps, w.rate_transverse_dps, w.rate_down_dps,   w.accel_longitudinal_mps2,
      w.accel_transverse_mps2, w.accel_down_mps2,     w.alignment_status};
  return true;
}

bool decode_group2(std::span<const std::uint8_t> m, Group2& out) noexcept {
  if (m.size() != kGroup2Bytes) return false;
  const auto w = load<WireGroup2Data>(m.data() + kTimeEnd);
  for (std::size_t i = 0; i < 3; ++i) {
    out.position_rms_m[i] = w.position_rms_m[i];
    out.velocity_rms_mps[i] = w.velocity_rms_mps[i];
    out.attitude_rms_deg[i] = w.attitude_rms_deg[i];
  }
  out.ellipse_major_m = w.ellipse_major_m;
  out.ellipse_minor_m = w.ellipse_minor_m;
  out.ellipse_orientation_deg = w.ellipse_orientation_deg;
  return true;
}

bool decode_group3(std::span<const std::uint8_t> m, Group3& out) noexcept {
  if (m.size() < kGroup3FixedBytes) return false;
  const auto head = load<WireGroup3Head>(m.data() + kTimeEnd);
  if (head.channel_bytes % sizeof(WireGnssChannel) != 0 ||
      m.size() != kGroup3FixedBytes + head.channel_bytes) {
    return false;
  }
  out.solution_status = head.solution_status;
  out.sv_count = head.sv_count;
  const std::size_t n = head.channel_bytes / sizeof(WireGnssChannel);
  out.channel_count = n < Group3::kMaxChannels ? n : Group3::kMaxChannels;
  out.channels_dropped = n - out.channel_count;
  const std::uint8_t* p = m.data() + kTimeEnd + sizeof(WireGroup3Head);
  for (std::size_t i = 0; i < out.channel_count; ++i) {
    const auto c = load<WireGnssChannel>(p + i * sizeof(WireGnssChannel));
    out.channels[i] = GnssChannel{c.prn,           c.tracking_status, c.azimuth_deg,
                                  c.elevation_deg, c.l1_snr_dbhz,     c.l2_snr_dbhz};
  }
  const auto t = load<WireGroup3Tail>(p + head.channel_bytes);
  out.hdop = t.hdop;
  out.vdop = t.vdop;
  out.dgps_latency_s = t.dgps_latency_s;
  out.dgps_reference_id = t.dgps_reference_id;
  out.gps_week = t.gps_week;
  out.gps_utc_offset_s = t.gps_utc_offset_s;
  out.message_latency_s = t.message_latency_s;
  out.geoid_separation_m = t.geoid_separation_m;
  out.receiver_type = t.receiver_type;
  out.status = t.status;
  return true;
}

bool decode_message(std::span<const std::uint8_t> m, Message& out) noexcept {
  if (m.size() < kMessageMinBytes) return false;
  out.id = load16(m.data() + 4);
  out.transaction = load16(m.data() + kHeaderBytes);
  out.body = m.subspan(kHeaderBytes + 2, m.size() - kHeaderBytes - 2 - kTrailerBytes);
  return true;
}

std::size_t encode_group(std::uint16_t id, const TimeDistance& t,
                         std::span<const std::uint8_t> data, std::span<std::uint8_t> out) noexcept {
  const std::size_t body = sizeof(WireTimeDistance) + data.size();
  if (!fits(body, out)) return 0;
  put_time(t, out.data() + kHeaderBytes);
  if (!data.empty()) std::memcpy(out.data() + kTimeEnd, data.data(), data.size());
  return seal("$GRP", id, body, out);
}

std::size_t encode_group1(const Group1& g, const TimeDistance& t,
                          std::span<std::uint8_t> out) noexcept {
  WireGroup1 w{};
  w.latitude_deg = g.latitude_deg;
  w.longitude_deg = g.longitude_deg;
  w.altitude_m = g.altitude_m;
  w.north_velocity_mps = g.north_velocity_mps;
  w.east_velocity_mps = g.east_velocity_mps;
  w.down_velocity_mps = g.down_velocity_mps;
  w.roll_deg = g.roll_deg;
  w.pitch_deg = g.pitch_deg;
  w.heading_deg = g.heading_deg;
  w.wander_deg = g.wander_deg;
  w.track_deg = g.track_deg;
  w.speed_mps = g.speed_mps;
  w.rate_longitudinal_dps = g.rate_longitudinal_dps;
  w.rate_transverse_dps = g.rate_transverse_dps;
  w.rate_down_dps = g.rate_down_dps;
  w.accel_longitudinal_mps2 = g.accel_longitudinal_mps2;
  w.accel_transverse_mps2 = g.accel_transverse_mps2;
  w.accel_down_mps2 = g.accel_down_mps2;
  w.alignment_status = g.alignment_status;
  constexpr std::size_t kData = offsetof(WireGroup1, pad) + 1 - kTimeEnd;  // includes the pad byte
  const auto* data = reinterpret_cast<const std::uint8_t*>(&w) + kTimeEnd;
  return encode_group(1, t, {data, kData}, out);
}

std::size_t encode_group2(const Group2& g, const TimeDistance& t,
                          std::span<std::uint8_t> out) noexcept {
  WireGroup2Data w{};
  for (std::size_t i = 0; i < 3; ++i) {
    w.position_rms_m[i] = g.position_rms_m[i];
    w.velocity_rms_mps[i] = g.velocity_rms_mps[i];
    w.attitude_rms_deg[i] = g.attitude_rms_deg[i];
  }
  w.ellipse_major_m = g.ellipse_major_m;
  w.ellipse_minor_m = g.ellipse_minor_m;
  w.ellipse_orientation_deg = g.ellipse_orientation_deg;
  return encode_group(2, t, {reinterpret_cast<const std::uint8_t*>(&w), sizeof(w)}, out);
}

std::size_t encode_group3(const Group3& g, const TimeDistance& t,
                          std::span<std::uint8_t> out) noexcept {
  const std::size_t n =
      g.channel_count < Group3::kMaxChannels ? g.channel_count : Group3::kMaxChannels;
  const std::size_t channel_bytes = n * sizeof(WireGnssChannel);
  const std::size_t body =
      sizeof(WireTimeDistance) + sizeof(WireGroup3Head) + channel_bytes + sizeof(WireGroup3Tail);
  if (!fits(body, out)) return 0;
  put_time(t, out.data() + kHeaderBytes);
  std::uint8_t* p = out.data() + kTimeEnd;
  const WireGroup3Head head{g.solution_status, g.sv_count,
                            static_cast<std::uint16_t>(channel_bytes)};
  std::memcpy(p, &head, sizeof(head));
  p += sizeof(head);
  for (std::size_t i = 0; i < n; ++i, p += sizeof(WireGnssChannel)) {
    const GnssChannel& c = g.channels[i];
    const WireGnssChannel w{c.prn,           c.tracking_status, c.azimuth_deg,
                            c.elevation_deg, c.l1_snr_dbhz,     c.l2_snr_dbhz};
    std::memcpy(p, &w, sizeof(w));
  }
  const WireGroup3Tail tail{g.hdop,
                            g.vdop,
                            g.dgps_latency_s,
                            g.dgps_reference_id,
                            g.gps_week,
                            g.gps_utc_offset_s,
                            g.message_latency_s,
                            g.geoid_separation_m,
                            g.receiver_type,
                            g.status};
  std::memcpy(p, &tail, sizeof(tail));
  return seal("$GRP", 3, body, out);
}

std::size_t encode_message(std::uint16_t id, std::uint16_t transaction,
                           std::span<const std::uint8_t> body,
                           std::span<std::uint8_t> out) noexcept {
  if (!fits(2 + body.size(), out)) return 0;
  store16(out.data() + kHeaderBytes, transaction);
  if (!body.empty()) std::memcpy(out.data() + kHeaderBytes + 2, body.data(), body.size());
  return seal("$MSG", id, 2 + body.size(), out);
}

std::optional<std::int64_t> gps_time_ns(TimeType type, double time_s, std::uint32_t week,
                                        double gps_utc_offset_s) noexcept {
  if (type != TimeType::gps && type != TimeType::utc) return std::nullopt;
  if (!std::isfinite(time_s) || !std::isfinite(gps_utc_offset_s)) return std::nullopt;
  const double of_week = type == TimeType::utc ? time_s + gps_utc_offset_s : time_s;
  // A week no receiver sends yet, or seconds far outside one week: no time (and no int64
  // overflow below; found by fuzz/applanix_stream_fuzz).
  if (week > kMaxGpsWeek || !(std::fabs(of_week) <= 2.0 * kSecondsPerWeek)) return std::nullopt;
  const auto ns_of_week = static_cast<std::int64_t>(std::llround(of_week * 1e9));
  return static_cast<std::int64_t>(week) * kSecondsPerWeek * 1'000'000'000 + ns_of_week;
}

bool plausible(const Group1& g) noexcept {
  const double values[] = {
      g.latitude_deg,      g.longitude_deg,         g.altitude_m,          g.roll_deg,
      g.pitch_deg,         g.heading_deg,           g.north_velocity_mps,  g.east_velocity_mps,
      g.down_velocity_mps, g.rate_longitudinal_dps, g.rate_transverse_dps, g.rate_down_dps};
  for (const double v : values) {
    if (!std::isfinite(v)) return false;
  }
  const double speed2 = g.north_velocity_mps * g.north_velocity_mps +
                        g.east_velocity_mps * g.east_velocity_mps +
                        g.down_velocity_mps * g.down_velocity_mps;
  return std::fabs(g.latitude_deg) <= 90 && std::fabs(g.longitude_deg) <= 360 &&
         g.altitude_m >= -1000 && g.altitude_m <= 20000 && speed2 <= 200.0 * 200.0;
}

}  // namespace stac::applanix
