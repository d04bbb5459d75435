#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <string>

#include "drivers/velodyne/decoder.hpp"
#include "shared_data.hpp"
#include "sim/run.hpp"

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

// Dual return (S3): the last-return blocks carry a second echo where one physically occurs
// (through foliage, at edges), and the same return as the strongest block where there is one
// echo only (as Velodyne's manuals state for dual mode); of two echoes the last block holds the
// farther.
TEST(SimLidar, DualReturnGivesADifferentLastEchoOnVegetation) {
  STAC_REQUIRE_SHARED_DATA(kCalib);
  const velodyne::Calibration cal = calibration();
  RunConfig rc = config("urban", 4, 0.4);
  rc.lidar.dual_return = true;
  rc.lidar.model = velodyne::Model::kS3;
  auto run = SimRun::create(cal, rc);
  ASSERT_TRUE(run) << run.error().message;
  velodyne::DecoderConfig dc;
  dc.model = velodyne::Model::kS3;
  dc.min_range_m = 0.0f;
  dc.max_range_m = 200.0f;
  velodyne::PacketDecoder decoder(cal, dc);
  std::array<std::uint8_t, velodyne::kPacketSize> bytes{};
  std::size_t veg = 0, veg_differ = 0, solid = 0, solid_differ = 0, last_points = 0;
  std::size_t far_brighter = 0;  // two echoes, the last one the stronger
  for (std::uint32_t k = 0; k < (*run)->packet_count(); ++k) {
    std::map<int, BeamRecord> beams;  // strongest block * 64 + laser -> record
    std::int64_t first = 0;
    (*run)->packet(k, bytes, first, {}, [&](const BeamRecord& b) {
      if (b.returned) beams[b.block * 64 + b.laser] = b;
    });
    const velodyne::RawPacket* p = velodyne::as_packet(bytes);
    ASSERT_NE(p, nullptr);
    for (int block = 0; block < 12; ++block) {
      if (block % 4 >= 2) continue;  // the strongest blocks; block + 2 is the last-return one
      velodyne::Point strongest[32], last[32];
      const int ns = decoder.decode_block(p->blocks[block], block, true, 0, strongest);
      const int nl = decoder.decode_block(p->blocks[block + 2], block + 2, true, 0, last);
      ASSERT_EQ(ns, nl) << "every strongest return has a last-block return";
      last_points += static_cast<std::size_t>(nl);
      for (int i = 0; i < ns; ++i) {
        ASSERT_EQ(strongest[i].laser, last[i].laser);
        // The record names the block its echo is in: the strongest, or the last when swapped.
        auto it = beams.find(block * 64 + strongest[i].laser);
        if (it == beams.end()) it = beams.find((block + 2) * 64 + strongest[i].laser);
        ASSERT_NE(it, beams.end());
        const bool differ = std::abs(strongest[i].distance_m - last[i].distance_m) > 0.3f;
        const std::int64_t actor = it->second.actor;
        const bool vegetation =
            actor >= 0 &&
            ((*run)->world().actors()[static_cast<std::size_t>(actor)].cls == ObjectClass::kTree ||
             (*run)->world().actors()[static_cast<std::size_t>(actor)].cls == ObjectClass::kBush);
        if (vegetation) {
          ++veg;
          veg_differ += differ ? 1 : 0;
        } else {
          ++solid;
          solid_differ += differ ? 1 : 0;
        }
        // Where the last block differs, it holds the farther echo (the last return); the
        // strongest block the stronger, or, when the stronger is the last, the other one.
        if (differ) {
          EXPECT_GT(last[i].distance_m, strongest[i].distance_m);
          // Raw bytes: the decoded intensities carry a distance-dependent focal correction.
          const std::size_t j = strongest[i].laser % 32u;
          const int in_last = p->blocks[block + 2].returns[j].intensity;
          const int in_strongest = p->blocks[block].returns[j].intensity;
          far_brighter += in_last > in_strongest ? 1 : 0;
          // The record describes the main echo, the brighter one, in whichever block it went.
          if (it->second.block == block + 2) {
            EXPECT_GE(in_last, in_strongest);
          } else {
            EXPECT_EQ(it->second.block, block);
            EXPECT_GE(in_strongest, in_last);
          }
        }
      }
    }
  }
  std::printf(
      "dual return: %zu of %zu foliage beams and %zu of %zu others have a second echo; "
      "in %zu the last echo is the stronger\n",
      veg_differ, veg, solid_differ, solid, far_brighter);
  // Foliage before a brighter surface: the strongest echo is the last one, so the strongest
  // block holds the second strongest (REFERENCE.md, after valgur/velodyne_decoder).
  EXPECT_GT(far_brighter, 100u);
  EXPECT_GT(last_points, 200'000u);
  ASSERT_GT(veg, 500u);
  // Most beams into foliage have a second echo (the foliage or what is behind it).
  EXPECT_GT(static_cast<double>(veg_differ) / static_cast<double>(veg), 0.5)
      << veg_differ << " of " << veg;
  // On solid surfaces only edges give a second echo: some, but few.
  EXPECT_GT(solid_differ, 100u);
  EXPECT_LT(static_cast<double>(solid_differ) / static_cast<double>(solid), 0.1)
      << solid_differ << " of " << solid;
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
        points.push_back({static_cast<std::uint32_t>(b.actor), b.world_xyz[0], b.world_xyz[1],
                          b.world_xyz[2], b.time_s});
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

// A plan-view rectangle by its corners, for an overlap check written independently of the
// scenario code (corner containment and edge crossings, not separating axes).
struct Rect {
  double px[4], py[4];
};

Rect rect(double x, double y, double yaw, double length, double width) {
  const double c = std::cos(yaw), s = std::sin(yaw), l = length / 2, w = width / 2;
  const double lx[4] = {l, -l, -l, l}, ly[4] = {w, w, -w, -w};
  Rect r{};
  for (int i = 0; i < 4; ++i) {
    r.px[i] = x + c * lx[i] - s * ly[i];
    r.py[i] = y + s * lx[i] + c * ly[i];
  }
  return r;
}

bool inside(const Rect& r, double x, double y) {  // strictly inside (convex, either winding)
  int sign = 0;
  for (int i = 0; i < 4; ++i) {
    const int j = (i + 1) % 4;
    const double cross = (r.px[j] - r.px[i]) * (y - r.py[i]) - (r.py[j] - r.py[i]) * (x - r.px[i]);
    const int sg = cross > 1e-9 ? 1 : cross < -1e-9 ? -1 : 0;
    if (sg == 0) return false;
    if (sign == 0) sign = sg;
    if (sg != sign) return false;
  }
  return true;
}

bool segments_cross(double ax, double ay, double bx, double by, double cx, double cy, double dx,
                    double dy) {
  auto orient = [](double ox, double oy, double px, double py, double qx, double qy) {
    return (px - ox) * (qy - oy) - (py - oy) * (qx - ox);
  };
  const double o1 = orient(ax, ay, bx, by, cx, cy), o2 = orient(ax, ay, bx, by, dx, dy);
  const double o3 = orient(cx, cy, dx, dy, ax, ay), o4 = orient(cx, cy, dx, dy, bx, by);
  return ((o1 > 0) != (o2 > 0)) && ((o3 > 0) != (o4 > 0)) && o1 != 0 && o2 != 0 && o3 != 0 &&
         o4 != 0;
}

bool rects_overlap(const Rect& a, const Rect& b) {
  for (int i = 0; i < 4; ++i) {
    if (inside(a, b.px[i], b.py[i]) || inside(b, a.px[i], a.py[i])) return true;
    for (int j = 0; j < 4; ++j) {
      if (segments_cross(a.px[i], a.py[i], a.px[(i + 1) % 4], a.py[(i + 1) % 4], b.px[j], b.py[j],
                         b.px[(j + 1) % 4], b.py[(j + 1) % 4])) {
        return true;
      }
    }
  }
  return false;
}

// Every 0.05 s of the drive: no car, pedestrian or bicyclist inside the ego's footprint, and
// nobody inside a car (cars are kept apart from everyone, pedestrians and bicyclists from cars).
// Returns the number of overlaps found (with a description of the first few).
// With `people`, the pairs checked are instead pedestrian / pedestrian and pedestrian /
// bicyclist (and the ego is not checked).
std::size_t overlaps_in(const std::string& name, std::uint64_t seed, double duration,
                        std::string& first, bool people = false) {
  auto s = make_scenario(name, seed, duration);
  EXPECT_TRUE(s);
  if (!s) return 1;
  std::vector<std::size_t> fg;
  for (std::size_t i = 0; i < s->actors.size(); ++i) {
    if (is_foreground(s->actors[i].cls)) fg.push_back(i);
  }
  std::size_t found = 0;
  std::vector<Rect> boxes(fg.size());
  std::vector<Pose> poses(fg.size());
  const int steps = static_cast<int>(std::floor(duration / 0.05));
  for (int k = 0; k <= steps; ++k) {
    const double t = k * 0.05;
    const Pose e = s->ego_path.pose_at(t);
    const Rect ego = rect(e.x, e.y, e.yaw, kEgoLength, kEgoWidth);
    for (std::size_t n = 0; n < fg.size(); ++n) {
      const Actor& a = s->actors[fg[n]];
      poses[n] = a.path.pose_at(t);
      boxes[n] = rect(poses[n].x, poses[n].y, poses[n].yaw, a.size.x, a.size.y);
      if (!people && std::hypot(poses[n].x - e.x, poses[n].y - e.y) < 20 &&
          rects_overlap(boxes[n], ego)) {
        if (found++ < 3)
          first += "t=" + std::to_string(t) + " actor " + std::to_string(a.id) + " in the ego; ";
      }
    }
    for (std::size_t n = 0; n < fg.size(); ++n) {
      const Actor& a = s->actors[fg[n]];
      for (std::size_t m = n + 1; m < fg.size(); ++m) {
        const Actor& b = s->actors[fg[m]];
        const bool cars = a.cls == ObjectClass::kCar || b.cls == ObjectClass::kCar;
        const bool riders =
            (a.cls == ObjectClass::kPedestrian || a.cls == ObjectClass::kBicyclist) &&
            (b.cls == ObjectClass::kPedestrian || b.cls == ObjectClass::kBicyclist);
        if (people ? !riders : !cars) continue;
        if (std::hypot(poses[n].x - poses[m].x, poses[n].y - poses[m].y) >
            0.5 * (a.size.x + b.size.x) + 2)
          continue;
        if (rects_overlap(boxes[n], boxes[m])) {
          if (found++ < 3) {
            first += "t=" + std::to_string(t) + " actors " + std::to_string(a.id) + " and " +
                     std::to_string(b.id) + "; ";
          }
        }
      }
    }
  }
  return found;
}

TEST(Scenarios, NoActorEverOverlapsTheEgoOrACar) {
  struct Case {
    std::string name;
    std::uint64_t seed;
    double duration;
  };
  std::vector<Case> cases;
  for (std::uint64_t seed = 1; seed <= 5; ++seed) cases.push_back({"urban", seed, 20.0});
  cases.push_back({"urban", 5, 0.35});
  cases.push_back({"urban", 2, 3.0});
  cases.push_back({"urban", 9, 60.0});
  for (const std::string name : {"intersection", "highway", "parking-lot", "crowd"}) {
    for (std::uint64_t seed = 1; seed <= 3; ++seed) {
      cases.push_back({name, seed, 20.0});
      cases.push_back({name, seed + 10, 2.0});
    }
  }
  for (const Case& c : cases) {
    std::string first;
    EXPECT_EQ(overlaps_in(c.name, c.seed, c.duration, first), 0u)
        << c.name << " seed " << c.seed << " " << c.duration << " s: " << first;
  }
}

// Pedestrians and bicyclists keep clear of each other (two people in one box cannot be told
// apart by any segmenter; bicyclists queue in the bike lane): every 0.05 s of every scenario, no
// two of their footprints overlap.
TEST(Scenario, PedestriansAndBicyclistsNeverOverlap) {
  struct Case {
    std::string name;
    std::uint64_t seed;
    double duration;
  };
  std::vector<Case> cases;
  for (std::uint64_t seed : {1u, 2u, 3u, 4u, 5u, 2026u, 7777u})
    cases.push_back({"urban", seed, 20.0});
  cases.push_back({"urban", 9, 60.0});
  for (const std::string name : {"intersection", "parking-lot", "crowd"}) {
    for (std::uint64_t seed = 1; seed <= 3; ++seed) {
      cases.push_back({name, seed, 20.0});
      cases.push_back({name, seed + 10, 2.0});
    }
  }
  for (const Case& c : cases) {
    std::string first;
    EXPECT_EQ(overlaps_in(c.name, c.seed, c.duration, first, true), 0u)
        << c.name << " seed " << c.seed << " " << c.duration << " s: " << first;
  }
}

// Nothing stops dead or corners on rails: over every scenario, each road user's velocity (and
// the ego's) changes by at most its class's rate, measured over 0.5 s (the braking ramps: cars
// 2.5 m/s^2, bicyclists 1.5, pedestrians 1.0; cars' corners at most 3 m/s^2 sideways, taken on
// 8 chords, hence the margin).
TEST(Scenarios, SpeedsChangeAtBoundedRates) {
  struct Case {
    std::string name;
    std::uint64_t seed;
  };
  std::vector<Case> cases;
  for (std::uint64_t seed : {1u, 2u, 3u, 4u, 5u, 2026u, 5150u}) cases.push_back({"urban", seed});
  for (const std::string name : {"intersection", "highway", "parking-lot", "crowd"}) {
    for (std::uint64_t seed = 1; seed <= 3; ++seed) cases.push_back({name, seed});
  }
  const auto limit = [](ObjectClass c) {
    return c == ObjectClass::kCar ? 3.5 : c == ObjectClass::kBicyclist ? 2.0 : 1.5;
  };
  std::size_t pauses = 0;
  for (const Case& c : cases) {
    auto s = make_scenario(c.name, c.seed, 20.0);
    ASSERT_TRUE(s) << s.error().message;
    std::vector<std::pair<const Trajectory*, double>> paths = {
        {&s->ego_path, limit(ObjectClass::kCar)}};
    for (const Actor& a : s->actors) {
      if (is_foreground(a.cls) && a.path.points.size() > 1)
        paths.push_back({&a.path, limit(a.cls)});
    }
    for (const auto& [path, max_accel] : paths) {
      bool stood = false;
      for (double t = 0.0; t + 0.5 <= 20.0; t += 0.05) {
        const V3 v0 = path->velocity_at(t), v1 = path->velocity_at(t + 0.5);
        const double accel = std::hypot(v1.x - v0.x, v1.y - v0.y) / 0.5;
        ASSERT_LE(accel, max_accel)
            << c.name << " seed " << c.seed << " t=" << t << " s: from (" << v0.x << ", " << v0.y
            << ") to (" << v1.x << ", " << v1.y << ") m/s";
        if (std::hypot(v0.x, v0.y) < 1e-6 && t > 0.5) stood = true;
      }
      pauses += stood ? 1 : 0;
    }
  }
  EXPECT_GT(pauses, 20u) << "the scenarios should make road users wait (and so brake)";
}

// The sensor never ends up inside an object: over a 20 s urban drive (which stops at the
// crossing and meets traffic) every scan has at least 60 % of the median points.
TEST(SimRun, NoScanOfAnUrbanDriveIsSwallowed) {
  STAC_REQUIRE_SHARED_DATA(kCalib);
  const velodyne::Calibration cal = calibration();
  auto run = SimRun::create(cal, config("urban", 1, 20.0));
  ASSERT_TRUE(run) << run.error().message;
  std::vector<std::uint32_t> points;
  std::array<std::uint8_t, velodyne::kPacketSize> bytes{};
  for (std::uint32_t k = 0; k < (*run)->packet_count(); ++k) {
    std::int64_t first = 0;
    (*run)->packet(k, bytes, first, [&](const TruthScan& s) { points.push_back(s.points); });
  }
  ASSERT_GE(points.size(), 190u);
  std::vector<std::uint32_t> sorted = points;
  std::sort(sorted.begin(), sorted.end());
  const double median = sorted[sorted.size() / 2];
  EXPECT_GT(median, 90'000.0);
  for (std::size_t i = 0; i < points.size(); ++i) {
    EXPECT_GE(points[i], 0.6 * median) << "scan " << i;
  }
}

TEST(Scenarios, EachBuildsItsWorld) {
  for (const std::string& name : scenario_names()) {
    SCOPED_TRACE(name);
    auto s = make_scenario(name, 3, 20.0);
    ASSERT_TRUE(s) << s.error().message;
    std::map<ObjectClass, int> count;
    for (const Actor& a : s->actors) ++count[a.cls];
    if (name == "empty") {
      EXPECT_EQ(count[ObjectClass::kCar] + count[ObjectClass::kPedestrian] +
                    count[ObjectClass::kBicyclist],
                0);
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
