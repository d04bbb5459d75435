#include "drivers/velodyne/decoder.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <set>

#include "drivers/velodyne/beam.hpp"
#include "drivers/velodyne/calibration.hpp"
#include "drivers/velodyne/packet_builder.hpp"
#include "shared_data.hpp"

namespace stac::velodyne {
namespace {

using stac::testing::shared_data;

constexpr const char* kSample = "velodyne/hdl64e_s2_manual_sample_packet_1206B.bin";
constexpr const char* kSztakiYaml = "velodyne/calib/rosdrivers_64e_s2.1-sztaki.yaml";

std::vector<std::uint8_t> read_file(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

Calibration sztaki() {
  auto c = load_calibration(shared_data(kSztakiYaml));
  EXPECT_TRUE(c) << (c ? "" : c.error().message);
  return *c;
}

static_assert(noexcept(std::declval<PacketDecoder&>().decode_block(std::declval<const RawBlock&>(),
                                                                   0, false, 0, nullptr)));

TEST(PacketDecoder, RealS2SamplePacketGivesPlausiblePoints) {
  STAC_REQUIRE_SHARED_DATA(kSample);
  const auto bytes = read_file(shared_data(kSample));
  ASSERT_EQ(bytes.size(), kPacketSize);
  const RawPacket* packet = as_packet(bytes);
  ASSERT_NE(packet, nullptr);
  // Old-firmware trailer: spin count 9 and "v26b".
  const SpinTrailer trailer = read_spin_trailer(*packet);
  EXPECT_EQ(trailer.spin_count, 9);
  EXPECT_EQ(std::string(reinterpret_cast<const char*>(trailer.info), 4), "v26b");

  PacketDecoder decoder(sztaki(), DecoderConfig{});
  std::vector<Point> points;
  for (int b = 0; b < kBlocksPerPacket; ++b) {
    EXPECT_EQ(packet->blocks[b].bank, b % 2 == 0 ? kUpperBank : kLowerBank);
    EXPECT_EQ(packet->blocks[b].rotation, 450);
    Point out[kLasersPerBlock];
    const int n = decoder.decode_block(packet->blocks[b], b, false, 0, out);
    points.insert(points.end(), out, out + n);
  }
  EXPECT_EQ(points.size(), 384u);  // every return present, 2.1-3.2 m raw
  std::set<int> lasers;
  for (const Point& p : points) {
    lasers.insert(p.laser);
    // A wall about 4 m ahead, a few degrees right of the sensor's forward axis.
    EXPECT_GT(p.x, 3.0f);
    EXPECT_LT(p.x, 5.0f);
    EXPECT_LT(std::abs(p.y), 1.2f);
    EXPECT_GT(p.z, -2.0f);
    EXPECT_LT(p.z, 0.7f);  // top beam +4.97 deg at about 4.5 m, plus its ~0.2 m offset
    EXPECT_GE(p.intensity, 0.0f);
    EXPECT_LE(p.intensity, 255.0f);
    EXPECT_EQ(p.azimuth, 450);
  }
  EXPECT_EQ(lasers.size(), 64u);
}

// Expected values computed by hand (double precision, the REFERENCE §1 formulas written out
// independently) from the sample packet and the sztaki ROS yaml.
TEST(PacketDecoder, MatchesHandComputedCorrections) {
  STAC_REQUIRE_SHARED_DATA(kSample);
  const auto bytes = read_file(shared_data(kSample));
  const RawPacket* packet = as_packet(bytes);
  ASSERT_NE(packet, nullptr);
  struct Expect {
    int block, j, laser;
    double distance, x, y, z, intensity_cm, intensity_ros;
  };
  const Expect cases[] = {
      {0, 0, 0, 4.309526, 4.208917, -0.847561, -0.464263, 108.5580, 75.4393},
      {0, 5, 5, 4.383579, 4.430358, -0.170612, -0.366140, 77.2568, 73.0975},
      {1, 0, 32, 3.908182, 3.578233, -0.745082, -1.413442, 76.9158, 45.0000},
      {1, 31, 63, 4.550974, 4.522067, -0.268906, -0.845087, 106.5458, 98.3467},
      {6, 17, 17, 4.159452, 4.191905, -0.163214, 0.120633, 81.5502, 65.0559},
      {11, 31, 63, 4.556974, 4.527911, -0.269221, -0.846339, 107.5275, 99.3650},
  };
  DecoderConfig ros_cfg;
  ros_cfg.ros_intensity_units = true;
  PacketDecoder decoder(sztaki(), DecoderConfig{});
  PacketDecoder ros(sztaki(), ros_cfg);
  for (const Expect& e : cases) {
    SCOPED_TRACE("block " + std::to_string(e.block) + " laser " + std::to_string(e.laser));
    Point out[kLasersPerBlock];
    Point out_ros[kLasersPerBlock];
    ASSERT_EQ(decoder.decode_block(packet->blocks[e.block], e.block, false, 0, out), 32);
    ASSERT_EQ(ros.decode_block(packet->blocks[e.block], e.block, false, 0, out_ros), 32);
    const Point& p = out[e.j];
    EXPECT_EQ(p.laser, e.laser);
    EXPECT_NEAR(p.distance_m, e.distance, 1e-5);
    EXPECT_NEAR(p.x, e.x, 1e-4);
    EXPECT_NEAR(p.y, e.y, 1e-4);
    EXPECT_NEAR(p.z, e.z, 1e-4);
    EXPECT_NEAR(p.intensity, e.intensity_cm, 1e-2);
    EXPECT_NEAR(out_ros[e.j].intensity, e.intensity_ros, 1e-2);
    EXPECT_EQ(out_ros[e.j].x, p.x);  // intensity units change nothing else
  }
}

TEST(PacketDecoder, TwoPointGateChangesOnlyFarPoints) {
  STAC_REQUIRE_SHARED_DATA(kSztakiYaml);
  DecoderConfig gated;
  gated.gate_two_point_correction = true;
  PacketDecoder plain(sztaki(), DecoderConfig{});
  PacketDecoder gate(sztaki(), gated);
  PacketBuilder b;
  b.set_block(0, kUpperBank, 0);  // straight ahead: xx small, yy = range
  for (int j = 0; j < kLasersPerBlock; ++j)
    b.set_return(0, j, j < 16 ? 5000 : 30000, 50);  // 10 m, 60 m
  const RawPacket* packet = as_packet(b.bytes());
  Point a[32], g[32];
  ASSERT_EQ(plain.decode_block(packet->blocks[0], 0, false, 0, a), 32);
  ASSERT_EQ(gate.decode_block(packet->blocks[0], 0, false, 0, g), 32);
  for (int j = 0; j < 16; ++j) EXPECT_EQ(a[j].x, g[j].x) << j;  // 10 m: below the gate
  int changed = 0;
  for (int j = 16; j < 32; ++j) changed += std::abs(a[j].x - g[j].x) > 1e-3f ? 1 : 0;
  EXPECT_EQ(changed, 16);  // 60 m: ROS extrapolates the correction, the gate drops it
}

TEST(PacketDecoder, DropsNoReturnAndOutOfRange) {
  STAC_REQUIRE_SHARED_DATA(kSztakiYaml);
  PacketDecoder decoder(sztaki(), DecoderConfig{});
  PacketBuilder b;
  b.set_block(0, kLowerBank, 100);
  b.set_return(0, 0, 0, 10);      // no return
  b.set_return(0, 1, 1, 10);      // 2 mm + ~1.5 m correction: in range
  b.set_return(0, 2, 65535, 10);  // 131 m + correction: beyond 130 m
  b.set_return(0, 3, 2000, 10);
  const RawPacket* packet = as_packet(b.bytes());
  Point out[32];
  const int n = decoder.decode_block(packet->blocks[0], 0, false, 0, out);
  EXPECT_EQ(n, 2);
  EXPECT_EQ(decoder.counters().no_return, 29u);
  EXPECT_EQ(decoder.counters().out_of_range, 1u);
  EXPECT_EQ(out[0].laser, 33);
  EXPECT_EQ(out[1].laser, 35);
}

TEST(PacketDecoder, FiringTimesFollowTheModel) {
  STAC_REQUIRE_SHARED_DATA(kSztakiYaml);
  DecoderConfig s3;
  s3.model = Model::kS3;
  PacketDecoder s2_decoder(sztaki(), DecoderConfig{});
  PacketDecoder s3_decoder(sztaki(), s3);
  // S2: 48 us per firing (block pair), 6 us per group of 4 lasers, {0,1.26,2.46,3.66} in group.
  EXPECT_EQ(s2_decoder.firing_offset_ns(3, 5, false), 48000 + 6000 + 1260);
  EXPECT_EQ(s2_decoder.firing_offset_ns(11, 31, false), 5 * 48000 + 7 * 6000 + 3660);
  // S3 dual: 4 blocks per firing, 57.6 / 7.2 us.
  EXPECT_EQ(s3_decoder.firing_offset_ns(5, 10, true), 57600 + 2 * 7200 + 2500);
  EXPECT_EQ(s3_decoder.firing_offset_ns(5, 10, false), 2 * 57600 + 2 * 7200 + 2500);
  EXPECT_EQ(s2_decoder.packet_span_ns(false), 5 * 48000 + 7 * 6000 + 3660);
}

TEST(PacketDecoder, RingsSortLasersByElevation) {
  STAC_REQUIRE_SHARED_DATA(kSztakiYaml);
  const Calibration c = sztaki();
  PacketDecoder decoder(c, DecoderConfig{});
  std::vector<std::pair<int, double>> by_ring;
  std::set<int> rings;
  for (int l = 0; l < 64; ++l) {
    rings.insert(decoder.ring_of(l));
    by_ring.emplace_back(decoder.ring_of(l),
                         c.lasers[static_cast<std::size_t>(l)].vert_correction_rad);
  }
  EXPECT_EQ(rings.size(), 64u);
  std::sort(by_ring.begin(), by_ring.end());
  for (std::size_t i = 1; i < by_ring.size(); ++i)
    EXPECT_LE(by_ring[i - 1].second, by_ring[i].second);
}

TEST(PacketDecoder, ParsesModelNames) {
  EXPECT_EQ(parse_model("S2"), Model::kS2);
  EXPECT_EQ(parse_model("hdl-64e s2.1"), Model::kS2_1);
  EXPECT_EQ(parse_model("S3"), Model::kS3);
  EXPECT_EQ(parse_model("VLP-16"), Model::kVlp16);
  EXPECT_FALSE(parse_model("VLS-128"));
}

}  // namespace
}  // namespace stac::velodyne

namespace stac::velodyne {
namespace {

// The vectorised decoder against the double-precision reference, over every laser of every
// real calibration, all rotations in steps, and distances from 1 to 120 m.
TEST(PacketDecoder, AgreesWithTheReferenceBeamMath) {
  for (const char* file :
       {"velodyne/calib/rosdrivers_64e_s2.1-sztaki.yaml",
        "velodyne/calib/rosdrivers_64e_s3-xiesc.yaml", "velodyne/calib/veloview_HDL-64.xml"}) {
    STAC_REQUIRE_SHARED_DATA(file);
    auto c = load_calibration(stac::testing::shared_data(file));
    ASSERT_TRUE(c) << c.error().message;
    for (bool gate : {false, true}) {
      DecoderConfig cfg;
      cfg.gate_two_point_correction = gate;
      cfg.min_range_m = 0.0f;
      cfg.max_range_m = 200.0f;
      PacketDecoder decoder(*c, cfg);
      double worst = 0.0;
      for (std::uint16_t rotation = 0; rotation < 36000; rotation += 97) {
        for (int bank = 0; bank < 2; ++bank) {
          PacketBuilder b;
          b.set_block(0, bank == 0 ? kUpperBank : kLowerBank, rotation);
          for (int j = 0; j < 32; ++j)
            b.set_return(0, j, static_cast<std::uint16_t>(500 + 1850 * j), 100);
          Point out[32];
          ASSERT_EQ(decoder.decode_block(as_packet(b.bytes())->blocks[0], 0, false, 0, out), 32);
          for (int j = 0; j < 32; ++j) {
            const LaserCalibration& l = c->lasers[static_cast<std::size_t>(bank * 32 + j)];
            const double d = (500 + 1850 * j) * c->distance_resolution_m + l.dist_correction_m;
            const Vec3 ref = beam_point(l, rotation, d, gate);
            const double err = std::hypot(out[j].x - ref[0], out[j].y - ref[1], out[j].z - ref[2]);
            worst = std::max(worst, err);
          }
        }
      }
      // Single precision over 120 m: a few tens of micrometres.
      EXPECT_LT(worst, 1e-4) << file << " gate " << gate;
    }
  }
}

TEST(BeamLine, IsTheDecodedPointAlongTheBeam) {
  STAC_REQUIRE_SHARED_DATA("velodyne/calib/rosdrivers_64e_s2.1-sztaki.yaml");
  auto c = load_calibration(
      stac::testing::shared_data("velodyne/calib/rosdrivers_64e_s2.1-sztaki.yaml"));
  ASSERT_TRUE(c);
  for (int laser : {0, 17, 40, 63}) {
    const LaserCalibration& l = c->lasers[static_cast<std::size_t>(laser)];
    for (int r : {0, 4500, 12345, 27000, 35999}) {
      const auto rotation = static_cast<std::uint16_t>(r);
      const BeamLine line = beam_line(l, rotation, 20.0, false);
      for (double d : {15.0, 20.0, 24.0}) {
        const Vec3 p = beam_point(l, rotation, d, false);
        for (int i = 0; i < 3; ++i) EXPECT_NEAR(line.origin[i] + line.direction[i] * d, p[i], 1e-6);
      }
      const double norm = std::hypot(line.direction[0], line.direction[1], line.direction[2]);
      EXPECT_NEAR(norm, 1.0, 0.01);  // the corrections bend the scale by at most a percent
    }
  }
}

}  // namespace
}  // namespace stac::velodyne
