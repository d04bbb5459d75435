#include "drivers/velodyne/status.hpp"

#include <cmath>
#include <cstring>
#include <numbers>
#include <string>

#include "drivers/velodyne/packet.hpp"

namespace stac::velodyne {
namespace {

constexpr std::array<std::uint8_t, kStatusTypedBytes> kTypedOrder{'H', 'M', 'S', 'D', 'N',
                                                                  'Y', 'G', 'T', 'V'};
constexpr char kUnit[] = "UNIT#";
constexpr std::size_t kLaserRecords = 7;              // first laser record in the dump
constexpr std::size_t kLaserRecordSize = 28;          // 4 cycles per laser; 21 bytes used
constexpr std::size_t kTail = kStatusDumpBytes - 28;  // date, humidity, unit parameters, checksum
constexpr double kDegToRad = std::numbers::pi / 180.0;
// Scales of the laser record fields (REFERENCE §1): angles in 0.01 deg, lengths in 0.1 cm (mm),
// the focal slope in 0.1. valgur/velodyne_decoder reads the focal slope in 0.001 instead; the
// S3 manual and velodyne-rs say 0.1, which gives the db.xml's usual values (0.4 .. 2.0).
constexpr double kAngleUnitDeg = 0.01;
constexpr double kLengthUnitM = 0.001;
constexpr double kFocalSlopeUnit = 0.1;

bool is_typed(std::uint8_t type) noexcept {
  for (std::uint8_t t : kTypedOrder) {
    if (t == type) return true;
  }
  return false;
}

std::int16_t load_i16(const std::uint8_t* p) noexcept {
  return static_cast<std::int16_t>(load_u16(p));
}

bool valid_date_time(const DateTime& t) noexcept {
  return t.month >= 1 && t.month <= 12 && t.day >= 1 && t.day <= 31 && t.hour >= 0 && t.hour < 24 &&
         t.minute >= 0 && t.minute < 60 && t.second >= 0 && t.second < 60;
}

GpsState gps_state(std::uint8_t raw) noexcept {
  switch (raw) {
    case 0:
      return GpsState::kNone;
    case 'A':
      return GpsState::kPpsAndNmea;
    case 'V':
      return GpsState::kNmeaOnly;
    case 'P':
      return GpsState::kPpsOnly;
    default:
      return GpsState::kUnknown;
  }
}

std::uint16_t checksum_of(const std::array<std::uint8_t, kStatusDumpBytes>& dump) noexcept {
  // CRC over bytes 1..20 of every laser record (the id excluded), as the S3 computes it.
  std::array<std::uint8_t, std::size_t{kMaxLasers} * 20> records{};
  for (int i = 0; i < kMaxLasers; ++i) {
    std::memcpy(records.data() + static_cast<std::size_t>(i) * 20,
                dump.data() + kLaserRecords + i * kLaserRecordSize + 1, 20);
  }
  return crc16_8005(records);
}

// Days since 1970-01-01 of a civil date (proleptic Gregorian).
std::int64_t days_from_civil(int y, int m, int d) noexcept {
  y -= m <= 2 ? 1 : 0;
  const int era = (y >= 0 ? y : y - 399) / 400;
  const int yoe = y - era * 400;
  const int doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
  const int doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  return static_cast<std::int64_t>(era) * 146097 + doe - 719468;
}

// The type byte of data byte `index` (0..6) of dump cycle `cycle`, as an S3 sends them
// (SkoltechRobotics/velodyne-rs); the S2.1 sends no 'W' bytes. The decoder does not rely on them.
std::uint8_t data_type(Model model, int cycle, int index) noexcept {
  static constexpr std::array<std::uint8_t, 7> kPlain{'1', '2', '3', '4', '5', '6', '7'};
  static constexpr std::array<std::uint8_t, 7> kFirst{'1', '2', '3', '4', '5', 0xF7, 0xF6};
  static constexpr std::array<std::uint8_t, 7> kState0{0xFE, 0xFF, 0xFC, 0xFD, 0xFA, 0xFB, 0x37};
  static constexpr std::array<std::uint8_t, 7> kState2{0x31, 0x32, 0xF9, 0x34, 0xF8, 0x36, 0x37};
  const auto i = static_cast<std::size_t>(index);
  if (cycle == 0) return kFirst[i];
  if (cycle == kStatusDumpCycles - 3) return kState0[i];
  if (cycle == kStatusDumpCycles - 1) return kState2[i];
  const bool warning_cycle = cycle >= 1 && cycle < kStatusDumpCycles - 4 && (cycle - 1) % 4 == 3;
  if (warning_cycle && index == 0 && traits(model).supports_dual_return) return 'W';
  return kPlain[i];
}

}  // namespace

const char* to_string(GpsState s) noexcept {
  switch (s) {
    case GpsState::kNone:
      return "none";
    case GpsState::kPpsAndNmea:
      return "PPS+NMEA";
    case GpsState::kNmeaOnly:
      return "NMEA only";
    case GpsState::kPpsOnly:
      return "PPS only";
    case GpsState::kUnknown:
      break;
  }
  return "unknown";
}

const char* to_string(ReturnMode m) noexcept {
  switch (m) {
    case ReturnMode::kStrongest:
      return "strongest";
    case ReturnMode::kLast:
      return "last";
    case ReturnMode::kDual:
      return "dual";
    case ReturnMode::kUnknown:
      break;
  }
  return "unknown";
}

std::uint16_t crc16_8005(std::span<const std::uint8_t> bytes) noexcept {
  std::uint16_t crc = 0;
  for (std::uint8_t b : bytes) {
    crc = static_cast<std::uint16_t>(crc ^ (b << 8));
    for (int bit = 0; bit < 8; ++bit) {
      crc = (crc & 0x8000) != 0 ? static_cast<std::uint16_t>((crc << 1) ^ 0x8005)
                                : static_cast<std::uint16_t>(crc << 1);
    }
  }
  return crc;
}

void StatusDecoder::add(std::uint8_t type, std::uint8_t value) noexcept {
  ++counters_.packets;
  if (position_ < 0) {  // waiting for the start of a cycle
    if (type != 'H') return;
    position_ = 0;
  }
  const bool expected = position_ < kStatusTypedBytes
                            ? type == kTypedOrder[static_cast<std::size_t>(position_)]
                            : !is_typed(type);
  if (!expected) {
    ++counters_.out_of_sequence;
    if (dump_len_ > 0) ++counters_.dumps_broken;
    dump_len_ = 0;
    position_ = -1;
    if (type == 'H')
      position_ = 0;  // a new cycle starts here
    else
      return;
  }
  if (position_ < kStatusTypedBytes) {
    typed_[static_cast<std::size_t>(position_)] = value;
    if (++position_ == kStatusTypedBytes) {
      SensorStatus s;
      s.time = {2000 + typed_[5], typed_[4], typed_[3], typed_[0], typed_[1], typed_[2]};
      s.valid = valid_date_time(s.time);
      s.gps_raw = typed_[6];
      s.gps = gps_state(typed_[6]);
      s.temperature_c = typed_[7];
      s.firmware = typed_[8];
      sensor_ = s;
    }
    return;
  }
  data_[static_cast<std::size_t>(position_ - kStatusTypedBytes)] = value;
  if (type == 'W') {
    w_byte_ = value;
    have_w_ = true;
  }
  if (++position_ == kStatusCyclePackets) {
    position_ = 0;
    finish_cycle();
  }
}

void StatusDecoder::finish_cycle() noexcept {
  ++counters_.cycles;
  if (dump_len_ == 0 && std::memcmp(data_.data(), kUnit, 5) != 0) return;  // not at a dump's start
  std::memcpy(dump_.data() + dump_len_, data_.data(), kStatusDataBytes);
  dump_len_ += kStatusDataBytes;
  if (dump_len_ == kStatusDumpBytes) {
    finish_dump();
    dump_len_ = 0;
  }
}

void StatusDecoder::finish_dump() noexcept {
  for (int i = 0; i < kMaxLasers; ++i) {
    if (dump_[static_cast<std::size_t>(kLaserRecords + i * kLaserRecordSize)] != i) {
      ++counters_.bad_layout;
      return;
    }
  }
  const std::uint8_t* tail = dump_.data() + kTail;
  const std::uint16_t stored = load_u16(tail + 26);
  const std::uint16_t crc = checksum_of(dump_);
  const bool crc_ok = stored == crc;
  // The S3 carries a CRC; the S2.1 writes the dump length there (valgur/velodyne_decoder).
  const bool ok = traits(model_).supports_dual_return
                      ? crc_ok
                      : crc_ok || stored == static_cast<std::uint16_t>(kStatusDumpBytes);
  if (!ok) {
    ++counters_.bad_checksum;
    return;
  }
  if (!crc_ok) {  // S2.1: no CRC, so the same bytes twice in a row before they are used
    if (!have_candidate_ || candidate_ != dump_) {
      candidate_ = dump_;
      have_candidate_ = true;
      ++counters_.unconfirmed;
      return;
    }
  }
  for (int i = 0; i < kMaxLasers; ++i) {
    const std::uint8_t* r = dump_.data() + kLaserRecords + i * kLaserRecordSize;
    LaserCalibration& l = lasers_[static_cast<std::size_t>(i)];
    l.laser_id = i;
    l.vert_correction_rad = load_i16(r + 1) * kAngleUnitDeg * kDegToRad;
    l.rot_correction_rad = load_i16(r + 3) * kAngleUnitDeg * kDegToRad;
    l.dist_correction_m = load_i16(r + 5) * kLengthUnitM;
    l.dist_correction_x_m = load_i16(r + 7) * kLengthUnitM;
    l.dist_correction_y_m = load_i16(r + 9) * kLengthUnitM;
    l.vert_offset_m = load_i16(r + 11) * kLengthUnitM;
    l.horiz_offset_m = load_i16(r + 13) * kLengthUnitM;
    l.focal_distance_m = load_i16(r + 15) * kLengthUnitM;
    l.focal_slope = load_i16(r + 17) * kFocalSlopeUnit;
    l.min_intensity = r[19];
    l.max_intensity = r[20];
    l.two_pt_correction_available = l.dist_correction_x_m != 0.0 || l.dist_correction_y_m != 0.0;
    l.enabled = true;
  }
  UnitParameters u;
  u.upper_noise_threshold = dump_[5];
  u.lower_noise_threshold = dump_[6];
  const DateTime date{2000 + tail[0], tail[1], tail[2], tail[3], tail[4], tail[5]};
  bool unset = true;
  for (int i = 0; i < 6; ++i) unset = unset && tail[i] == 0xFF;
  if (!unset && valid_date_time(date)) u.calibration_date = date;
  u.humidity = tail[6];
  u.rpm = load_u16(tail + 7);
  u.fov_start = load_u16(tail + 9);
  u.fov_end = load_u16(tail + 11);
  u.run_hours = load_u16(tail + 13);
  std::memcpy(u.ip_source.data(), tail + 15, 4);
  std::memcpy(u.ip_destination.data(), tail + 19, 4);
  u.return_mode = tail[23] <= 2 ? static_cast<ReturnMode>(tail[23]) : ReturnMode::kUnknown;
  u.warnings = have_w_ ? w_byte_ : tail[24];
  u.power_level = tail[25];
  u.crc_checked = crc_ok;
  unit_ = u;
  ++counters_.dumps;
}

rt::Result<Calibration> StatusDecoder::calibration() const {
  if (!has_calibration()) {
    return rt::make_error(
        "no complete calibration in the status bytes yet: an S2.1/S3 sends one every 4160 "
        "packets (1.2 s), and it needs an unbroken run of them, an S2.1's twice the same (" +
        std::to_string(counters_.packets) + " packets seen, " +
        std::to_string(counters_.dumps_broken) + " dumps broken by lost or reordered packets, " +
        std::to_string(counters_.bad_checksum) + " with a bad checksum, " +
        std::to_string(counters_.unconfirmed) + " S2.1 dumps not yet confirmed by the next)");
  }
  Calibration c;
  c.lasers = lasers_;
  c.num_lasers = kMaxLasers;
  c.distance_resolution_m = 0.002;
  c.source = "status stream";
  if (auto ok = check_calibration(c); !ok) return rt::Unexpected<rt::Error>{ok.error()};
  return c;
}

std::optional<std::int64_t> resolve_past_hour_ns(std::uint32_t usec_past_hour,
                                                 std::int64_t reference_ns) noexcept {
  constexpr std::int64_t kHourNs = 3'600'000'000'000;
  if (usec_past_hour >= 3'600'000'000U) return std::nullopt;
  const std::int64_t hour =
      reference_ns >= 0 ? reference_ns / kHourNs : (reference_ns + 1) / kHourNs - 1;
  const std::int64_t t = hour * kHourNs + static_cast<std::int64_t>(usec_past_hour) * 1000;
  if (t - reference_ns > kHourNs / 2) return t - kHourNs;  // still the previous hour
  if (reference_ns - t > kHourNs / 2) return t + kHourNs;  // already the next hour
  return t;
}

std::optional<std::int64_t> utc_time_ns(const SensorStatus& status,
                                        std::uint32_t usec_past_hour) noexcept {
  if (!status.valid) return std::nullopt;
  const DateTime& t = status.time;
  const std::int64_t cycle_s = days_from_civil(t.year, t.month, t.day) * 86400 +
                               std::int64_t{t.hour} * 3600 + std::int64_t{t.minute} * 60 + t.second;
  return resolve_past_hour_ns(usec_past_hour, cycle_s * 1'000'000'000);
}

StatusByte typed_status_byte(int position, const SensorStatus& s) noexcept {
  const auto u8 = [](int v) { return static_cast<std::uint8_t>(v & 0xFF); };
  std::uint8_t value = 0;
  switch (position) {
    case 0:
      value = u8(s.time.hour);
      break;
    case 1:
      value = u8(s.time.minute);
      break;
    case 2:
      value = u8(s.time.second);
      break;
    case 3:
      value = u8(s.time.day);
      break;
    case 4:
      value = u8(s.time.month);
      break;
    case 5:
      value = u8(s.time.year - 2000);
      break;
    case 6:
      value = s.gps_raw;
      break;
    case 7:
      value = u8(s.temperature_c);
      break;
    default:
      value = s.firmware;
      break;
  }
  return {kTypedOrder[static_cast<std::size_t>(position)], value};
}

rt::Status encode_status_sequence(Model model, const SensorStatus& status,
                                  const UnitParameters& unit, const Calibration& calibration,
                                  std::span<StatusByte, kStatusDumpPackets> out) {
  std::array<std::uint8_t, kStatusDumpBytes> dump{};
  std::memcpy(dump.data(), kUnit, 5);
  dump[5] = unit.upper_noise_threshold;
  dump[6] = unit.lower_noise_threshold;
  if (calibration.num_lasers != kMaxLasers) {
    return rt::make_error(calibration.source + ": the status dump carries 64 lasers, not " +
                          std::to_string(calibration.num_lasers));
  }
  for (int i = 0; i < kMaxLasers; ++i) {
    const LaserCalibration& l = calibration.lasers[static_cast<std::size_t>(i)];
    std::uint8_t* r = dump.data() + kLaserRecords + i * kLaserRecordSize;
    r[0] = static_cast<std::uint8_t>(i);
    struct Field {
      const char* name;
      double value, unit;
      int offset;
    };
    const Field fields[] = {
        {"vert_correction", l.vert_correction_rad / kDegToRad, kAngleUnitDeg, 1},
        {"rot_correction", l.rot_correction_rad / kDegToRad, kAngleUnitDeg, 3},
        {"dist_correction", l.dist_correction_m, kLengthUnitM, 5},
        {"dist_correction_x", l.dist_correction_x_m, kLengthUnitM, 7},
        {"dist_correction_y", l.dist_correction_y_m, kLengthUnitM, 9},
        {"vert_offset_correction", l.vert_offset_m, kLengthUnitM, 11},
        {"horiz_offset_correction", l.horiz_offset_m, kLengthUnitM, 13},
        {"focal_distance", l.focal_distance_m, kLengthUnitM, 15},
        {"focal_slope", l.focal_slope, kFocalSlopeUnit, 17},
    };
    for (const Field& f : fields) {
      const double q = std::round(f.value / f.unit);
      if (!(q >= -32768 && q <= 32767)) {
        return rt::make_error(calibration.source + ": laser " + std::to_string(i) + ": '" + f.name +
                              "' = " + std::to_string(f.value) +
                              " does not fit the status dump's 16-bit field");
      }
      store_u16(r + f.offset, static_cast<std::uint16_t>(static_cast<std::int16_t>(q)));
    }
    r[19] = static_cast<std::uint8_t>(l.min_intensity);
    r[20] = static_cast<std::uint8_t>(l.max_intensity);
    // The S3's 'W' byte (the S2.1 leaves it unused); laser 63 has no warning cycle.
    if (i < kMaxLasers - 1) r[21] = unit.warnings;
  }
  std::uint8_t* tail = dump.data() + kTail;
  if (unit.calibration_date) {
    const DateTime& d = *unit.calibration_date;
    const int date[6] = {d.year - 2000, d.month, d.day, d.hour, d.minute, d.second};
    for (int i = 0; i < 6; ++i) tail[i] = static_cast<std::uint8_t>(date[i]);
  } else {
    std::memset(tail, 0xFF, 6);
  }
  tail[6] = unit.humidity;
  store_u16(tail + 7, unit.rpm);
  store_u16(tail + 9, unit.fov_start);
  store_u16(tail + 11, unit.fov_end);
  store_u16(tail + 13, unit.run_hours);
  std::memcpy(tail + 15, unit.ip_source.data(), 4);
  std::memcpy(tail + 19, unit.ip_destination.data(), 4);
  tail[23] = static_cast<std::uint8_t>(unit.return_mode);
  tail[24] = unit.warnings;
  tail[25] = unit.power_level;
  const bool s3 = traits(model).supports_dual_return;
  store_u16(tail + 26, s3 ? checksum_of(dump) : static_cast<std::uint16_t>(kStatusDumpBytes));

  for (int k = 0; k < kStatusDumpPackets; ++k) {
    const int cycle = k / kStatusCyclePackets, p = k % kStatusCyclePackets;
    if (p < kStatusTypedBytes) {
      out[static_cast<std::size_t>(k)] = typed_status_byte(p, status);
    } else {
      const int index = p - kStatusTypedBytes;
      out[static_cast<std::size_t>(k)] = {data_type(model, cycle, index),
                                          dump[static_cast<std::size_t>(cycle) * kStatusDataBytes +
                                               static_cast<std::size_t>(index)]};
    }
  }
  return {};
}

DateTime utc_date_time(std::int64_t utc_ns) noexcept {
  const std::int64_t s = utc_ns >= 0 ? utc_ns / 1'000'000'000 : (utc_ns + 1) / 1'000'000'000 - 1;
  std::int64_t z = (s >= 0 ? s : s - 86399) / 86400;  // days since 1970
  const auto sod = static_cast<int>(s - z * 86400);
  z += 719468;  // civil_from_days (proleptic Gregorian)
  const std::int64_t era = (z >= 0 ? z : z - 146096) / 146097;
  const auto doe = static_cast<int>(z - era * 146097);
  const int yoe = (doe - doe / 1460 + doe / 36524 - doe / 146096) / 365;
  const int doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
  const int mp = (5 * doy + 2) / 153;
  const int day = doy - (153 * mp + 2) / 5 + 1;
  const int month = mp < 10 ? mp + 3 : mp - 9;
  const auto year = static_cast<int>(yoe + era * 400 + (month <= 2 ? 1 : 0));
  return {year, month, day, sod / 3600, sod / 60 % 60, sod % 60};
}

rt::Result<StatusTrailerWriter> StatusTrailerWriter::create(Model model, const SensorStatus& status,
                                                            const UnitParameters& unit,
                                                            const Calibration& calibration) {
  StatusTrailerWriter w;
  w.sequence_.resize(kStatusDumpPackets);
  w.status_ = status;
  auto ok = encode_status_sequence(model, status, unit, calibration,
                                   std::span<StatusByte, kStatusDumpPackets>(w.sequence_));
  if (!ok) return rt::Unexpected<rt::Error>{ok.error()};
  return w;
}

void StatusTrailerWriter::write(std::uint8_t* trailer, std::int64_t utc_ns) noexcept {
  const auto k = static_cast<std::size_t>(next_++ % kStatusDumpPackets);
  const int position = static_cast<int>(k % kStatusCyclePackets);
  if (position == 0) status_.time = utc_date_time(utc_ns);
  const StatusByte b =
      position < kStatusTypedBytes ? typed_status_byte(position, status_) : sequence_[k];
  store_u32(trailer, usec_past_hour(utc_ns));
  trailer[4] = b.type;
  trailer[5] = b.value;
}

}  // namespace stac::velodyne
