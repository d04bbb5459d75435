// Velodyne position packets (UDP port 8308) of the HDL-32E, VLP-16/Puck and VLP-32C, and the NMEA
// sentence ($xxRMC or $xxGGA) they echo from the GPS receiver wired to the sensor.
//
// Payload (512 bytes; offsets from its start, i.e. after the 42-byte Ethernet/IP/UDP headers;
// multi-byte values little-endian):
//     0..197  zero, except: HDL-32E bytes 14..37 = 3 boards x {gyro, temperature, accel x,
//             accel y}, each a u16 whose low 12 bits are two's complement (gyro 0.09766 deg/s,
//             temperature 0.1453 C + 25 C, accel 0.001221 g); newer VLP/VLS firmware puts board
//             temperatures and ADC status at 187..197 (not read here)
//   198..201  u32 microseconds past the top of the hour
//        202  PPS status: 0 absent, 1 synchronizing, 2 locked, 3 error
//   203..205  unused (newer firmware: thermal status and temperatures, not read here)
//   206..333  NMEA sentence, CR LF terminated, NUL padded (128 bytes)
//   334..511  unused, zero
// Sources: VLP-16 User Manual 63-9243 Rev D, tables 9-3/9-4 (offsets from the frame start:
// timestamp 0xF0, PPS 0xF4, 3 unused, sentence 0xF8 = payload 198, 202, 206); VLS-128 User Manual
// 63-9483, table 9-2 (0xC6 timestamp, 0xCA PPS, 0xCE..0x14D sentence, 0x14E..0x1FF unused); HDL-32E
// User's Manual appendix B (timestamp bytes "7c bd 9c 91" = 0x919cbd7c us: little-endian);
// Kitware/VeloView vtkVelodyneHDLPositionReader.cxx (HDL-32E: zeros 0..13, gyro/temp/accel at 14 +
// 8i, timestamp 198, sentence 206, the scale factors); kaarta/velodyne position_packet_converter.cc
// (PPS 0xCA, sentence 0xCE, the same 12-bit layout and gyro/accel scales); valgur/velodyne_decoder
// telemetry_packet.cpp (0xC6, 0xCA, 0xCE + 128 for all models incl. the VLP-32C);
// ros-drivers/velodyne input.h (POSITION_PORT_NUMBER 8308).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

#include "rt/expected.hpp"

namespace stac::velodyne {

inline constexpr std::uint16_t kPortPosition = 8308;
inline constexpr std::size_t kPositionPacketSize = 512;
inline constexpr std::size_t kNmeaMaxLength = 128;  // the packet's sentence field

enum class PpsStatus : std::uint8_t { kAbsent = 0, kSynchronizing = 1, kLocked = 2, kError = 3 };

enum class PositionError : std::uint8_t {
  kWrongSize,            // the payload is not 512 bytes
  kBadPpsStatus,         // PPS byte not 0..3
  kNoSentence,           // no sentence, or it does not start with '$' (a unit without GPS: zeros)
  kTruncated,            // no "*hh" checksum, or fewer fields than the sentence type has
  kBadChecksum,          // "*hh" is not the XOR of the characters between '$' and '*'
  kUnsupportedSentence,  // not [A-Z][A-Z]RMC or [A-Z][A-Z]GGA
  kMalformedField,       // a field not in its format (letters in a number, wrong width, ...)
  kOutOfRange,           // a well-formed value out of range (lat > 90, minutes >= 60, month 13)
};
const char* to_string(PositionError e) noexcept;
const char* to_string(PpsStatus s) noexcept;

enum class NmeaSentence : std::uint8_t { kRmc, kGga };

struct NmeaDate {  // UTC calendar date; RMC's two-digit year: 80..99 -> 1980.., 00..79 -> 2000..
  int year = 0, month = 0, day = 0;
};

struct NmeaFix {
  NmeaSentence sentence = NmeaSentence::kRmc;
  std::array<char, 2> talker{'G', 'P'};  // GP GPS, GN several constellations, GL, GA, ...
  bool checksum_ok = false;  // "*hh" equals the XOR of the characters between '$' and '*'
  bool valid = false;        // RMC: status 'A' and mode not 'N'; GGA: quality > 0
  // Each empty when its field is empty (a receiver without a fix sends ",,,").
  std::optional<std::int64_t> time_of_day_ns;  // UTC; 23:59:60.x (leap second) >= 86400 s
  std::optional<NmeaDate> date;                // RMC only
  std::optional<double> latitude_deg;          // north positive, [-90, 90]
  std::optional<double> longitude_deg;         // east positive, [-180, 180]
  std::optional<double> speed_mps;             // RMC: over ground, knots * 0.514444, [0, 1000 kn]
  std::optional<double> course_deg;            // RMC: true course over ground, [0, 360]
  std::uint8_t gga_quality = 0;                // GGA: 0 invalid, 1 GPS, 2 DGPS, 4 RTK fixed, ...
};

struct PositionPacket {
  std::uint32_t usec_past_hour = 0;
  PpsStatus pps = PpsStatus::kAbsent;
  std::array<char, kNmeaMaxLength + 1> sentence{};  // NUL-terminated, without CR LF
  std::size_t sentence_length = 0;
  NmeaFix fix;
  std::string_view nmea() const noexcept { return {sentence.data(), sentence_length}; }
};

using ParseResult = rt::Expected<PositionPacket, PositionError>;

// One position packet payload. Never throws or allocates; any byte string gives a packet or the
// first thing wrong with it. The sentence's checksum must match (else kBadChecksum).
ParseResult parse_position_packet(std::span<const std::uint8_t> payload) noexcept;

// One NMEA sentence, with or without its CR LF: the fix, or empty when it is not an RMC or GGA
// sentence in the format, or a value is out of range. A wrong or missing checksum is flagged in
// checksum_ok, not rejected (the packet parser rejects it).
std::optional<NmeaFix> parse_nmea(std::string_view sentence) noexcept;

// UTC nanoseconds since 1970 of the fix's date and time of day; empty without both (GGA).
std::optional<std::int64_t> nmea_utc_ns(const NmeaFix& fix) noexcept;

// The HDL-32E's gyros, temperatures and accelerometers (bytes 14..37), three boards whose axes
// are drawn in its manual's figure B2. Empty for a payload that is not 512 bytes. Other models
// send zeros there.
struct Hdl32eMotion {
  std::array<double, 3> gyro_deg_per_s{}, temperature_c{}, accel_x_g{}, accel_y_g{};
};
std::optional<Hdl32eMotion> parse_hdl32e_motion(std::span<const std::uint8_t> payload) noexcept;

// Writes a payload as a VLP-16/VLP-32C sends it: zeros, the timestamp, the PPS byte and `fix` as
// an RMC or GGA sentence (fix.sentence, fix.talker) with its checksum and CR LF. Time is written
// in milliseconds, positions in 1e-6 minutes, speed in 0.001 kn, course in 0.01 deg; absent
// values as empty fields. kOutOfRange for a value outside the ranges above (or NaN, a time of
// day >= 24 h, a year outside 1980..2079, usec_past_hour >= 3.6e9), kMalformedField for a
// talker that is not two upper-case letters; `out` is then left unchanged.
rt::Expected<void, PositionError> write_position_packet(
    std::uint32_t usec_past_hour, PpsStatus pps, const NmeaFix& fix,
    std::span<std::uint8_t, kPositionPacketSize> out) noexcept;

}  // namespace stac::velodyne
