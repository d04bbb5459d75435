#include "drivers/can/dbc.hpp"

#include <gtest/gtest.h>

#include <array>
#include <random>

#include "test_paths.hpp"

namespace stac::can {
namespace {

using Payload = std::array<std::uint8_t, 8>;

Signal make(std::uint16_t start, std::uint16_t length, ByteOrder order, bool is_signed,
            double factor = 1.0, double offset = 0.0) {
  Signal s;
  s.name = "S";
  s.start_bit = start;
  s.length = length;
  s.order = order;
  s.is_signed = is_signed;
  s.factor = factor;
  s.offset = offset;
  return s;
}

// Every expected value below was worked out by hand from the bit layout.
TEST(DbcSignal, IntelAlignedUnsignedAndSigned) {
  const Payload p{0x34, 0x12, 0xFF, 0xFE, 0, 0, 0, 0};
  EXPECT_EQ(make(0, 16, ByteOrder::kIntel, false).raw(p), 0x1234);
  EXPECT_EQ(make(16, 16, ByteOrder::kIntel, true).raw(p), -257);  // 0xFEFF
  EXPECT_EQ(make(16, 16, ByteOrder::kIntel, false).raw(p), 0xFEFF);
  EXPECT_DOUBLE_EQ(make(16, 16, ByteOrder::kIntel, true, 0.01).decode(p), -2.57);
}

TEST(DbcSignal, IntelCrossingBytesAtOddBits) {
  // bits 12..21: byte 1 bits 4..7 are the low nibble 0xA, byte 2 bits 0..5 the high six bits 0x3F.
  const Payload p{0, 0xA0, 0x3F, 0, 0, 0, 0, 0};
  EXPECT_EQ(make(12, 10, ByteOrder::kIntel, false).raw(p), 0x3FA);
  EXPECT_EQ(make(12, 10, ByteOrder::kIntel, true).raw(p), 0x3FA - 1024);
  EXPECT_EQ(make(20, 1, ByteOrder::kIntel, false).raw(p), 1);  // byte 2 bit 4
  EXPECT_EQ(make(22, 1, ByteOrder::kIntel, false).raw(p), 0);  // byte 2 bit 6
}

TEST(DbcSignal, MotorolaAlignedWord) {
  // start bit 7 = MSB of byte 0: byte 0 is the high byte.
  const Payload p{0x0E, 0x10, 0, 0, 0, 0, 0, 0};
  const Signal s = make(7, 16, ByteOrder::kMotorola, false, 0.01);
  EXPECT_EQ(s.raw(p), 0x0E10);
  EXPECT_DOUBLE_EQ(s.decode(p), 36.0);
  EXPECT_EQ(s.bytes_needed(), 2);
}

TEST(DbcSignal, MotorolaCrossingBytesFromAMidByteStart) {
  // start 3, 12 bits: byte 0 bits 3..0 (0xB of 0xAB) then all of byte 1 (0xCD).
  const Payload a{0xAB, 0xCD, 0, 0, 0, 0, 0, 0};
  EXPECT_EQ(make(3, 12, ByteOrder::kMotorola, false).raw(a), 0xBCD);
  // start 13 (byte 1 bit 5), 14 bits: byte 1 bits 5..0 = 0b100101, then byte 2 = 0x9C.
  const Payload b{0xFF, 0xE5, 0x9C, 0xFF, 0, 0, 0, 0};
  EXPECT_EQ(make(13, 14, ByteOrder::kMotorola, false).raw(b), 0x259C);
  EXPECT_EQ(make(13, 14, ByteOrder::kMotorola, true).raw(b), 0x259C - 16384);
  EXPECT_EQ(make(13, 14, ByteOrder::kMotorola, false).bytes_needed(), 3);
  // start 4, 20 bits over three bytes: byte 0 bits 4..0 = 10101, byte 1 = 01100111, byte 2
  // bits 7..1 = 1000100 -> 1010 1011 0011 1100 0100 = 0xAB3C4.
  const Payload c{0x35, 0x67, 0x89, 0, 0, 0, 0, 0};
  EXPECT_EQ(make(4, 20, ByteOrder::kMotorola, false).raw(c), 0xAB3C4);
  EXPECT_EQ(make(4, 20, ByteOrder::kMotorola, false).bytes_needed(), 3);
}

TEST(DbcSignal, SixtyFourBitsAndOffsets) {
  const Payload p{0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x07, 0x88};
  EXPECT_EQ(static_cast<std::uint64_t>(make(0, 64, ByteOrder::kIntel, false).raw(p)),
            0x8807060504030201ull);
  EXPECT_EQ(static_cast<std::uint64_t>(make(7, 64, ByteOrder::kMotorola, false).raw(p)),
            0x0102030405060788ull);
  EXPECT_DOUBLE_EQ(make(0, 8, ByteOrder::kIntel, false, 0.5, -40).decode(p), 0.5 - 40);
}

TEST(DbcSignal, EncodeWritesOnlyItsBitsWithTheHandComputedLayout) {
  Payload p{};
  p.fill(0xFF);
  // -6756 as 14-bit two's complement = 0x259C: byte 1 bits 5..0 = 0x25, byte 2 = 0x9C.
  ASSERT_TRUE(make(13, 14, ByteOrder::kMotorola, true).encode(-6756, p));
  EXPECT_EQ(p, (Payload{0xFF, 0xE5, 0x9C, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF}));
  Payload q{};
  ASSERT_TRUE(make(12, 10, ByteOrder::kIntel, true).encode(-6, q));  // 0x3FA
  EXPECT_EQ(q, (Payload{0, 0xA0, 0x3F, 0, 0, 0, 0, 0}));
}

TEST(DbcSignal, EncodeRefusesValuesOutsideTheRawRange) {
  Payload p{};
  const Signal u8 = make(0, 8, ByteOrder::kIntel, false, 0.5);
  EXPECT_TRUE(u8.encode(127.5, p));
  EXPECT_FALSE(u8.encode(128.0, p));
  EXPECT_FALSE(u8.encode(-0.5, p));
  EXPECT_FALSE(u8.encode(std::nan(""), p));
  const Signal s8 = make(0, 8, ByteOrder::kIntel, true);
  EXPECT_TRUE(s8.encode(-128, p));
  EXPECT_FALSE(s8.encode(128, p));
  EXPECT_EQ(p[0], 0x80);  // the refused value left the payload alone
}

TEST(DbcSignal, RandomRoundTripsKeepEveryOtherBit) {
  std::mt19937_64 rng(42);
  for (int i = 0; i < 20000; ++i) {
    const auto order = (rng() & 1) != 0 ? ByteOrder::kIntel : ByteOrder::kMotorola;
    const auto length = static_cast<std::uint16_t>(1 + rng() % 64);
    const auto start = static_cast<std::uint16_t>(rng() % 64);
    Signal s = make(start, length, order, (rng() & 1) != 0);
    // keep only layouts that fit 8 bytes
    const int msb = (7 - start / 8) * 8 + start % 8;
    if (order == ByteOrder::kIntel ? start + length > 64 : msb - (length - 1) < 0) continue;
    Payload before{};
    for (auto& b : before) b = static_cast<std::uint8_t>(rng());
    const std::uint64_t mask = length == 64 ? ~0ull : (1ull << length) - 1;
    std::uint64_t bits = rng() & mask;
    if (length > 53) bits &= (1ull << 52) - 1;  // exactly representable as a double
    const std::int64_t value = s.is_signed && length < 64 && ((bits >> (length - 1)) & 1) != 0
                                   ? static_cast<std::int64_t>(bits | ~mask)
                                   : static_cast<std::int64_t>(bits);
    Payload p = before;
    ASSERT_TRUE(s.encode(static_cast<double>(value), p)) << start << "|" << length;
    ASSERT_EQ(s.raw(p), value) << start << "|" << length
                               << (order == ByteOrder::kIntel ? "@1" : "@0");
    // the other bits are untouched: re-encoding the old raw value restores the old payload
    // (when that value is exact as a double)
    if (length > 53) continue;
    ASSERT_TRUE(s.encode(static_cast<double>(s.raw(before)), p));
    ASSERT_EQ(p, before);
  }
}

constexpr const char* kDbc = R"(VERSION ""
NS_ :
	CM_
	SG_MUL_VAL_
BS_:
BU_: A B
BO_ 416 WheelSpeeds: 8 A
 SG_ VehicleSpeed : 7|16@0+ (0.01,0) [0|655.35] "km/h" B
 SG_ Counter : 51|4@1+ (1,0) [0|15] "" B
BO_ 2566844926 CCVS1: 8 A
 SG_ WheelBasedVehicleSpeed : 8|16@1+ (0.00390625,0) [0|250.996] "km/h" B
BO_ 1024 Muxed: 4 A
 SG_ Mode M : 0|8@1+ (1,0) [0|255] "" B
 SG_ ValueA m1 : 8|16@1- (1e-1,-5) [-100|100] "deg/s" B
BO_ 3221225472 VECTOR__INDEPENDENT_SIG_MSG: 0 Vector__XXX
 SG_ Orphan : 0|8@1+ (1,0) [0|0] "" Vector__XXX
CM_ "a comment that spans lines
SG_ NotASignal : 0|8@1+ (1,0) [0|0] "" X
and ends here";
BA_ "GenMsgCycleTime" BO_ 416 10;
)";

TEST(DbcParse, MessagesSignalsAndTheExtendedFlag) {
  const auto db = parse_dbc(kDbc, "test.dbc");
  ASSERT_TRUE(db) << db.error().message;
  ASSERT_EQ(db->messages.size(), 3u);
  const Message* speed = db->find("WheelSpeeds");
  ASSERT_NE(speed, nullptr);
  EXPECT_EQ(speed->id, 416u);
  EXPECT_FALSE(speed->extended);
  EXPECT_EQ(speed->dlc, 8);
  ASSERT_EQ(speed->signals.size(), 2u);
  const Signal& v = speed->signals[0];
  EXPECT_EQ(v.name, "VehicleSpeed");
  EXPECT_EQ(v.start_bit, 7);
  EXPECT_EQ(v.length, 16);
  EXPECT_EQ(v.order, ByteOrder::kMotorola);
  EXPECT_FALSE(v.is_signed);
  EXPECT_DOUBLE_EQ(v.factor, 0.01);
  EXPECT_DOUBLE_EQ(v.max, 655.35);
  EXPECT_EQ(v.unit, "km/h");
  const Message* ccvs = db->find(0x18FEF1FE, true);
  ASSERT_NE(ccvs, nullptr);
  EXPECT_EQ(ccvs->name, "CCVS1");
  EXPECT_EQ(db->find(0x18FEF1FE, false), nullptr);
  const Message* mux = db->find("Muxed");
  ASSERT_NE(mux, nullptr);
  EXPECT_TRUE(mux->signals[0].multiplexer);
  EXPECT_EQ(mux->signals[1].multiplex_value, 1);
  EXPECT_TRUE(mux->signals[1].is_signed);
  EXPECT_DOUBLE_EQ(mux->signals[1].factor, 0.1);
  EXPECT_DOUBLE_EQ(mux->signals[1].offset, -5);
  EXPECT_EQ(db->find("VECTOR__INDEPENDENT_SIG_MSG"), nullptr);
}

// Each bad line must give "<file>:<line>: ..." with what is wrong.
TEST(DbcParse, ErrorsNameTheFileTheLineAndTheProblem) {
  struct Case {
    const char* text;
    const char* expected;
  };
  const Case cases[] = {
      {"BO_ 100 A: 8 X\n SG_ S : 0|8@2+ (1,0) [0|1] \"\" X\n",
       "bad.dbc:2: SG_ A.S: byte order must be @1"},
      {"BO_ 100 A: 2 X\n SG_ S : 8|16@1+ (1,0) [0|1] \"\" X\n",
       "bad.dbc:2: SG_ A.S: bits 8|16@1 do not fit the message's 2 bytes"},
      {"BO_ 100 A: 8 X\n SG_ S : 3|8@0+ (1,0) [0|1] \"\" X\n SG_ T : 59|8@0+ (1,0) [0|1] \"\" X\n",
       "bad.dbc:3: SG_ A.T: bits 59|8@0 do not fit"},
      {"\n SG_ S : 0|8@1+ (1,0) [0|1] \"\" X\n", "bad.dbc:2: SG_ outside a BO_ message"},
      {"BO_ 2048 A: 8 X\n", "bad.dbc:1: BO_ A: id 2048 does not fit 11 bits"},
      {"BO_ 1 A: 8 X\nBO_ 1 B: 8 X\n", "bad.dbc:2: BO_ B: id 1 is already used by A"},
      {"BO_ 1 A: 9 X\n", "bad.dbc:1: BO_ A: dlc 9 > 8"},
      {"BO_ 1 A: 8 X\n SG_ S : 0|8@1+ (0,0) [0|1] \"\" X\n", "factor must be non-zero"},
      // Issue 31: a factor of 1e308 made infinite odometry marked "ok".
      {"BO_ 1 A: 8 X\n SG_ S : 0|8@1+ (1e308,0) [0|1] \"\" X\n", "at most 1e9 in magnitude"},
      {"BO_ 1 A: 8 X\n SG_ S : 0|8@1+ (1,1e300) [0|1] \"\" X\n", "offset at most 1e15"},
      {"BO_ 1 A: 8 X\n SG_ S : 0|0@1+ (1,0) [0|1] \"\" X\n", "length 0 is not in 1..64"},
      {"BO_ 1 A: 8 X\n SG_ S : 0|8@1* (1,0) [0|1] \"\" X\n", "sign must be '+'"},
      {"BO_ 1 A: 8 X\n SG_ S : 0|8@1+ (1;0) [0|1] \"\" X\n",
       "bad.dbc:2: SG_ A.S: expected (factor,offset)"},
      {"BO_ 1 A: 8 X\n SG_ S : 0|8@1+ (1,0) [0|1] km X\n", "expected the unit in double quotes"},
      {"BO_ x A: 8 X\n", "bad.dbc:1: BO_: expected a numeric message id"},
      {"CM_ \"never closed\n", "a quoted string is never closed"},
  };
  for (const Case& c : cases) {
    const auto db = parse_dbc(c.text, "bad.dbc");
    ASSERT_FALSE(db) << c.text;
    EXPECT_NE(db.error().message.find(c.expected), std::string::npos)
        << "got: " << db.error().message << "\nwanted: " << c.expected;
  }
}

TEST(DbcParse, TheShippedVehicleDbcLoads) {
  const auto db =
      load_dbc(std::filesystem::path(::stac::testing::source_dir()) / "config/can/vehicle.dbc");
  ASSERT_TRUE(db) << db.error().message;
  EXPECT_NE(db->find("WheelSpeeds"), nullptr);
  EXPECT_NE(db->find("YawRate"), nullptr);
  const auto missing = load_dbc("/nonexistent/x.dbc");
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().message.find("/nonexistent/x.dbc"), std::string::npos);
}

}  // namespace
}  // namespace stac::can
