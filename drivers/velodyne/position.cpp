#include "drivers/velodyne/position.hpp"

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <limits>

#include "drivers/velodyne/packet.hpp"

namespace stac::velodyne {
namespace {

// The payload as the manuals draw it (position.hpp has the sources).
#pragma pack(push, 1)
struct RawPositionPacket {
  std::uint8_t reserved_0[14];
  std::uint8_t hdl32e_motion[24];  // HDL-32E: 3 x {gyro, temperature, accel x, accel y}, u16 each
  std::uint8_t reserved_38[160];
  std::uint8_t usec_past_hour[4];  // u32
  std::uint8_t pps_status;
  std::uint8_t reserved_203[3];
  char nmea[kNmeaMaxLength];  // CR LF terminated, NUL padded
  std::uint8_t reserved_334[178];
};
#pragma pack(pop)
static_assert(sizeof(RawPositionPacket) == kPositionPacketSize);
static_assert(offsetof(RawPositionPacket, hdl32e_motion) == 14);
static_assert(offsetof(RawPositionPacket, usec_past_hour) == 198);
static_assert(offsetof(RawPositionPacket, pps_status) == 202);
static_assert(offsetof(RawPositionPacket, nmea) == 206);

constexpr double kKnotToMps = 1852.0 / 3600.0;  // 0.514444 (the knot is 1852 m per hour)
constexpr double kMaxSpeedKnots = 1000.0;       // receivers stop reporting above (COCOM limit)
constexpr std::int64_t kSecondNs = 1'000'000'000;
constexpr std::int64_t kDayNs = 86'400 * kSecondNs;
constexpr std::uint32_t kUsecPerHour = 3'600'000'000U;
constexpr int kMaxFractionDigits = 9;  // more are read but ignored (below 1 ns, 1e-9 knots)
constexpr std::uint64_t kHugeInteger =
    100'000'000'000'000;                   // an integer part this big: out of range
constexpr std::size_t kMaxFields = 24;     // data fields after the address (GGA has 14)
constexpr std::size_t kRmcFields = 9;      // time, status, lat, N/S, lon, E/W, speed, course, date
constexpr std::size_t kRmcModeField = 11;  // NMEA 2.3 mode indicator ('N' = not valid)
constexpr std::size_t kGgaFields = 6;      // time, lat, N/S, lon, E/W, quality
constexpr int kFirstYear = 1980;           // RMC's two-digit year covers 1980..2079
// HDL-32E motion scales (VeloView; kaarta/velodyne): 12-bit two's complement raw values.
constexpr double kGyroDegPerS = 0.09766;
constexpr double kTemperatureC = 0.1453;
constexpr double kTemperatureOffsetC = 25.0;
constexpr double kAccelG = 0.001221;

using Step = rt::Expected<void, PositionError>;
using Failure = rt::Unexpected<PositionError>;

bool is_digit(char c) noexcept {
  return c >= '0' && c <= '9';
}
bool is_upper(char c) noexcept {
  return c >= 'A' && c <= 'Z';
}

bool all_digits(std::string_view s) noexcept {
  for (char c : s) {
    if (!is_digit(c)) return false;
  }
  return !s.empty();
}

int digits_value(std::string_view s) noexcept {  // s: a few digits, checked by the caller
  int v = 0;
  for (char c : s) v = v * 10 + (c - '0');
  return v;
}

int hex_value(char c) noexcept {
  if (is_digit(c)) return c - '0';
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  return -1;
}

constexpr std::array<double, kMaxFractionDigits + 1> kPow10{1e0, 1e1, 1e2, 1e3, 1e4,
                                                            1e5, 1e6, 1e7, 1e8, 1e9};

// An unsigned decimal "d+[.d+]" (no sign, exponent, "nan" or "inf"), read without allocating.
struct Decimal {
  std::uint64_t integer = 0;
  std::uint64_t fraction = 0;  // the first kMaxFractionDigits digits
  int fraction_digits = 0;
  bool huge = false;  // integer part >= 1e15: out of any range here
  double value() const noexcept {
    if (huge) return std::numeric_limits<double>::infinity();
    return static_cast<double>(integer) +
           static_cast<double>(fraction) / kPow10[static_cast<std::size_t>(fraction_digits)];
  }
};

std::optional<Decimal> parse_decimal(std::string_view s) noexcept {
  Decimal d;
  std::size_t i = 0;
  for (; i < s.size() && is_digit(s[i]); ++i) {
    if (d.integer >= kHugeInteger)
      d.huge = true;
    else
      d.integer = d.integer * 10 + static_cast<std::uint64_t>(s[i] - '0');
  }
  if (i == 0) return std::nullopt;
  if (i == s.size()) return d;
  if (s[i] != '.' || i + 1 == s.size()) return std::nullopt;
  for (++i; i < s.size(); ++i) {
    if (!is_digit(s[i])) return std::nullopt;
    if (d.fraction_digits < kMaxFractionDigits) {
      d.fraction = d.fraction * 10 + static_cast<std::uint64_t>(s[i] - '0');
      ++d.fraction_digits;
    }
  }
  return d;
}

bool valid_date(const NmeaDate& d) noexcept {
  if (d.year < kFirstYear || d.year >= kFirstYear + 100) return false;
  if (d.month < 1 || d.month > 12 || d.day < 1 || d.day > 31) return false;
  const std::chrono::year_month_day ymd{std::chrono::year{d.year},
                                        std::chrono::month{static_cast<unsigned>(d.month)},
                                        std::chrono::day{static_cast<unsigned>(d.day)}};
  return ymd.ok();
}

// "hhmmss[.s+]"; empty leaves `out` empty. 23:59:60 is a leap second.
Step parse_time(std::string_view s, std::optional<std::int64_t>& out) noexcept {
  if (s.empty()) return {};
  if (s.size() < 6 || !all_digits(s.substr(0, 6))) return Failure{PositionError::kMalformedField};
  std::int64_t fraction_ns = 0;
  if (s.size() > 6) {
    if (s[6] != '.') return Failure{PositionError::kMalformedField};
    const auto fraction = parse_decimal(s.substr(5));  // "s.fff": the last second digit and more
    if (!fraction) return Failure{PositionError::kMalformedField};
    fraction_ns =
        static_cast<std::int64_t>(fraction->fraction) *
        static_cast<std::int64_t>(
            kPow10[static_cast<std::size_t>(kMaxFractionDigits - fraction->fraction_digits)]);
  }
  const int h = digits_value(s.substr(0, 2)), m = digits_value(s.substr(2, 2)),
            sec = digits_value(s.substr(4, 2));
  const bool leap_second = h == 23 && m == 59 && sec == 60;
  if (h > 23 || m > 59 || (sec > 59 && !leap_second)) return Failure{PositionError::kOutOfRange};
  out = ((std::int64_t{h} * 60 + m) * 60 + sec) * kSecondNs + fraction_ns;
  return {};
}

// "ddmm.m+" (latitude, max_degree_digits 2) or "dddmm.m+" (longitude, 3) and its hemisphere
// letter; both empty leaves `out` empty.
Step parse_angle(std::string_view value, std::string_view hemisphere, std::size_t max_degree_digits,
                 char positive, char negative, double limit_deg,
                 std::optional<double>& out) noexcept {
  if (value.empty() && hemisphere.empty()) return {};
  if (value.empty() || hemisphere.size() != 1 ||
      (hemisphere[0] != positive && hemisphere[0] != negative) || !parse_decimal(value)) {
    return Failure{PositionError::kMalformedField};
  }
  const std::size_t integer_digits = std::min(value.find('.'), value.size());
  if (integer_digits < 3 || integer_digits > max_degree_digits + 2) {
    return Failure{PositionError::kMalformedField};
  }
  const int degrees = digits_value(value.substr(0, integer_digits - 2));
  const double minutes = parse_decimal(value.substr(integer_digits - 2))->value();
  const double angle = degrees + minutes / 60.0;
  if (minutes >= 60.0 || angle > limit_deg) return Failure{PositionError::kOutOfRange};
  out = hemisphere[0] == negative ? -angle : angle;
  return {};
}

// A non-negative decimal no larger than `limit`, scaled; empty leaves `out` empty.
Step parse_bounded(std::string_view s, double limit, double scale,
                   std::optional<double>& out) noexcept {
  if (s.empty()) return {};
  const auto d = parse_decimal(s);
  if (!d) return Failure{PositionError::kMalformedField};
  const double v = d->value();
  if (v > limit) return Failure{PositionError::kOutOfRange};
  out = v * scale;
  return {};
}

// "ddmmyy"; empty leaves `out` empty.
Step parse_date(std::string_view s, std::optional<NmeaDate>& out) noexcept {
  if (s.empty()) return {};
  if (s.size() != 6 || !all_digits(s)) return Failure{PositionError::kMalformedField};
  const int yy = digits_value(s.substr(4, 2));
  const NmeaDate d{yy + (yy >= kFirstYear % 100 ? 1900 : 2000), digits_value(s.substr(2, 2)),
                   digits_value(s.substr(0, 2))};
  if (!valid_date(d)) return Failure{PositionError::kOutOfRange};
  out = d;
  return {};
}

struct Fields {
  std::array<std::string_view, kMaxFields + 1> at{};  // [0] = address ("GPRMC")
  std::size_t count = 0;                              // data fields, after the address
  std::string_view data(std::size_t i) const noexcept { return i < count ? at[i + 1] : ""; }
};

// "$" body "*hh": the body split at commas, and whether the checksum matches.
rt::Expected<Fields, PositionError> split_sentence(std::string_view s, bool& checksum_ok) noexcept {
  while (!s.empty() && (s.back() == '\n' || s.back() == '\r')) s.remove_suffix(1);
  if (s.empty() || s[0] != '$') return Failure{PositionError::kNoSentence};
  const std::size_t star = s.find('*');
  if (star == std::string_view::npos) return Failure{PositionError::kTruncated};
  const std::string_view body = s.substr(1, star - 1), tail = s.substr(star + 1);
  if (tail.size() < 2) return Failure{PositionError::kTruncated};
  if (tail.size() > 2 || hex_value(tail[0]) < 0 || hex_value(tail[1]) < 0) {
    return Failure{PositionError::kMalformedField};
  }
  unsigned sum = 0;
  for (char c : body) {
    const auto u = static_cast<unsigned char>(c);
    if (u < 0x20 || u > 0x7E || c == '$') return Failure{PositionError::kMalformedField};
    sum ^= u;
  }
  checksum_ok = sum == static_cast<unsigned>(hex_value(tail[0]) * 16 + hex_value(tail[1]));
  Fields f;
  std::size_t start = 0, n = 0;
  for (;;) {
    const std::size_t comma = body.find(',', start);
    if (n == f.at.size()) return Failure{PositionError::kMalformedField};  // too many fields
    f.at[n++] =
        body.substr(start, comma == std::string_view::npos ? body.size() - start : comma - start);
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  f.count = n - 1;
  return f;
}

// Latitude, N/S, longitude, E/W from data field `first` on.
Step parse_position(const Fields& f, std::size_t first, NmeaFix& fix) noexcept {
  if (auto ok = parse_angle(f.data(first), f.data(first + 1), 2, 'N', 'S', 90.0, fix.latitude_deg);
      !ok) {
    return ok;
  }
  return parse_angle(f.data(first + 2), f.data(first + 3), 3, 'E', 'W', 180.0, fix.longitude_deg);
}

Step parse_rmc(const Fields& f, NmeaFix& fix) noexcept {
  if (f.count < kRmcFields) return Failure{PositionError::kTruncated};
  const std::string_view status = f.data(1), mode = f.data(kRmcModeField);
  if (status.size() > 1 || (status.size() == 1 && status != "A" && status != "V")) {
    return Failure{PositionError::kMalformedField};
  }
  fix.valid = status == "A" && mode != "N";
  Step ok = parse_time(f.data(0), fix.time_of_day_ns);
  if (ok) ok = parse_position(f, 2, fix);
  if (ok) ok = parse_bounded(f.data(6), kMaxSpeedKnots, kKnotToMps, fix.speed_mps);
  if (ok) ok = parse_bounded(f.data(7), 360.0, 1.0, fix.course_deg);
  if (ok) ok = parse_date(f.data(8), fix.date);
  return ok;
}

Step parse_gga(const Fields& f, NmeaFix& fix) noexcept {
  if (f.count < kGgaFields) return Failure{PositionError::kTruncated};
  const std::string_view quality = f.data(5);
  if (!quality.empty() && !all_digits(quality)) return Failure{PositionError::kMalformedField};
  if (quality.size() > 1) return Failure{PositionError::kOutOfRange};
  fix.gga_quality = static_cast<std::uint8_t>(quality.empty() ? 0 : quality[0] - '0');
  fix.valid = fix.gga_quality > 0;
  Step ok = parse_time(f.data(0), fix.time_of_day_ns);
  if (ok) ok = parse_position(f, 1, fix);
  return ok;
}

rt::Expected<NmeaFix, PositionError> parse_sentence(std::string_view s,
                                                    bool require_checksum) noexcept {
  NmeaFix fix;
  auto fields = split_sentence(s, fix.checksum_ok);
  if (!fields) return Failure{fields.error()};
  if (require_checksum && !fix.checksum_ok) return Failure{PositionError::kBadChecksum};
  const std::string_view address = fields->at[0];
  if (address.size() != 5 || !is_upper(address[0]) || !is_upper(address[1])) {
    return Failure{PositionError::kUnsupportedSentence};
  }
  fix.talker = {address[0], address[1]};
  Step ok;
  if (address.substr(2) == "RMC") {
    fix.sentence = NmeaSentence::kRmc;
    ok = parse_rmc(*fields, fix);
  } else if (address.substr(2) == "GGA") {
    fix.sentence = NmeaSentence::kGga;
    ok = parse_gga(*fields, fix);
  } else {
    return Failure{PositionError::kUnsupportedSentence};
  }
  if (!ok) return Failure{ok.error()};
  return fix;
}

int twelve_bit(std::uint16_t raw) noexcept {
  const int v = raw & 0x0FFF;
  return (v & 0x0800) != 0 ? v - 0x1000 : v;
}

// Appends to a fixed buffer; writing past its end is counted, not done.
class TextWriter {
 public:
  explicit TextWriter(std::span<char> out) noexcept : out_(out) {}
  void put(char c) noexcept {
    if (size_ < out_.size()) out_[size_] = c;
    ++size_;
  }
  void put(std::string_view s) noexcept {
    for (char c : s) put(c);
  }
  void put_uint(std::uint64_t v, int min_width) noexcept {  // zero-padded
    std::array<char, 20> digits{};
    const auto end = std::to_chars(digits.data(), digits.data() + digits.size(), v).ptr;
    for (auto n = static_cast<int>(end - digits.data()); n < min_width; ++n) put('0');
    put(std::string_view(digits.data(), static_cast<std::size_t>(end - digits.data())));
  }
  void put_fixed(std::uint64_t scaled, int min_integer_width, int decimals) noexcept {
    const auto unit = static_cast<std::uint64_t>(kPow10[static_cast<std::size_t>(decimals)]);
    put_uint(scaled / unit, min_integer_width);
    put('.');
    put_uint(scaled % unit, decimals);
  }
  std::size_t size() const noexcept { return size_; }
  bool overflowed() const noexcept { return size_ > out_.size(); }

 private:
  std::span<char> out_;
  std::size_t size_ = 0;
};

// `v` in units of 10^-decimals, rounded, when it is finite and in [0, limit]; else empty.
std::optional<std::uint64_t> scaled(double v, double limit, int decimals) noexcept {
  if (!(v >= 0.0 && v <= 2.0 * limit)) return std::nullopt;  // NaN fails too
  const double unit = kPow10[static_cast<std::size_t>(decimals)];
  const auto q = static_cast<std::uint64_t>(std::llround(v * unit));
  if (static_cast<double>(q) > limit * unit) return std::nullopt;
  return q;
}

constexpr int kMinuteDecimals = 6;

void put_angle(TextWriter& w, const std::optional<std::uint64_t>& micro_minutes, bool negative,
               int degree_width, char positive_letter, char negative_letter) noexcept {
  if (micro_minutes) {
    constexpr std::uint64_t kPerDegree = 60'000'000;
    w.put_uint(*micro_minutes / kPerDegree, degree_width);
    w.put_fixed(*micro_minutes % kPerDegree, 2, kMinuteDecimals);
    w.put(',');
    w.put(negative ? negative_letter : positive_letter);
  } else {
    w.put(',');
  }
  w.put(',');
}

}  // namespace

const char* to_string(PositionError e) noexcept {
  switch (e) {
    case PositionError::kWrongSize:
      return "position packet is not 512 bytes";
    case PositionError::kBadPpsStatus:
      return "PPS status byte is not 0..3";
    case PositionError::kNoSentence:
      return "no NMEA sentence";
    case PositionError::kTruncated:
      return "NMEA sentence truncated";
    case PositionError::kBadChecksum:
      return "NMEA checksum mismatch";
    case PositionError::kUnsupportedSentence:
      return "NMEA sentence is not RMC or GGA";
    case PositionError::kMalformedField:
      return "NMEA field malformed";
    case PositionError::kOutOfRange:
      return "value out of range";
  }
  return "unknown position error";
}

const char* to_string(PpsStatus s) noexcept {
  switch (s) {
    case PpsStatus::kAbsent:
      return "absent";
    case PpsStatus::kSynchronizing:
      return "synchronizing";
    case PpsStatus::kLocked:
      return "locked";
    case PpsStatus::kError:
      return "error";
  }
  return "unknown";
}

ParseResult parse_position_packet(std::span<const std::uint8_t> payload) noexcept {
  if (payload.size() != kPositionPacketSize) return Failure{PositionError::kWrongSize};
  RawPositionPacket raw{};
  std::memcpy(&raw, payload.data(), sizeof raw);
  if (raw.pps_status > static_cast<std::uint8_t>(PpsStatus::kError)) {
    return Failure{PositionError::kBadPpsStatus};
  }
  PositionPacket p;
  p.usec_past_hour = load_u32(raw.usec_past_hour);
  if (p.usec_past_hour >= kUsecPerHour) return Failure{PositionError::kOutOfRange};
  p.pps = static_cast<PpsStatus>(raw.pps_status);
  while (p.sentence_length < kNmeaMaxLength && raw.nmea[p.sentence_length] != '\0' &&
         raw.nmea[p.sentence_length] != '\r' && raw.nmea[p.sentence_length] != '\n') {
    p.sentence[p.sentence_length] = raw.nmea[p.sentence_length];
    ++p.sentence_length;
  }
  auto fix = parse_sentence(p.nmea(), /*require_checksum=*/true);
  if (!fix) return Failure{fix.error()};
  p.fix = *fix;
  return p;
}

std::optional<NmeaFix> parse_nmea(std::string_view sentence) noexcept {
  auto fix = parse_sentence(sentence, /*require_checksum=*/false);
  if (!fix) return std::nullopt;
  return *fix;
}

std::optional<std::int64_t> nmea_utc_ns(const NmeaFix& fix) noexcept {
  if (!fix.date || !fix.time_of_day_ns || !valid_date(*fix.date)) return std::nullopt;
  const std::int64_t tod = *fix.time_of_day_ns;
  if (tod < 0 || tod >= kDayNs + kSecondNs) return std::nullopt;  // a day and its leap second
  const std::chrono::year_month_day ymd{std::chrono::year{fix.date->year},
                                        std::chrono::month{static_cast<unsigned>(fix.date->month)},
                                        std::chrono::day{static_cast<unsigned>(fix.date->day)}};
  const std::int64_t days = std::chrono::sys_days{ymd}.time_since_epoch().count();
  return days * kDayNs + tod;
}

std::optional<Hdl32eMotion> parse_hdl32e_motion(std::span<const std::uint8_t> payload) noexcept {
  if (payload.size() != kPositionPacketSize) return std::nullopt;
  Hdl32eMotion m;
  for (std::size_t i = 0; i < 3; ++i) {
    const std::uint8_t* board = payload.data() + offsetof(RawPositionPacket, hdl32e_motion) + 8 * i;
    m.gyro_deg_per_s[i] = kGyroDegPerS * twelve_bit(load_u16(board));
    m.temperature_c[i] = kTemperatureC * twelve_bit(load_u16(board + 2)) + kTemperatureOffsetC;
    m.accel_x_g[i] = kAccelG * twelve_bit(load_u16(board + 4));
    m.accel_y_g[i] = kAccelG * twelve_bit(load_u16(board + 6));
  }
  return m;
}

rt::Expected<void, PositionError> write_position_packet(
    std::uint32_t usec_past_hour, PpsStatus pps, const NmeaFix& fix,
    std::span<std::uint8_t, kPositionPacketSize> out) noexcept {
  if (!is_upper(fix.talker[0]) || !is_upper(fix.talker[1]) ||
      (fix.sentence != NmeaSentence::kRmc && fix.sentence != NmeaSentence::kGga)) {
    return Failure{PositionError::kMalformedField};
  }
  const bool rmc = fix.sentence == NmeaSentence::kRmc;
  // Every value checked and scaled before anything is written.
  const bool bad_time =
      fix.time_of_day_ns && (*fix.time_of_day_ns < 0 || *fix.time_of_day_ns >= kDayNs);
  const bool bad_date = fix.date && !valid_date(*fix.date);
  std::optional<std::uint64_t> lat, lon, speed, course;
  if (fix.latitude_deg) {
    lat = scaled(std::abs(*fix.latitude_deg) * 60.0, 90.0 * 60.0, kMinuteDecimals);
  }
  if (fix.longitude_deg) {
    lon = scaled(std::abs(*fix.longitude_deg) * 60.0, 180.0 * 60.0, kMinuteDecimals);
  }
  if (fix.speed_mps) speed = scaled(*fix.speed_mps / kKnotToMps, kMaxSpeedKnots, 3);
  if (fix.course_deg) course = scaled(*fix.course_deg, 360.0, 2);
  if (usec_past_hour >= kUsecPerHour || pps > PpsStatus::kError || bad_time || bad_date ||
      fix.latitude_deg.has_value() != lat.has_value() ||
      fix.longitude_deg.has_value() != lon.has_value() ||
      (rmc && fix.speed_mps.has_value() != speed.has_value()) ||
      (rmc && fix.course_deg.has_value() != course.has_value()) || (!rmc && fix.gga_quality > 9)) {
    return Failure{PositionError::kOutOfRange};
  }

  RawPositionPacket raw{};
  TextWriter w(std::span<char>(raw.nmea, kNmeaMaxLength));
  w.put('$');
  w.put(std::string_view(fix.talker.data(), 2));
  w.put(rmc ? "RMC," : "GGA,");
  if (fix.time_of_day_ns) {
    const std::int64_t ms = *fix.time_of_day_ns / 1'000'000;  // truncated
    w.put_uint(static_cast<std::uint64_t>(ms / 3'600'000), 2);
    w.put_uint(static_cast<std::uint64_t>(ms / 60'000 % 60), 2);
    w.put_fixed(static_cast<std::uint64_t>(ms % 60'000), 2, 3);
  }
  w.put(',');
  if (rmc) w.put(fix.valid ? "A," : "V,");
  put_angle(w, lat, fix.latitude_deg && *fix.latitude_deg < 0, 2, 'N', 'S');
  put_angle(w, lon, fix.longitude_deg && *fix.longitude_deg < 0, 3, 'E', 'W');
  if (rmc) {
    if (speed) w.put_fixed(*speed, 3, 3);
    w.put(',');
    if (course) w.put_fixed(*course, 3, 2);
    w.put(',');
    if (fix.date) {
      w.put_uint(static_cast<std::uint64_t>(fix.date->day), 2);
      w.put_uint(static_cast<std::uint64_t>(fix.date->month), 2);
      w.put_uint(static_cast<std::uint64_t>(fix.date->year % 100), 2);
    }
    w.put(",,,");  // magnetic variation and its direction: not known
    w.put(fix.valid ? 'A' : 'N');
  } else {
    const int quality = fix.valid ? (fix.gga_quality > 0 ? fix.gga_quality : 1) : 0;
    w.put(static_cast<char>('0' + quality));
    w.put(",,,,,,,,");  // satellites, HDOP, altitude, M, geoid separation, M, age, station
  }
  unsigned sum = 0;
  for (std::size_t i = 1; i < w.size() && i < kNmeaMaxLength; ++i) {
    sum ^= static_cast<unsigned char>(raw.nmea[i]);
  }
  constexpr std::string_view kHex = "0123456789ABCDEF";
  w.put('*');
  w.put(kHex[(sum >> 4) & 0xF]);
  w.put(kHex[sum & 0xF]);
  w.put("\r\n");
  if (w.overflowed()) return Failure{PositionError::kOutOfRange};  // cannot happen: < 90 chars

  store_u32(raw.usec_past_hour, usec_past_hour);
  raw.pps_status = static_cast<std::uint8_t>(pps);
  std::memcpy(out.data(), &raw, sizeof raw);
  return {};
}

}  // namespace stac::velodyne
