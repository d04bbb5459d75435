#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <set>

#include "drivers/velodyne/decoder.hpp"
#include "sim/run.hpp"
#include "shared_data.hpp"

namespace stac::sim {
namespace {

constexpr const char* kCalib = "velodyne/calib/rosdrivers_64e_s2.1-sztaki.yaml";

velodyne::Calibration calibration() {
  auto c = velodyne::load_calibration(stac::testing::shared_data(kCalib));
  EXPECT_TRUE(c) << c.error().message;
  return *c;
}

RunConfig config(const std::string& scenario, std::uint64_t seed, double seconds) {
  RunConfig rc;
  rc.scenario = scenario;
  rc.seed = seed;
  rc.duration_s = seconds;
  rc.lidar.seed = seed;
  return rc;
}

// Closing the loop: decoding the simulated packets gives back every hit (before noise) within
// 3 mm, the 2 mm range quantisation being the only error left.
TEST(SimLidar, DecoderReturnsEveryHitWithin3mm) {
  STAC_REQUIRE_SHARED_DATA(kCalib);
  const velodyne::Calibration cal = calibration();
  RunConfig rc = config("urban", 11, 0.3);
  rc.lidar.range_noise_m = 0.0;
  rc.lidar.dropout = 0.0;
  auto run = SimRun::create(cal, rc);
  ASSERT_TRUE(run) << run.error().message;
  velodyne::DecoderConfig dc;
  dc.model = velodyne::Model::kS2_1;
  dc.min_range_m = 0.0f;
  dc.max_range_m = 200.0f;
  velodyne::PacketDecoder decoder(cal, dc);
  std::array<std::uint8_t, velodyne::kPacketSize> bytes{};
  std::size_t compared = 0;
  double worst = 0.0;
  for (std::uint32_t k = 0; k < (*run)->packet_count(); ++k) {
    std::map<int, BeamRecord> beams;  // block * 64 + laser -> record
    std::int64_t first = 0;
    (*run)->packet(k, bytes, first, {}, [&](const BeamRecord& b) {
      if (b.returned) beams[b.block * 64 + b.laser] = b;
    });
    const velodyne::RawPacket* p = velodyne::as_packet(bytes);
    ASSERT_NE(p, nullptr);
    std::size_t decoded = 0;
    for (int block = 0; block < 12; ++block) {
      velodyne::Point out[32];
      const int n = decoder.decode_block(p->blocks[block], block, false, 0, out);
      for (int i = 0; i < n; ++i) {
        const auto it = beams.find(block * 64 + out[i].laser);
        ASSERT_NE(it, beams.end()) << "a decoded point the simulator did not hit";
        const double* s = it->second.sensor_xyz;
        const double err = std::hypot(out[i].x - s[0], out[i].y - s[1], out[i].z - s[2]);
        worst = std::max(worst, err);
        ++compared;
        ++decoded;
      }
    }
    ASSERT_EQ(decoded, beams.size()) << "packet " << k;
  }
  EXPECT_GT(compared, 300'000u);
  EXPECT_LT(worst, 0.003);
}

TEST(SimRun, SameScenarioAndSeedGiveIdenticalBytes) {
  STAC_REQUIRE_SHARED_DATA(kCalib);
  const velodyne::Calibration cal = calibration();
  auto collect = [&](std::uint64_t seed) {
    auto run = SimRun::create(cal, config("urban", seed, 0.25));
    EXPECT_TRUE(run);
    std::string all;
    std::array<std::uint8_t, velodyne::kPacketSize> bytes{};
    for (std::uint32_t k = 0; k < (*run)->packet_count(); ++k) {
      std::int64_t first = 0;
      (*run)->packet(k, bytes, first, [&](const TruthScan& s) { all += to_json(s); });
      all.append(reinterpret_cast<const char*>(bytes.data()), bytes.size());
    }
    return all;
  };
  const std::string a = collect(5), b = collect(5), c = collect(6);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
}

// Truth consistent with the points: the returns of each object lie in its truth box, moved
// with the truth velocity to the time each return was fired.
TEST(SimRun, TruthBoxesHoldTheirObjectsPoints) {
  STAC_REQUIRE_SHARED_DATA(kCalib);
  const velodyne::Calibration cal = calibration();
  auto run = SimRun::create(cal, config("urban", 21, 1.2));
  ASSERT_TRUE(run);
  struct P {
    std::uint32_t actor;
    double x, y, z, t;
  };
  std::vector<P> points;
  std::vector<TruthScan> scans;
  std::array<std::uint8_t, velodyne::kPacketSize> bytes{};
  std::size_t in_scan = 0, inside = 0, total = 0;
  std::map<std::string, std::size_t> per_class;
  auto check = [&](const TruthScan& s) {
    std::map<std::uint32_t, const TruthObject*> by_id;
    std::map<std::uint32_t, std::uint32_t> counted;
    for (const auto& o : s.objects) by_id[o.id] = &o;
    for (const P& p : points) {
      const Actor& a = (*run)->world().actors()[p.actor];
      ++counted[a.id];
      if (!is_foreground(a.cls)) continue;
      const auto it = by_id.find(a.id);
      ASSERT_NE(it, by_id.end());
      const TruthObject& o = *it->second;
      const double c = std::cos(o.yaw), sn = std::sin(o.yaw);
      // The box is given at o.time_s; at the point's firing time it has moved by v * dt (an
      // object ahead is swept at the start and at the end of a scan cut there).
      const double dt = p.t - o.time_s;
      const double dx = p.x - (o.x + o.vx * dt), dy = p.y - (o.y + o.vy * dt);
      const double lx = c * dx + sn * dy, ly = -sn * dx + c * dy, lz = p.z - o.z;
      const double tol = 0.1;
      ++total;
      if (std::abs(lx) <= o.length / 2 + tol && std::abs(ly) <= o.width / 2 + tol &&
          std::abs(lz) <= o.height / 2 + tol) {
        ++inside;
      }
      ++per_class[std::string(class_name(a.cls))];
    }
    for (const auto& o : s.objects) EXPECT_EQ(o.points, counted[o.id]) << "object " << o.id;
    points.clear();
    ++in_scan;
  };
  for (std::uint32_t k = 0; k < (*run)->packet_count(); ++k) {
    std::int64_t first = 0;
    (*run)->packet(k, bytes, first, check, [&](const BeamRecord& b) {
      if (b.returned && b.actor >= 0) {
        points.push_back({static_cast<std::uint32_t>(b.actor), b.world_xyz[0], b.world_xyz[1], b.world_xyz[2],
                          b.time_s});
      }
    });
  }
  EXPECT_GE(in_scan, 11u);
  EXPECT_GT(total, 10'000u);
  EXPECT_GE(static_cast<double>(inside) / static_cast<double>(total), 0.995)
      << inside << " of " << total;
  EXPECT_GT(per_class["car"], 1000u);
  EXPECT_GT(per_class["pedestrian"], 50u);
}

TEST(Scenarios, EachBuildsItsWorld) {
  for (const std::string& name : scenario_names()) {
    SCOPED_TRACE(name);
    auto s = make_scenario(name, 3, 20.0);
    ASSERT_TRUE(s) << s.error().message;
    std::map<ObjectClass, int> count;
    for (const Actor& a : s->actors) ++count[a.cls];
    if (name == "empty") {
      EXPECT_EQ(count[ObjectClass::kCar] + count[ObjectClass::kPedestrian] + count[ObjectClass::kBicyclist], 0);
      EXPECT_GT(count[ObjectClass::kBuilding], 5);
    } else if (name == "highway") {
      EXPECT_GE(count[ObjectClass::kCar], 30);
      EXPECT_EQ(count[ObjectClass::kPedestrian], 0);
    } else if (name == "crowd") {
      EXPECT_GE(count[ObjectClass::kPedestrian], 150);
    } else {
      EXPECT_GT(count[ObjectClass::kCar], 10);
      EXPECT_GT(count[ObjectClass::kPedestrian], 10);
      EXPECT_GE(count[ObjectClass::kBicyclist], 2);
    }
  }
  EXPECT_FALSE(make_scenario("moon", 1, 10));
}

}  // namespace
}  // namespace stac::sim
