// Velodyne position packets (UDP port 8308) and their NMEA sentence: the input as a 512-byte
// payload, as a sentence, and as the sentence field of a payload. Whatever is accepted must be in
// range, and a fix the writer takes must read back the same, to the writer's resolution.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <string_view>

#include "drivers/velodyne/position.hpp"

namespace {

using stac::velodyne::NmeaFix;
using stac::velodyne::NmeaSentence;
using stac::velodyne::PpsStatus;

constexpr double kKnot = 1852.0 / 3600.0;

void require(bool ok) {
  if (!ok) __builtin_trap();
}

bool near(const std::optional<double>& a, const std::optional<double>& b, double tolerance) {
  if (a.has_value() != b.has_value()) return false;
  return !a || std::abs(*a - *b) <= tolerance;
}

void check_in_range(const NmeaFix& f) {
  require(!f.latitude_deg || std::abs(*f.latitude_deg) <= 90.0);
  require(!f.longitude_deg || std::abs(*f.longitude_deg) <= 180.0);
  require(!f.speed_mps || (*f.speed_mps >= 0.0 && *f.speed_mps <= 1000.0 * kKnot + 1e-9));
  require(!f.course_deg || (*f.course_deg >= 0.0 && *f.course_deg <= 360.0));
  require(!f.time_of_day_ns || (*f.time_of_day_ns >= 0 && *f.time_of_day_ns < 86'401'000'000'000));
  require(!f.date || (f.date->year >= 1980 && f.date->year < 2080));
  require(!f.date || stac::velodyne::nmea_utc_ns(f).has_value() == f.time_of_day_ns.has_value());
}

void check_round_trip(const NmeaFix& f, std::uint32_t usec_past_hour, PpsStatus pps) {
  std::array<std::uint8_t, stac::velodyne::kPositionPacketSize> out{};
  if (!stac::velodyne::write_position_packet(usec_past_hour, pps, f, out)) return;
  const auto r = stac::velodyne::parse_position_packet(out);
  require(r.has_value());
  require(r->usec_past_hour == usec_past_hour && r->pps == pps);
  const NmeaFix& g = r->fix;
  require(g.sentence == f.sentence && g.talker == f.talker && g.checksum_ok && g.valid == f.valid);
  require(g.time_of_day_ns.has_value() == f.time_of_day_ns.has_value());
  require(!f.time_of_day_ns || *g.time_of_day_ns == *f.time_of_day_ns / 1'000'000 * 1'000'000);
  require(near(g.latitude_deg, f.latitude_deg, 1e-8));
  require(near(g.longitude_deg, f.longitude_deg, 1e-8));
  if (f.sentence == NmeaSentence::kRmc) {
    require(g.date.has_value() == f.date.has_value());
    require(!f.date || (g.date->year == f.date->year && g.date->month == f.date->month &&
                        g.date->day == f.date->day));
    require(near(g.speed_mps, f.speed_mps, 0.0006 * kKnot));
    require(near(g.course_deg, f.course_deg, 0.0051));
  } else if (f.valid && f.gga_quality > 0) {
    require(g.gga_quality == f.gga_quality);
  }
}

void check_packet(const stac::velodyne::ParseResult& r) {
  if (!r) {
    require(std::string_view(stac::velodyne::to_string(r.error())) != "unknown position error");
    return;
  }
  require(r->sentence_length <= stac::velodyne::kNmeaMaxLength);
  require(r->sentence[r->sentence_length] == '\0');
  require(r->fix.checksum_ok);
  check_in_range(r->fix);
  check_round_trip(r->fix, r->usec_past_hour, r->pps);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::span<const std::uint8_t> bytes(data, size);
  check_packet(stac::velodyne::parse_position_packet(bytes));
  (void)stac::velodyne::parse_hdl32e_motion(bytes);

  const std::string_view text(reinterpret_cast<const char*>(data), size);
  if (const auto fix = stac::velodyne::parse_nmea(text)) {
    check_in_range(*fix);
    check_round_trip(*fix, 1'234'567'890U, PpsStatus::kLocked);
  }
  if (size != stac::velodyne::kPositionPacketSize) {  // the text in a VLP-16's packet
    std::array<std::uint8_t, stac::velodyne::kPositionPacketSize> payload{};
    std::memcpy(payload.data() + 206, data, std::min(size, stac::velodyne::kNmeaMaxLength));
    payload[202] = static_cast<std::uint8_t>(PpsStatus::kLocked);
    check_packet(stac::velodyne::parse_position_packet(payload));
  }
  return 0;
}
