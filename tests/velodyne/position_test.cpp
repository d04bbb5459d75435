#include "drivers/velodyne/position.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "rt/testing/alloc_counter.hpp"

namespace stac::velodyne {
namespace {

using Payload = std::array<std::uint8_t, kPositionPacketSize>;

constexpr std::size_t kSentenceAt = 206;
constexpr double kKnot = 1852.0 / 3600.0;
constexpr std::int64_t kSecondNs = 1'000'000'000;
// The classic RMC example of NMEA tutorials (checksum 6A as published).
constexpr std::string_view kClassicRmc =
    "$GPRMC,123519,A,4807.038,N,01131.000,E,022.4,084.4,230394,003.1,W*6A";
constexpr std::string_view kClassicGga =
    "$GPGGA,123519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,*47";

// A payload as a VLP-16 sends it: the sentence (as given: with or without CR LF) at byte 206.
Payload packet_with(std::string_view sentence, std::uint32_t usec_past_hour = 1'234'567,
                    std::uint8_t pps = 2) {
  Payload p{};
  for (int i = 0; i < 4; ++i) p[198 + i] = static_cast<std::uint8_t>(usec_past_hour >> (8 * i));
  p[202] = pps;
  std::memcpy(p.data() + kSentenceAt, sentence.data(), std::min(sentence.size(), kNmeaMaxLength));
  return p;
}

std::string with_checksum(std::string_view body) {  // "$" body "*hh"
  unsigned sum = 0;
  for (char c : body) sum ^= static_cast<unsigned char>(c);
  static constexpr std::string_view kHex = "0123456789ABCDEF";
  std::string s = "$";
  s.append(body);
  s.push_back('*');
  s.push_back(kHex[sum >> 4]);
  s.push_back(kHex[sum & 0xF]);
  return s;
}

PositionError packet_error(std::string_view sentence) {
  const Payload p = packet_with(sentence);
  auto r = parse_position_packet(p);
  EXPECT_FALSE(r) << sentence;
  return r ? PositionError::kWrongSize : r.error();
}

PositionError sentence_error(std::string_view body) {  // the body gets a correct checksum
  return packet_error(with_checksum(body));
}

TEST(PositionPacket, ContractIsNoexcept) {
  static_assert(noexcept(parse_position_packet(std::span<const std::uint8_t>{})));
  static_assert(noexcept(parse_nmea(std::string_view{})));
  static_assert(noexcept(nmea_utc_ns(NmeaFix{})));
  static_assert(noexcept(parse_hdl32e_motion(std::span<const std::uint8_t>{})));
  static_assert(
      noexcept(write_position_packet(0, PpsStatus::kAbsent, NmeaFix{}, std::declval<Payload&>())));
  EXPECT_EQ(kPortPosition, 8308);
  EXPECT_EQ(kPositionPacketSize, 512u);
}

TEST(PositionPacket, ClassicRmcWithPublishedChecksum) {
  const Payload p = packet_with(std::string(kClassicRmc) + "\r\n", 3'599'999'999U, 2);
  auto r = parse_position_packet(p);
  ASSERT_TRUE(r) << to_string(r.error());
  EXPECT_EQ(r->usec_past_hour, 3'599'999'999U);
  EXPECT_EQ(r->pps, PpsStatus::kLocked);
  EXPECT_EQ(r->nmea(), kClassicRmc);  // without CR LF
  EXPECT_EQ(r->sentence[kClassicRmc.size()], '\0');
  const NmeaFix& f = r->fix;
  EXPECT_EQ(f.sentence, NmeaSentence::kRmc);
  EXPECT_EQ(std::string_view(f.talker.data(), 2), "GP");
  EXPECT_TRUE(f.checksum_ok);
  EXPECT_TRUE(f.valid);
  EXPECT_EQ(f.time_of_day_ns, ((12 * 60 + 35) * 60 + 19) * kSecondNs);
  ASSERT_TRUE(f.date);
  EXPECT_EQ(f.date->year, 1994);
  EXPECT_EQ(f.date->month, 3);
  EXPECT_EQ(f.date->day, 23);
  EXPECT_NEAR(*f.latitude_deg, 48.1173, 1e-12);
  EXPECT_NEAR(*f.longitude_deg, 11.0 + 31.0 / 60.0, 1e-12);
  EXPECT_NEAR(*f.speed_mps, 22.4 * 0.514444, 1e-5);
  EXPECT_NEAR(*f.course_deg, 84.4, 1e-12);
  EXPECT_EQ(nmea_utc_ns(f), 764'426'119 * kSecondNs);  // 1994-03-23T12:35:19Z
}

TEST(PositionPacket, ClassicGgaHasTimeAndPositionButNoDate) {
  auto r = parse_position_packet(packet_with(std::string(kClassicGga) + "\r\n"));
  ASSERT_TRUE(r) << to_string(r.error());
  const NmeaFix& f = r->fix;
  EXPECT_EQ(f.sentence, NmeaSentence::kGga);
  EXPECT_TRUE(f.valid);
  EXPECT_EQ(f.gga_quality, 1);
  EXPECT_NEAR(*f.latitude_deg, 48.1173, 1e-12);
  EXPECT_EQ(f.time_of_day_ns, ((12 * 60 + 35) * 60 + 19) * kSecondNs);
  EXPECT_FALSE(f.date);
  EXPECT_FALSE(f.speed_mps);
  EXPECT_FALSE(nmea_utc_ns(f));  // no date in a GGA
}

TEST(PositionPacket, SentenceEndsAtNulCrOrLfOrTheFieldEnd) {
  for (std::string_view end : {"", "\r\n", "\n", "\r", "\r\ngarbage after the end"}) {
    auto r = parse_position_packet(packet_with(std::string(kClassicRmc) + std::string(end)));
    ASSERT_TRUE(r) << "end '" << end << "'";
    EXPECT_EQ(r->nmea(), kClassicRmc);
  }
  // A sentence filling all 128 bytes, unterminated: the field's end ends it.
  const std::string full =
      with_checksum("GPRMC,123519." + std::string(44, '0') +
                    ",A,4807.038,N,01131.000,E,022.4,084.4,230394,003.1,W,A,V,,,,,,,,,,,");
  ASSERT_EQ(full.size(), kNmeaMaxLength);
  auto r = parse_position_packet(packet_with(full));
  ASSERT_TRUE(r) << to_string(r.error());
  EXPECT_EQ(r->nmea(), full);
  EXPECT_EQ(r->sentence_length, kNmeaMaxLength);
}

TEST(NmeaSentence, SouthernAndWesternHemispheresAreNegative) {
  auto south = parse_nmea("$GPRMC,081836,A,3751.65,S,14507.36,E,000.0,360.0,130998,011.3,E*62");
  ASSERT_TRUE(south);
  EXPECT_TRUE(south->checksum_ok);
  EXPECT_NEAR(*south->latitude_deg, -(37.0 + 51.65 / 60.0), 1e-12);
  EXPECT_NEAR(*south->longitude_deg, 145.0 + 7.36 / 60.0, 1e-12);
  EXPECT_EQ(*south->course_deg, 360.0);  // the upper bound is allowed
  EXPECT_EQ(south->date->year, 1998);

  auto west = parse_nmea("$GPRMC,225446,A,4916.45,N,12311.12,W,000.5,054.7,191194,020.3,E*68");
  ASSERT_TRUE(west);
  EXPECT_TRUE(west->checksum_ok);
  EXPECT_NEAR(*west->latitude_deg, 49.0 + 16.45 / 60.0, 1e-12);
  EXPECT_NEAR(*west->longitude_deg, -(123.0 + 11.12 / 60.0), 1e-12);
  EXPECT_NEAR(*west->speed_mps, 0.5 * kKnot, 1e-12);
}

TEST(PositionPacket, ReceiverWithoutFixSendsEmptyFields) {
  auto rmc = parse_position_packet(packet_with("$GPRMC,,V,,,,,,,,,,N*53\r\n", 17, 0));
  ASSERT_TRUE(rmc) << to_string(rmc.error());
  EXPECT_EQ(rmc->pps, PpsStatus::kAbsent);
  const NmeaFix& f = rmc->fix;
  EXPECT_FALSE(f.valid);
  EXPECT_FALSE(f.time_of_day_ns);
  EXPECT_FALSE(f.date);
  EXPECT_FALSE(f.latitude_deg);
  EXPECT_FALSE(f.longitude_deg);
  EXPECT_FALSE(f.speed_mps);
  EXPECT_FALSE(f.course_deg);
  EXPECT_FALSE(nmea_utc_ns(f));

  auto gga = parse_position_packet(packet_with("$GPGGA,,,,,,0,00,99.99,,,,,,*48\r\n"));
  ASSERT_TRUE(gga) << to_string(gga.error());
  EXPECT_FALSE(gga->fix.valid);
  EXPECT_FALSE(gga->fix.latitude_deg);
}

TEST(NmeaSentence, StatusVOrModeNIsNotValid) {
  auto v =
      parse_nmea(with_checksum("GPRMC,123519,V,4807.038,N,01131.000,E,022.4,084.4,230394,003.1,W"));
  ASSERT_TRUE(v);
  EXPECT_FALSE(v->valid);
  EXPECT_TRUE(v->latitude_deg);  // the last known position, flagged
  auto n = parse_nmea(
      with_checksum("GNRMC,123519,A,4807.038,N,01131.000,E,022.4,084.4,230394,003.1,W,N"));
  ASSERT_TRUE(n);
  EXPECT_EQ(std::string_view(n->talker.data(), 2), "GN");
  EXPECT_FALSE(n->valid);
  auto a = parse_nmea(
      with_checksum("GNRMC,123519,A,4807.038,N,01131.000,E,022.4,084.4,230394,003.1,W,D"));
  ASSERT_TRUE(a);
  EXPECT_TRUE(a->valid);
}

// The fix of an RMC at 00:00:00 UTC on `ddmmyy`, or empty.
std::optional<NmeaFix> rmc_on(std::string_view ddmmyy) {
  return parse_nmea(with_checksum("GPRMC,000000.00,A,4807.038,N,01131.000,E,0.0,0.0," +
                                  std::string(ddmmyy) + ",,"));
}

TEST(NmeaSentence, DatesAroundTheCenturyAndLeapDays) {
  auto y2k = rmc_on("010100");
  ASSERT_TRUE(y2k);
  EXPECT_EQ(y2k->date->year, 2000);
  EXPECT_EQ(nmea_utc_ns(*y2k), 946'684'800 * kSecondNs);  // 2000-01-01T00:00:00Z

  auto leap_2024 = rmc_on("290224");
  ASSERT_TRUE(leap_2024);
  EXPECT_EQ(nmea_utc_ns(*leap_2024), 1'709'164'800 * kSecondNs);  // 2024-02-29
  auto leap_2000 = rmc_on("290200");                              // divisible by 400: a leap year
  ASSERT_TRUE(leap_2000);
  EXPECT_EQ(nmea_utc_ns(*leap_2000), 951'782'400 * kSecondNs);

  auto eighties = rmc_on("010180");  // two-digit years from 80 are 1980..1999 (GPS began 1980)
  ASSERT_TRUE(eighties);
  EXPECT_EQ(eighties->date->year, 1980);
  EXPECT_EQ(nmea_utc_ns(*eighties), 315'532'800 * kSecondNs);
  auto last = rmc_on("311279");
  ASSERT_TRUE(last);
  EXPECT_EQ(last->date->year, 2079);

  for (std::string_view bad :
       {"290223", "290201", "300200", "310424", "000124", "010024", "011324", "320124"}) {
    EXPECT_FALSE(rmc_on(bad)) << bad;
    EXPECT_EQ(sentence_error("GPRMC,000000,A,,,,,,," + std::string(bad)),
              PositionError::kOutOfRange)
        << bad;
  }
}

TEST(NmeaSentence, TimeOfDayFractionAndLeapSecond) {
  auto f = parse_nmea(with_checksum("GPGGA,235959.123456789123,,,,,1"));
  ASSERT_TRUE(f);
  EXPECT_EQ(f->time_of_day_ns, 86'399 * kSecondNs + 123'456'789);  // below 1 ns: dropped
  auto leap = parse_nmea(with_checksum("GPRMC,235960.5,A,,,,,,,311216"));
  ASSERT_TRUE(leap);
  EXPECT_EQ(leap->time_of_day_ns, 86'400 * kSecondNs + 500'000'000);
  EXPECT_EQ(nmea_utc_ns(*leap), (1'483'228'800 + 0) * kSecondNs + 500'000'000);  // = 2017-01-01
  for (std::string_view bad : {"240000", "126000", "125960", "995959"}) {
    EXPECT_EQ(sentence_error("GPGGA," + std::string(bad) + ",,,,,1"), PositionError::kOutOfRange)
        << bad;
  }
  for (std::string_view bad :
       {"12351", "1235199", "123519.", "123519,5", "12:35:19", "-12351", "123519.5e3", "1235 9"}) {
    EXPECT_EQ(sentence_error("GPGGA," + std::string(bad) + ",,,,,1"),
              PositionError::kMalformedField)
        << bad;
  }
}

TEST(PositionPacket, BadChecksumIsRejectedByThePacketAndFlaggedByParseNmea) {
  std::string wrong(kClassicRmc);
  wrong.back() = 'B';  // *6B
  EXPECT_EQ(packet_error(wrong), PositionError::kBadChecksum);
  auto flagged = parse_nmea(wrong);
  ASSERT_TRUE(flagged);
  EXPECT_FALSE(flagged->checksum_ok);
  EXPECT_NEAR(*flagged->latitude_deg, 48.1173, 1e-12);

  std::string flipped(kClassicRmc);
  flipped[19] = '8';  // a digit changed in transit: 4808.038
  EXPECT_EQ(packet_error(flipped), PositionError::kBadChecksum);

  std::string lower(kClassicRmc);
  lower.back() = 'a';  // lower-case hex digits are read too
  auto r = parse_position_packet(packet_with(lower));
  EXPECT_TRUE(r);

  EXPECT_EQ(packet_error(std::string(kClassicRmc.substr(0, kClassicRmc.size() - 2)) + "G1"),
            PositionError::kMalformedField);
  EXPECT_EQ(packet_error(std::string(kClassicRmc) + "0"), PositionError::kMalformedField);
}

TEST(PositionPacket, TruncatedSentences) {
  // Cut anywhere before the checksum's second digit: never accepted.
  for (std::size_t n = 1; n + 1 < kClassicRmc.size(); ++n) {
    const PositionError e = packet_error(kClassicRmc.substr(0, n));
    EXPECT_TRUE(e == PositionError::kTruncated) << n << ": " << to_string(e);
    EXPECT_FALSE(parse_nmea(kClassicRmc.substr(0, n))) << n;
  }
  // A checksum that matches but too few fields for the sentence type.
  EXPECT_EQ(sentence_error("GPRMC,123519,A,4807.038,N"), PositionError::kTruncated);
  EXPECT_EQ(sentence_error("GPGGA,123519,4807.038,N,01131.000,E"), PositionError::kTruncated);
  EXPECT_EQ(sentence_error("GPRMC"), PositionError::kTruncated);
}

TEST(PositionPacket, WrongSizeIsRejectedWithoutReading) {
  const Payload good = packet_with(kClassicRmc);
  std::vector<std::uint8_t> bytes(good.begin(), good.end());
  for (std::size_t n : {0u, 1u, 206u, 511u, 513u, 554u}) {
    bytes.resize(n, 0);
    auto r = parse_position_packet(bytes);
    ASSERT_FALSE(r) << n;
    EXPECT_EQ(r.error(), PositionError::kWrongSize) << n;
    EXPECT_FALSE(parse_hdl32e_motion(bytes)) << n;
  }
}

TEST(PositionPacket, HeaderFieldsOutOfRange) {
  auto zeros = parse_position_packet(Payload{});  // a unit without GPS
  ASSERT_FALSE(zeros);
  EXPECT_EQ(zeros.error(), PositionError::kNoSentence);
  for (std::uint8_t pps = 4; pps != 0; ++pps) {
    auto r = parse_position_packet(packet_with(kClassicRmc, 0, pps));
    ASSERT_FALSE(r);
    EXPECT_EQ(r.error(), PositionError::kBadPpsStatus);
  }
  auto hour = parse_position_packet(packet_with(kClassicRmc, 3'600'000'000U));
  ASSERT_FALSE(hour);
  EXPECT_EQ(hour.error(), PositionError::kOutOfRange);
  for (std::uint8_t pps = 0; pps < 4; ++pps) {
    auto r = parse_position_packet(packet_with(kClassicRmc, 0, pps));
    ASSERT_TRUE(r);
    EXPECT_EQ(static_cast<std::uint8_t>(r->pps), pps);
    EXPECT_NE(std::string_view(to_string(r->pps)), "unknown");
  }
}

TEST(NmeaSentence, NotAnRmcOrGga) {
  EXPECT_EQ(packet_error("GPRMC,123519,A*00"), PositionError::kNoSentence);  // no '$'
  EXPECT_EQ(packet_error("!AIVDM,1,1,,A,13aEOK?P00PD2wVMdLDRhgvL289?,0*26"),
            PositionError::kNoSentence);
  EXPECT_EQ(sentence_error("GPGSV,3,1,11,03,03,111,00,04,15,270,00,06,01,010,00,13,06,292,00"),
            PositionError::kUnsupportedSentence);
  EXPECT_EQ(sentence_error("PGRMZ,246,f,3"), PositionError::kUnsupportedSentence);
  EXPECT_EQ(sentence_error("gpRMC,123519,A,,,,,,,"), PositionError::kUnsupportedSentence);
  EXPECT_EQ(sentence_error("GPRMCX,123519,A,,,,,,,"), PositionError::kUnsupportedSentence);
  EXPECT_EQ(sentence_error(""), PositionError::kUnsupportedSentence);
  EXPECT_FALSE(parse_nmea(""));
  EXPECT_FALSE(parse_nmea("$"));
  EXPECT_FALSE(parse_nmea("*"));
}

TEST(NmeaSentence, PositionFieldsOutOfRangeOrMalformed) {
  struct Case {
    std::string_view lat, ns, lon, ew;
    PositionError error;
  };
  const Case cases[] = {
      {"9000.001", "N", "01131.000", "E", PositionError::kOutOfRange},  // > 90 deg
      {"9100.000", "S", "01131.000", "E", PositionError::kOutOfRange},
      {"4860.000", "N", "01131.000", "E", PositionError::kOutOfRange},  // 60 minutes
      {"4807.038", "N", "18000.001", "W", PositionError::kOutOfRange},  // > 180 deg
      {"4807.038", "N", "00099.000", "E", PositionError::kOutOfRange},  // 99 minutes
      {"4807.038", "X", "01131.000", "E", PositionError::kMalformedField},
      {"4807.038", "N", "01131.000", "N", PositionError::kMalformedField},
      {"4807.038", "", "01131.000", "E", PositionError::kMalformedField},  // hemisphere missing
      {"", "N", "01131.000", "E", PositionError::kMalformedField},         // value missing
      {"4807.038", "NN", "01131.000", "E", PositionError::kMalformedField},
      {"-4807.038", "N", "01131.000", "E", PositionError::kMalformedField},
      {"+4807.038", "N", "01131.000", "E", PositionError::kMalformedField},
      {"48.07038", "N", "01131.000", "E", PositionError::kMalformedField},   // degrees, not ddmm
      {"04807.038", "N", "01131.000", "E", PositionError::kMalformedField},  // 3 degree digits
      {"4807.03.8", "N", "01131.000", "E", PositionError::kMalformedField},
      {"4807.", "N", "01131.000", "E", PositionError::kMalformedField},
      {"nan", "N", "01131.000", "E", PositionError::kMalformedField},
      {"4807.038", "N", "inf", "E", PositionError::kMalformedField},
      {"4807.038", "N", "1e3", "E", PositionError::kMalformedField},
      {"4807.038", "N", "0x1F", "E", PositionError::kMalformedField},
      {"123456789012345678901234567890.0", "N", "01131.000", "E", PositionError::kMalformedField},
  };
  for (const Case& c : cases) {
    const std::string rmc = "GPRMC,123519,A," + std::string(c.lat) + "," + std::string(c.ns) + "," +
                            std::string(c.lon) + "," + std::string(c.ew) + ",0,0,230394,,";
    EXPECT_EQ(sentence_error(rmc), c.error) << rmc;
    EXPECT_FALSE(parse_nmea(with_checksum(rmc))) << rmc;
    const std::string gga = "GPGGA,123519," + std::string(c.lat) + "," + std::string(c.ns) + "," +
                            std::string(c.lon) + "," + std::string(c.ew) + ",1,08,0.9,,,,,,";
    EXPECT_EQ(sentence_error(gga), c.error) << gga;
  }
  // The poles and the antimeridian are in range; minutes keep any number of decimals.
  auto pole = parse_nmea(with_checksum("GPGGA,,9000.000,S,18000.0000000000000001,W,1"));
  ASSERT_TRUE(pole);
  EXPECT_EQ(*pole->latitude_deg, -90.0);
  EXPECT_EQ(*pole->longitude_deg, -180.0);
}

TEST(NmeaSentence, SpeedAndCourseHugeNegativeOrNotNumbers) {
  auto speed_course = [](std::string_view speed, std::string_view course) {
    return "GPRMC,123519,A,4807.038,N,01131.000,E," + std::string(speed) + "," +
           std::string(course) + ",230394,,";
  };
  EXPECT_EQ(sentence_error(speed_course("1000.001", "0")), PositionError::kOutOfRange);
  EXPECT_EQ(sentence_error(speed_course("99999999999999999999999999999999999999.9", "0")),
            PositionError::kOutOfRange);
  EXPECT_EQ(sentence_error(speed_course("0", "360.01")), PositionError::kOutOfRange);
  EXPECT_EQ(sentence_error(speed_course("0", "18446744073709551617")), PositionError::kOutOfRange);
  for (std::string_view bad :
       {"-1.0", "NaN", "nan", "inf", "INF", "1e3", "1.5.", ".5", "0x10", " 1", "1 ", "1,5"}) {
    EXPECT_EQ(sentence_error(speed_course(bad, "0")), PositionError::kMalformedField) << bad;
    EXPECT_EQ(sentence_error(speed_course("0", bad)), PositionError::kMalformedField) << bad;
  }
  auto fast = parse_nmea(with_checksum(speed_course("1000.0", "359.99")));
  ASSERT_TRUE(fast);
  EXPECT_NEAR(*fast->speed_mps, 1000.0 * kKnot, 1e-9);
  auto long_fraction = parse_nmea(with_checksum(speed_course("1.0000000001234567890123", "0")));
  ASSERT_TRUE(long_fraction);
  EXPECT_NEAR(*long_fraction->speed_mps, kKnot, 1e-9);
}

TEST(PositionPacket, ControlCharactersAndGarbageNeverCrash) {
  EXPECT_EQ(packet_error(with_checksum("GPRMC,123519,A,\x01,,,,,,")),
            PositionError::kMalformedField);
  EXPECT_EQ(packet_error(with_checksum("GPRMC,123519,A,\xB0,,,,,,")),
            PositionError::kMalformedField);
  EXPECT_EQ(packet_error(with_checksum("GPRMC,$GPRMC,123519,A,,,,,,")),
            PositionError::kMalformedField);
  EXPECT_EQ(packet_error(with_checksum("GPRMC" + std::string(60, ','))),  // too many fields
            PositionError::kMalformedField);
  EXPECT_FALSE(parse_nmea(with_checksum("GPRMC" + std::string(1000, ','))));

  std::mt19937 rng(20260511);
  std::uniform_int_distribution<int> byte(0, 255);
  const std::string alphabet = "$*,.0123456789ABCDEFGNPRMSVW\r\n";
  std::uniform_int_distribution<std::size_t> pick(0, alphabet.size() - 1);
  int accepted = 0;
  for (int i = 0; i < 20'000; ++i) {
    Payload p{};
    if (i % 2 == 0) {
      for (auto& b : p) b = static_cast<std::uint8_t>(byte(rng));
    } else {  // NMEA-like noise around a valid sentence
      p = packet_with(kClassicRmc, 1, 2);
      for (int k = 0; k < 1 + i % 4; ++k) {
        p[kSentenceAt + std::uniform_int_distribution<std::size_t>(0, kClassicRmc.size())(rng)] =
            static_cast<std::uint8_t>(alphabet[pick(rng)]);
      }
    }
    auto r = parse_position_packet(p);
    if (!r) {
      EXPECT_NE(std::string_view(to_string(r.error())), "unknown position error");
      continue;
    }
    ++accepted;  // whatever is accepted is in range
    const NmeaFix& f = r->fix;
    EXPECT_TRUE(f.checksum_ok);
    EXPECT_LE(std::abs(f.latitude_deg.value_or(0)), 90.0);
    EXPECT_LE(std::abs(f.longitude_deg.value_or(0)), 180.0);
    EXPECT_TRUE(f.speed_mps.value_or(0) >= 0 && f.speed_mps.value_or(0) <= 1000 * kKnot);
    EXPECT_TRUE(f.course_deg.value_or(0) >= 0 && f.course_deg.value_or(0) <= 360);
  }
  EXPECT_GT(accepted, 0);  // some noise lands in the checksum's digits or after it
}

NmeaFix example_fix(NmeaSentence sentence) {
  NmeaFix f;
  f.sentence = sentence;
  f.talker = {'G', 'N'};
  f.valid = true;
  f.time_of_day_ns = ((23 * 60 + 59) * 60 + 58) * kSecondNs + 987'000'000;
  f.latitude_deg = -33.8567844;    // southern
  f.longitude_deg = -151.2152967;  // western (the antipode of Sydney's longitude)
  if (sentence == NmeaSentence::kRmc) {
    f.date = NmeaDate{2024, 2, 29};
    f.speed_mps = 13.5;
    f.course_deg = 359.99;
  } else {
    f.gga_quality = 4;
  }
  return f;
}

TEST(PositionPacketWriter, RoundTripsThroughTheParser) {
  for (NmeaSentence kind : {NmeaSentence::kRmc, NmeaSentence::kGga}) {
    const NmeaFix in = example_fix(kind);
    Payload p{};
    p.fill(0xAA);  // every byte is written
    auto w = write_position_packet(2'345'678'901U, PpsStatus::kSynchronizing, in, p);
    ASSERT_TRUE(w) << to_string(w.error());
    for (std::size_t i = 0; i < 198; ++i) ASSERT_EQ(p[i], 0) << i;
    auto r = parse_position_packet(p);
    ASSERT_TRUE(r) << to_string(r.error());
    EXPECT_EQ(r->usec_past_hour, 2'345'678'901U);
    EXPECT_EQ(r->pps, PpsStatus::kSynchronizing);
    const NmeaFix& out = r->fix;
    EXPECT_EQ(out.sentence, kind);
    EXPECT_EQ(out.talker, in.talker);
    EXPECT_TRUE(out.checksum_ok);
    EXPECT_TRUE(out.valid);
    EXPECT_EQ(out.time_of_day_ns, in.time_of_day_ns);
    EXPECT_NEAR(*out.latitude_deg, *in.latitude_deg, 1e-7);
    EXPECT_NEAR(*out.longitude_deg, *in.longitude_deg, 1e-7);
    if (kind == NmeaSentence::kRmc) {
      EXPECT_EQ(r->nmea(),
                "$GNRMC,235958.987,A,3351.407064,S,15112.917802,W,026.242,359.99,290224,,,A*"
                "4F");
      EXPECT_EQ(out.date->year, 2024);
      EXPECT_EQ(out.date->month, 2);
      EXPECT_EQ(out.date->day, 29);
      EXPECT_NEAR(*out.speed_mps, 13.5, 1e-3);
      EXPECT_NEAR(*out.course_deg, 359.99, 1e-9);
      EXPECT_EQ(nmea_utc_ns(out), (1'709'164'800 + 86'398) * kSecondNs + 987'000'000);
    } else {
      EXPECT_EQ(out.gga_quality, 4);
      EXPECT_FALSE(out.date);
    }
    // CR LF then NUL padding to the end.
    const std::size_t end = kSentenceAt + r->sentence_length;
    EXPECT_EQ(p[end], '\r');
    EXPECT_EQ(p[end + 1], '\n');
    for (std::size_t i = end + 2; i < p.size(); ++i) ASSERT_EQ(p[i], 0) << i;
  }
}

TEST(PositionPacketWriter, WritesAbsentValuesAsEmptyFields) {
  NmeaFix none;  // a receiver without a fix
  Payload p{};
  ASSERT_TRUE(write_position_packet(0, PpsStatus::kAbsent, none, p));
  auto r = parse_position_packet(p);
  ASSERT_TRUE(r) << to_string(r.error());
  EXPECT_EQ(r->nmea(), "$GPRMC,,V,,,,,,,,,,N*53");  // what receivers send
  EXPECT_FALSE(r->fix.valid);
  EXPECT_FALSE(r->fix.latitude_deg);

  none.sentence = NmeaSentence::kGga;
  ASSERT_TRUE(write_position_packet(0, PpsStatus::kAbsent, none, p));
  auto g = parse_position_packet(p);
  ASSERT_TRUE(g) << to_string(g.error());
  EXPECT_FALSE(g->fix.valid);
  EXPECT_EQ(g->fix.gga_quality, 0);
}

TEST(PositionPacketWriter, RejectsWhatTheParserWould) {
  struct Case {
    const char* what;
    void (*edit)(NmeaFix&);
    PositionError error;
  };
  const Case cases[] = {
      {"NaN latitude",
       [](NmeaFix& f) { f.latitude_deg = std::numeric_limits<double>::quiet_NaN(); },
       PositionError::kOutOfRange},
      {"latitude 90.0001", [](NmeaFix& f) { f.latitude_deg = 90.0001; },
       PositionError::kOutOfRange},
      {"longitude -181", [](NmeaFix& f) { f.longitude_deg = -181.0; }, PositionError::kOutOfRange},
      {"infinite longitude",
       [](NmeaFix& f) { f.longitude_deg = std::numeric_limits<double>::infinity(); },
       PositionError::kOutOfRange},
      {"negative speed", [](NmeaFix& f) { f.speed_mps = -0.1; }, PositionError::kOutOfRange},
      {"NaN speed", [](NmeaFix& f) { f.speed_mps = std::numeric_limits<double>::quiet_NaN(); },
       PositionError::kOutOfRange},
      {"1001 kn", [](NmeaFix& f) { f.speed_mps = 1001 * kKnot; }, PositionError::kOutOfRange},
      {"course 360.01", [](NmeaFix& f) { f.course_deg = 360.01; }, PositionError::kOutOfRange},
      {"course -1", [](NmeaFix& f) { f.course_deg = -1.0; }, PositionError::kOutOfRange},
      {"24:00", [](NmeaFix& f) { f.time_of_day_ns = 86'400 * kSecondNs; },
       PositionError::kOutOfRange},
      {"negative time", [](NmeaFix& f) { f.time_of_day_ns = -1; }, PositionError::kOutOfRange},
      {"year 2080",
       [](NmeaFix& f) {
         f.date = NmeaDate{2080, 1, 1};
       },
       PositionError::kOutOfRange},
      {"year 1979",
       [](NmeaFix& f) {
         f.date = NmeaDate{1979, 12, 31};
       },
       PositionError::kOutOfRange},
      {"month 13",
       [](NmeaFix& f) {
         f.date = NmeaDate{2024, 13, 1};
       },
       PositionError::kOutOfRange},
      {"month 0",
       [](NmeaFix& f) {
         f.date = NmeaDate{2024, 0, 1};
       },
       PositionError::kOutOfRange},
      {"2023-02-29",
       [](NmeaFix& f) {
         f.date = NmeaDate{2023, 2, 29};
       },
       PositionError::kOutOfRange},
      {"lower-case talker",
       [](NmeaFix& f) {
         f.talker = {'g', 'p'};
       },
       PositionError::kMalformedField},
      {"NUL talker",
       [](NmeaFix& f) {
         f.talker = {'\0', 'P'};
       },
       PositionError::kMalformedField},
  };
  for (const Case& c : cases) {
    NmeaFix f = example_fix(NmeaSentence::kRmc);
    c.edit(f);
    Payload p{};
    p.fill(0x5A);
    auto w = write_position_packet(0, PpsStatus::kLocked, f, p);
    ASSERT_FALSE(w) << c.what;
    EXPECT_EQ(w.error(), c.error) << c.what;
    EXPECT_TRUE(std::all_of(p.begin(), p.end(), [](std::uint8_t b) { return b == 0x5A; }))
        << c.what << ": out changed";
  }
  Payload p{};
  const NmeaFix f = example_fix(NmeaSentence::kRmc);
  EXPECT_FALSE(write_position_packet(3'600'000'000U, PpsStatus::kLocked, f, p));
  EXPECT_FALSE(write_position_packet(0, static_cast<PpsStatus>(4), f, p));
  NmeaFix gga = example_fix(NmeaSentence::kGga);
  gga.gga_quality = 10;
  EXPECT_FALSE(write_position_packet(0, PpsStatus::kLocked, gga, p));
}

TEST(NmeaSentence, UtcOfHandMadeFixesOutOfRangeIsEmpty) {
  NmeaFix f = example_fix(NmeaSentence::kRmc);
  ASSERT_TRUE(nmea_utc_ns(f));
  f.time_of_day_ns = -1;
  EXPECT_FALSE(nmea_utc_ns(f));
  f.time_of_day_ns = std::numeric_limits<std::int64_t>::max();
  EXPECT_FALSE(nmea_utc_ns(f));
  f.time_of_day_ns = 0;
  f.date = NmeaDate{32767, 12, 31};
  EXPECT_FALSE(nmea_utc_ns(f));
  f.date = NmeaDate{2024, 2, 30};
  EXPECT_FALSE(nmea_utc_ns(f));
}

TEST(Hdl32eMotion, TwelveBitTwosComplement) {
  Payload p = packet_with(kClassicRmc);
  auto put = [&](std::size_t at, std::uint16_t v) {
    p[at] = static_cast<std::uint8_t>(v & 0xFF);
    p[at + 1] = static_cast<std::uint8_t>(v >> 8);
  };
  put(14, 0xF001);      // board 1 gyro: +1 (the upper 4 bits are not data)
  put(16, 0x0000);      // temperature raw 0 = 25 C
  put(18, 0x07FF);      // accel x: +2047
  put(20, 0x0800);      // accel y: -2048
  put(22, 0x0FFF);      // board 2 gyro: -1
  put(24, 0x0064);      // temperature raw 100
  put(30 + 4, 0x0FFE);  // board 3 accel x: -2
  auto m = parse_hdl32e_motion(p);
  ASSERT_TRUE(m);
  EXPECT_NEAR(m->gyro_deg_per_s[0], 0.09766, 1e-12);
  EXPECT_NEAR(m->temperature_c[0], 25.0, 1e-12);
  EXPECT_NEAR(m->accel_x_g[0], 2047 * 0.001221, 1e-12);
  EXPECT_NEAR(m->accel_y_g[0], -2048 * 0.001221, 1e-12);
  EXPECT_NEAR(m->gyro_deg_per_s[1], -0.09766, 1e-12);
  EXPECT_NEAR(m->temperature_c[1], 25.0 + 100 * 0.1453, 1e-12);
  EXPECT_NEAR(m->accel_x_g[2], -2 * 0.001221, 1e-12);
  EXPECT_TRUE(parse_position_packet(p));  // the NMEA part does not care
}

TEST(PositionPacket, ParsesAndWritesWithoutAllocating) {
  const Payload rmc = packet_with(std::string(kClassicRmc) + "\r\n");
  const Payload broken = packet_with("$GPRMC,1235");
  const NmeaFix fix = example_fix(NmeaSentence::kRmc);
  Payload out{};
  int ok = 0;
  stac::rt::testing::AllocationCounter counter;
  for (int i = 0; i < 1000; ++i) {
    ok += parse_position_packet(rmc) ? 1 : 0;
    ok += parse_position_packet(broken) ? 1 : 0;
    ok += parse_nmea(kClassicGga) ? 1 : 0;
    ok += write_position_packet(1, PpsStatus::kLocked, fix, out) ? 1 : 0;
    ok += nmea_utc_ns(fix) ? 1 : 0;
  }
  counter.stop();
  EXPECT_EQ(ok, 4000);
  EXPECT_EQ(counter.allocations(), 0u);
}

}  // namespace
}  // namespace stac::velodyne
