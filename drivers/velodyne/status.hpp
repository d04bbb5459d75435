// The HDL-64E S2.1/S3 status cycle: the last two trailer bytes of every packet (type, value).
// REFERENCE §1; layout as read by valgur/velodyne_decoder and SkoltechRobotics/velodyne-rs.
//
// Every 16 packets: 9 typed bytes H M S D N Y G T V (GPS time and date, GPS state, temperature,
// firmware), then 7 data bytes. 260 cycles of data bytes (4160 packets, 1820 bytes) form the
// calibration dump: "UNIT#" + noise thresholds, 64 laser records, calibration date, unit
// parameters (RPM, FOV, IPs, return mode, power) and a checksum (S3: CRC-16 over the laser
// records; S2.1: the dump length 1820).
//
//   StatusDecoder status(Model::kS3);
//   for each packet: status.add(trailer[4], trailer[5]);    // no allocation, no exceptions
//   if (status.has_calibration()) use(status.calibration());  // allocates: start-up only
//
// A lost, duplicated or reordered packet breaks the cycle: the dump in progress is dropped and
// counted, and assembly resumes at the next "UNIT#" (a dump needs an unbroken 4160-packet run).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "drivers/velodyne/calibration.hpp"
#include "drivers/velodyne/model.hpp"
#include "rt/expected.hpp"

namespace stac::velodyne {

inline constexpr int kStatusCyclePackets = 16;
inline constexpr int kStatusTypedBytes = 9;  // H M S D N Y G T V
inline constexpr int kStatusDataBytes = 7;   // per cycle
inline constexpr int kStatusDumpCycles = 260;
inline constexpr int kStatusDumpBytes = kStatusDumpCycles * kStatusDataBytes;       // 1820
inline constexpr int kStatusDumpPackets = kStatusDumpCycles * kStatusCyclePackets;  // 4160

enum class GpsState : std::uint8_t { kNone, kPpsAndNmea, kNmeaOnly, kPpsOnly, kUnknown };
enum class ReturnMode : std::uint8_t { kStrongest = 0, kLast = 1, kDual = 2, kUnknown = 3 };
const char* to_string(GpsState s) noexcept;
const char* to_string(ReturnMode m) noexcept;

struct DateTime {  // UTC, as the sensor reports it from its GPS input (NMEA RMC)
  int year = 0, month = 0, day = 0, hour = 0, minute = 0, second = 0;
};

// The 9 typed bytes, refreshed every 16 packets.
struct SensorStatus {
  bool valid = false;  // a whole, in-order H..V sequence has been seen
  DateTime time;
  GpsState gps = GpsState::kUnknown;
  std::uint8_t gps_raw = 0;
  int temperature_c = 0;
  std::uint8_t firmware = 0;  // high nibble major, low nibble minor (0x47 = 4.07)
};

// What the calibration dump says besides the lasers, refreshed every 4160 packets.
struct UnitParameters {
  std::uint8_t upper_noise_threshold = 0, lower_noise_threshold = 0;
  std::optional<DateTime> calibration_date;  // absent when the unit sends 0xFF bytes
  std::uint8_t humidity = 0;
  std::uint16_t rpm = 0;
  std::uint16_t fov_start = 0, fov_end = 0;  // 0.01 deg
  std::uint16_t run_hours = 0;
  std::array<std::uint8_t, 4> ip_source{}, ip_destination{};
  ReturnMode return_mode = ReturnMode::kUnknown;
  std::uint8_t power_level = 0;  // 0xA8 auto normalised, 0xA0 auto raw, 0xN8 manual level N
  // Warning bits: 0 lens contaminated, 1 too hot, 2 too cold, 5 PPS present, 6 GPS time present
  // (S2.1 also 3 voltage low, 4 voltage high). S3 sends them as the 'W' bytes of the cycle.
  std::uint8_t warnings = 0;
  bool crc_checked = false;  // the dump carried a CRC-16 that matched (S3)
};

struct StatusCounters {
  std::uint64_t packets = 0;          // status bytes offered
  std::uint64_t cycles = 0;           // complete 16-packet cycles
  std::uint64_t out_of_sequence = 0;  // type byte not where the cycle puts it: resynchronised
  std::uint64_t dumps = 0;            // calibration dumps assembled and accepted
  std::uint64_t dumps_broken = 0;     // dumps in progress dropped by a broken cycle
  std::uint64_t bad_checksum = 0;     // complete dumps whose checksum did not match
  std::uint64_t bad_layout = 0;       // complete dumps whose laser ids were not 0..63
  // S2.1 dumps (no CRC: a flipped bit would pass) not yet seen twice in a row, byte for byte:
  // a dump is used only when the next one confirms it.
  std::uint64_t unconfirmed = 0;
};

class StatusDecoder {
 public:
  explicit StatusDecoder(Model model) noexcept : model_(model) {}

  // The status type and value bytes of one packet, in arrival order.
  void add(std::uint8_t type, std::uint8_t value) noexcept;

  const SensorStatus& sensor() const noexcept { return sensor_; }
  bool has_calibration() const noexcept { return counters_.dumps > 0; }
  const UnitParameters& unit() const noexcept { return unit_; }
  // The corrections of the last accepted dump, checked like a file's ("status stream" is its
  // source); an error saying why when no dump was accepted yet. Allocates: start-up only.
  rt::Result<Calibration> calibration() const;
  const StatusCounters& counters() const noexcept { return counters_; }

 private:
  void finish_cycle() noexcept;
  void finish_dump() noexcept;

  Model model_;
  int position_ = -1;  // position in the 16-packet cycle, -1 = waiting for 'H'
  std::array<std::uint8_t, kStatusTypedBytes> typed_{};
  std::array<std::uint8_t, kStatusDataBytes> data_{};
  std::uint8_t w_byte_ = 0;
  bool have_w_ = false;
  std::array<std::uint8_t, kStatusDumpBytes> dump_{};
  std::array<std::uint8_t, kStatusDumpBytes> candidate_{};  // the last unconfirmed S2.1 dump
  bool have_candidate_ = false;
  int dump_len_ = 0;
  SensorStatus sensor_;
  UnitParameters unit_;
  std::array<LaserCalibration, kMaxLasers> lasers_{};
  StatusCounters counters_;
};

// CRC-16 with polynomial 0x8005, initial value 0, no reflection (the S3 dump checksum).
std::uint16_t crc16_8005(std::span<const std::uint8_t> bytes) noexcept;

// The absolute time of `usec_past_hour` in the hour that puts it closest to `reference_ns`
// (any clock counting hours like UTC, e.g. an INS's UTC): resolves the top-of-hour rollover when
// the reference is within half an hour. Fails (empty) for usec_past_hour >= 3.6e9.
std::optional<std::int64_t> resolve_past_hour_ns(std::uint32_t usec_past_hour,
                                                 std::int64_t reference_ns) noexcept;

// UTC time (ns since 1970) of a packet from its microseconds past the hour and the cycle's date
// and time, which may be up to a cycle older: an hour rollover in between is resolved by taking
// the hour that puts the two closest. Empty when the status is not valid yet.
std::optional<std::int64_t> utc_time_ns(const SensorStatus& status,
                                        std::uint32_t usec_past_hour) noexcept;

// One packet's status bytes.
struct StatusByte {
  std::uint8_t type = 0, value = 0;
};
// The typed byte at `position` 0..8 of a cycle (H M S D N Y G T V) for `status`.
StatusByte typed_status_byte(int position, const SensorStatus& status) noexcept;
// The 4160 status bytes a unit sends for `calibration` (simulator, tests). Fails naming the
// laser and field when a correction does not fit the dump's 16-bit fields.
rt::Status encode_status_sequence(Model model, const SensorStatus& status,
                                  const UnitParameters& unit, const Calibration& calibration,
                                  std::span<StatusByte, kStatusDumpPackets> out);

// The UTC calendar date and time of `utc_ns` (ns since 1970).
DateTime utc_date_time(std::int64_t utc_ns) noexcept;

// Writes the 6 trailer bytes an S2.1/S3 sends: microseconds past the hour of the packet's time
// and the next status byte of the endlessly repeated status sequence, whose date and time follow
// the packet times. For the simulator and synthetic captures.
class StatusTrailerWriter {
 public:
  // `status` gives GPS state, temperature and firmware; its time is replaced per cycle.
  static rt::Result<StatusTrailerWriter> create(Model model, const SensorStatus& status,
                                                const UnitParameters& unit,
                                                const Calibration& calibration);
  void write(std::uint8_t* trailer, std::int64_t utc_ns) noexcept;

 private:
  StatusTrailerWriter() = default;
  std::vector<StatusByte> sequence_;
  SensorStatus status_;
  std::uint64_t next_ = 0;
};

}  // namespace stac::velodyne
