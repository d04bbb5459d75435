#include "perception/segmentation/segmenter.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <type_traits>

#include "rt/testing/alloc_counter.hpp"
#include "segmentation/scenes.hpp"

namespace stac::segmentation {
namespace {

using testing::Scene;

static_assert(noexcept(std::declval<Segmenter&>().segment(std::declval<const PointView&>(),
                                                          std::declval<Segments&>())));

SegmenterConfig test_config() {
  SegmenterConfig c;
  c.range_m = 30.0;
  return c;
}

Segments run(const Scene& scene, const SegmenterConfig& config = test_config()) {
  Segmenter segmenter(config);
  Segments out = segmenter.make_segments();
  segmenter.segment(scene.view(), out);
  return out;
}

std::uint64_t accounted(const SegmentCounters& k) {
  return k.ignored_invalid + k.ignored_out_of_range + k.ignored_over_capacity + k.ignored_below +
         k.dropped_cell_overflow + k.ground_points + k.ignored_above + k.obstacle_points;
}

TEST(Segmenter, TwoBoxesOneMetreApartAreTwoSegments) {
  Scene scene;
  scene.flat_ground();
  scene.box(8.0f, 0.0f, 2.0f, 1.0f, 1.2f);
  scene.box(8.0f, 2.0f, 2.0f, 1.0f, 1.2f);  // gap 1 m between the boxes
  const Segments out = run(scene);
  ASSERT_EQ(out.segments.size(), 2u);
  EXPECT_EQ(accounted(out.counters), scene.size());
  for (const Segment& s : out.segments) {
    EXPECT_NEAR(s.centroid[0], 8.0f, 0.1f);
    EXPECT_NEAR(s.box.length, 2.0f, 0.2f);
    EXPECT_NEAR(s.box.width, 1.0f, 0.2f);
    EXPECT_NEAR(std::fabs(s.box.yaw), 0.0f, 0.05f);  // long side along x
    EXPECT_NEAR(s.z_max, -testing::kSensorHeight + 1.2f, 0.06f);
    EXPECT_EQ(out.indices(s).size(), s.count);
  }
  EXPECT_NEAR(out.segments[0].centroid[1] + out.segments[1].centroid[1], 2.0f, 0.1f);
  EXPECT_EQ(out.counters.dropped_segment_overflow + out.counters.dropped_cell_overflow, 0u);
}

TEST(Segmenter, TouchingBoxesAreOneSegment) {
  Scene scene;
  scene.flat_ground();
  scene.box(8.0f, 0.0f, 2.0f, 1.0f, 1.2f);
  scene.box(8.0f, 1.0f, 2.0f, 1.0f, 1.2f);
  const Segments out = run(scene);
  ASSERT_EQ(out.segments.size(), 1u);
  EXPECT_NEAR(out.segments[0].box.length, 2.0f, 0.2f);
  EXPECT_NEAR(out.segments[0].box.width, 2.0f, 0.2f);
}

TEST(Segmenter, SegmentIndicesPointAtObstaclePointsOnly) {
  Scene scene;
  scene.flat_ground();
  scene.box(-6.0f, 5.0f, 1.0f, 1.0f, 1.0f);
  const Segments out = run(scene);
  ASSERT_EQ(out.segments.size(), 1u);
  const Segment& s = out.segments[0];
  EXPECT_EQ(s.count, out.counters.obstacle_points);
  for (const std::uint32_t i : out.indices(s)) {
    const float* p = scene.xyzi.data() + 4 * i;
    EXPECT_NEAR(p[0], -6.0f, 0.51f);
    EXPECT_NEAR(p[1], 5.0f, 0.51f);
    EXPECT_GT(p[2],
              -testing::kSensorHeight + test_config().ground_clearance_m);  // above the clearance
  }
}

TEST(Segmenter, SlopedRoadAndCurbGiveNoSegment) {
  Scene scene;
  // 5% slope along x and a 15 cm curb (sidewalk) for y > 3 m; plus road camber noise.
  scene.ground(25.0f, 0.1f, [](float x, float y) {
    return 0.05f * x + (y > 3.0f ? 0.15f : 0.0f) + 0.01f * std::sin(7.0f * x + 3.0f * y);
  });
  const Segments out = run(scene);
  EXPECT_EQ(out.segments.size(), 0u);
  EXPECT_EQ(out.counters.obstacle_cells, 0u);
  EXPECT_EQ(out.counters.ground_points,
            scene.size() - out.counters.ignored_out_of_range - out.counters.ignored_over_capacity);
}

TEST(Segmenter, PedestrianOnSidewalkOfSlopedRoadIsFound) {
  Scene scene;
  scene.ground(20.0f, 0.1f, [](float x, float y) { return 0.05f * x + (y > 3.0f ? 0.15f : 0.0f); });
  // A 1.7 m pedestrian on the sidewalk at x = 10 (ground there 0.5 + 0.15 m above the flat road).
  Scene person;
  person.cylinder(10.0f, 5.0f, 0.25f, 1.7f);
  for (std::size_t i = 0; i < person.size(); ++i) {
    scene.add(person.xyzi[4 * i], person.xyzi[4 * i + 1], person.xyzi[4 * i + 2] + 0.65f);
  }
  const Segments out = run(scene);
  ASSERT_EQ(out.segments.size(), 1u);
  EXPECT_NEAR(out.segments[0].centroid[0], 10.0f, 0.1f);
  EXPECT_NEAR(out.segments[0].centroid[1], 5.0f, 0.1f);
}

// Of two segments, the smaller one; the larger is the 4.5 x 1.8 m car beside it.
const Segment& beside_the_car(const Segments& out) {
  const Segment& car =
      out.segments[0].count > out.segments[1].count ? out.segments[0] : out.segments[1];
  EXPECT_NEAR(car.box.length, 4.5f, 0.2f);
  EXPECT_NEAR(car.box.width, 1.8f, 0.2f);
  return &car == &out.segments[0] ? out.segments[1] : out.segments[0];
}

TEST(Segmenter, PedestrianHalfAMetreFromCarIsSeparate) {
  Scene scene;
  scene.flat_ground();
  scene.box(10.0f, 0.0f, 4.5f, 1.8f, 1.5f);                 // car, side at y = 0.9
  scene.cylinder(10.0f, 0.9f + 0.5f + 0.25f, 0.25f, 1.7f);  // pedestrian 0.5 m from its side
  const Segments out = run(scene);
  ASSERT_EQ(out.segments.size(), 2u);
  const Segment& ped = beside_the_car(out);
  EXPECT_NEAR(ped.centroid[1], 1.65f, 0.1f);
  EXPECT_NEAR(ped.box.length, 0.5f, 0.15f);
}

// A car beside the sensor: its near side, and its roof hit by two rings 0.85 and 1.75 m behind
// it; nothing is seen between them (the roof between rings is not sampled, the road is hidden).
Scene car_with_roof_rings() {
  Scene scene;
  scene.ground(20.0f, 0.1f, [](float, float) { return 0.0f; });
  Scene kept;
  for (std::size_t i = 0; i < scene.size(); ++i) {
    const float x = scene.xyzi[4 * i], y = scene.xyzi[4 * i + 1];
    if (std::fabs(x) < 2.5f && y > 7.6f && y < 11.0f) continue;  // hidden by the car
    kept.add(x, y, scene.xyzi[4 * i + 2]);
  }
  for (float x = -2.0f; x <= 2.0f; x += 0.05f) {
    for (float z = -1.5f; z <= -0.25f; z += 0.05f) kept.add(x, 7.65f, z);
    kept.add(x, 8.5f, -0.25f);
    kept.add(x, 9.4f, -0.25f);
  }
  return kept;
}

TEST(Segmenter, CarRoofRingsAcrossUnseenCellsAreOneSegment) {
  const Scene scene = car_with_roof_rings();
  const Segments out = run(scene);
  ASSERT_EQ(out.segments.size(), 1u);
  EXPECT_NEAR(out.segments[0].box.width, 9.4f - 7.65f, 0.1f);
  SegmenterConfig no_bridge = test_config();
  no_bridge.bridge_m = 0.0;
  EXPECT_EQ(run(scene, no_bridge).segments.size(), 3u);  // side and two roof lines
}

TEST(Segmenter, SeenGroundKeepsObjectsOnOneRayApart) {
  Scene scene;
  scene.flat_ground();
  scene.cylinder(0.0f, 8.0f, 0.25f, 1.8f);
  scene.cylinder(0.0f, 9.2f, 0.25f, 1.8f);  // 0.7 m behind the first, ground visible between
  EXPECT_EQ(run(scene).segments.size(), 2u);
}

// A car 30 m ahead as the sensor sees it: the rear face of its body (0.35..0.8 m above the
// road), the road under the body between the wheels, and 1.3 m further the rear of its cabin
// (0.95..1.35 m); the road beyond is in the car's shadow.
Scene far_car_with_road_under_its_body() {
  Scene scene;
  scene.ground(40.0f, 0.1f, [](float, float) { return 0.0f; });
  Scene kept;
  const float g = -testing::kSensorHeight;
  for (std::size_t i = 0; i < scene.size(); ++i) {
    const float x = scene.xyzi[4 * i], y = scene.xyzi[4 * i + 1];
    const bool under_body = x > 30.1f && x < 31.2f;
    if (x > 30.0f && std::fabs(y) < 0.9f && !under_body) continue;  // hidden by the car
    if (x < 24.0f || std::fabs(y) > 6.0f) continue;                 // keep the scene small
    kept.add(x, y, scene.xyzi[4 * i + 2]);
  }
  for (float y = -0.9f; y <= 0.9f; y += 0.05f) {
    for (float z = 0.35f; z <= 0.8f; z += 0.15f) kept.add(30.0f, y, g + z);
    for (float z = 0.95f; z <= 1.35f; z += 0.2f) kept.add(31.3f, y, g + z);
  }
  return kept;
}

SegmenterConfig overhang_config() {
  SegmenterConfig c = test_config();
  c.range_m = 40.0;
  c.overhang_m = 0.25;
  return c;
}

TEST(Segmenter, RoadSeenUnderACarBodyDoesNotSplitTheCar) {
  const Scene scene = far_car_with_road_under_its_body();
  const Segments out = run(scene, overhang_config());
  ASSERT_EQ(out.segments.size(), 1u);
  EXPECT_NEAR(out.segments[0].box.width, 1.3f, 0.1f);  // rear face to cabin, along x
  EXPECT_NEAR(out.segments[0].box.length, 1.8f, 0.1f);
  SegmenterConfig off = overhang_config();
  off.overhang_m = 0.0;  // the seen road ends the walk: body face and cabin apart
  EXPECT_EQ(run(scene, off).segments.size(), 2u);
  SegmenterConfig flat = overhang_config();
  flat.overhang_height_m = 0.3;  // the cabin's top is 0.55 m above the body's: not linked
  EXPECT_EQ(run(scene, flat).segments.size(), 2u);
}

TEST(Segmenter, RoadSeenBetweenStandingObjectsStillKeepsThemApartWithOverhangs) {
  Scene scene;
  scene.flat_ground();
  scene.cylinder(0.0f, 8.0f, 0.25f, 1.8f);  // reach the ground: no overhang
  scene.cylinder(0.0f, 9.2f, 0.25f, 1.8f);
  SegmenterConfig c = test_config();
  c.overhang_m = 0.25;
  EXPECT_EQ(run(scene, c).segments.size(), 2u);
}

TEST(Segmenter, PedestrianUnderATreeCanopyIsNotJoinedToTheTree) {
  Scene scene;
  scene.flat_ground();
  scene.cylinder(10.0f, 0.0f, 0.2f, 2.8f);       // trunk
  for (float x = 7.5f; x <= 12.5f; x += 0.1f) {  // canopy 2.8..3.4 m above the ground
    for (float y = -2.5f; y <= 2.5f; y += 0.1f) {
      if (std::hypot(x - 10.0f, y) > 2.5f) continue;
      for (float z = 2.8f; z <= 3.4f; z += 0.3f) scene.add(x, y, -testing::kSensorHeight + z);
    }
  }
  scene.cylinder(10.0f, 1.5f, 0.25f, 1.8f);  // pedestrian under it
  const Segments out = run(scene);
  ASSERT_EQ(out.segments.size(), 2u);  // the trunk and the pedestrian
  EXPECT_GT(out.counters.ignored_above, 0u);
  for (const Segment& seg : out.segments) EXPECT_LT(seg.box.length, 0.7f);
}

// A sedan parked beside a tree whose crown reaches down to 2.25 m, below max_height_m, over the
// car and the trunk: the crown's cells join them into one segment unless, as overhead cells
// (nothing in them below overhead_m), they are kept apart from cells standing on the ground.
TEST(Segmenter, CarUnderATreeCrownIsNotJoinedToTheTrunkThroughOverheadCells) {
  Scene scene;
  scene.flat_ground();
  scene.cylinder(10.0f, 0.0f, 0.2f, 2.45f);  // trunk
  for (float x = 7.5f; x <= 12.5f; x += 0.1f) {
    for (float y = -2.5f; y <= 2.5f; y += 0.1f) {
      if (std::hypot(x - 10.0f, y) > 2.5f) continue;
      for (float z = 2.25f; z <= 2.46f; z += 0.1f) scene.add(x, y, -testing::kSensorHeight + z);
    }
  }
  scene.sedan(10.0f, 2.3f);  // 1.4..3.2 m from the trunk's axis, under the crown
  const auto joins_trunk_and_car = [&](const Segments& out) {
    for (const Segment& seg : out.segments) {
      bool trunk = false, car = false;
      for (const std::uint32_t i : out.indices(seg)) {
        const float x = scene.xyzi[4 * i], y = scene.xyzi[4 * i + 1];
        const float z = scene.xyzi[4 * i + 2] + testing::kSensorHeight;
        trunk = trunk || (std::hypot(x - 10.0f, y) < 0.3f && z < 2.0f);
        car = car || (y > 1.5f && z < 1.0f);
      }
      if (trunk && car) return true;
    }
    return false;
  };
  EXPECT_TRUE(joins_trunk_and_car(run(scene)));  // overhead_m 0: off
  SegmenterConfig c = test_config();
  c.overhead_m = 2.2;
  const Segments out = run(scene, c);
  EXPECT_FALSE(joins_trunk_and_car(out));
  bool sedan = false;
  for (const Segment& seg : out.segments) {
    sedan = sedan || (std::fabs(seg.box.length - 4.5f) < 0.3f && seg.box.width < 2.2f &&
                      std::fabs(seg.box.cy - 2.3f) < 0.3f);
  }
  EXPECT_TRUE(sedan);
}

SegmenterConfig no_split() {
  SegmenterConfig c = test_config();
  c.split_height_m = 0.0;
  return c;
}

// Three people walking in single file 0.9 m apart (as the simulator's groups): their strides
// touch (0.1 m between the legs), their shoulders and heads are 0.5 m apart.
TEST(Segmenter, PeopleWalkingInSingleFileAreOneSegmentEach) {
  Scene scene;
  scene.flat_ground();
  for (const float x : {9.0f, 9.9f, 10.8f}) scene.walker(x, 4.0f);
  ASSERT_EQ(run(scene, no_split()).segments.size(), 1u);  // the legs join them
  const Segments out = run(scene);
  ASSERT_EQ(out.segments.size(), 3u);
  EXPECT_EQ(out.counters.split_segments, 2u);
  EXPECT_EQ(out.counters.clusters, 1u);
  EXPECT_EQ(accounted(out.counters), scene.size());
  std::uint32_t points = 0;
  for (const Segment& seg : out.segments) {
    EXPECT_NEAR(seg.centroid[1], 4.0f, 0.05f);
    EXPECT_LT(seg.box.length, 0.9f);
    EXPECT_NEAR(std::fmod(seg.centroid[0] - 9.0f + 0.05f, 0.9f), 0.05f, 0.1f);  // one walker
    points += seg.count;
  }
  EXPECT_EQ(points, out.counters.obstacle_points);  // every point in one of the three
}

TEST(Segmenter, PersonBesideACarIsSplitFromIt) {
  Scene scene;
  scene.flat_ground();
  scene.sedan(10.0f, 0.0f);                               // side at y = 0.9, cabin side at 0.75
  scene.walker(10.0f, 0.9f + 0.3f + 0.2f);                // torso 0.3 m from the car's side
  ASSERT_EQ(run(scene, no_split()).segments.size(), 1u);  // the hands touch the side
  const Segments out = run(scene);
  ASSERT_EQ(out.segments.size(), 2u);
  const Segment& person = beside_the_car(out);
  EXPECT_NEAR(person.centroid[0], 10.0f, 0.1f);
  EXPECT_NEAR(person.centroid[1], 1.4f, 0.1f);
}

// A bicyclist passing a parked car, as in simulated urban drives: the rider shadows the car's
// side, which is seen in two pieces, and the road between them is hidden. The piece left of
// the shadow is joined only by ray bridges from the bike's wheels (tops 0.7 and 0.9 m), and it
// is nearer the rider's head and shoulders than the car's cabin: it stays with the car.
TEST(Segmenter, CarSideCutByABicyclistsShadowStaysWithTheCar) {
  Scene ground;
  ground.ground(15.0f, 0.1f, [](float, float) { return 0.0f; });
  Scene scene;
  for (std::size_t i = 0; i < ground.size(); ++i) {
    const float x = ground.xyzi[4 * i], y = ground.xyzi[4 * i + 1];
    if (y > 7.9f && x > -12.3f && x < -7.3f) continue;  // under the bike and the car, shadows
    scene.add(x, y, ground.xyzi[4 * i + 2]);
  }
  const float g = -testing::kSensorHeight;
  auto side = [&](float x0, float x1) {  // the car's near side, 0.3-0.9 m up, at y = 9.05
    for (float x = x0; x <= x1; x += 0.05f) {
      for (float z = 0.3f; z <= 0.9f; z += 0.1f) scene.add(x, 9.05f, g + z);
    }
  };
  side(-12.0f, -11.0f);                                    // left of the rider's shadow
  side(-10.2f, -7.5f);                                     // right of it
  scene.box(-9.0f, 9.95f, 2.0f, 1.5f, 1.4f, 0.05f, 0.9f);  // the cabin
  scene.box(-9.5f, 8.3f, 1.6f, 0.1f, 0.7f);                // wheels and frame
  scene.box(-8.9f, 8.3f, 0.1f, 0.5f, 1.0f, 0.05f, 0.9f);   // handlebar
  scene.cylinder(-9.6f, 8.3f, 0.2f, 1.5f, 0.05f, 0.8f);    // rider's legs and torso
  scene.cylinder(-9.5f, 8.3f, 0.1f, 1.75f, 0.05f, 1.5f);   // head
  ASSERT_EQ(run(scene, no_split()).segments.size(), 1u);   // the bridges join them
  const Segments out = run(scene);
  ASSERT_EQ(out.segments.size(), 2u);
  EXPECT_EQ(out.counters.split_segments, 1u);
  const bool first_is_car = out.segments[0].box.length > out.segments[1].box.length;
  const Segment& car = out.segments[first_is_car ? 0 : 1];
  const Segment& bike = out.segments[first_is_car ? 1 : 0];
  EXPECT_NEAR(car.box.length, 4.5f, 0.15f);  // both pieces of the side
  EXPECT_LT(bike.box.length, 1.8f);
  EXPECT_NEAR(bike.centroid[1], 8.3f, 0.1f);
  EXPECT_EQ(car.count + bike.count, out.counters.obstacle_points);
}

// One high group each (a person's shoulders and head, a rider, a cabin): never split.
TEST(Segmenter, SplitLeavesALonePersonABicyclistAndCarsWhole) {
  Scene person;
  person.flat_ground();
  person.walker(8.0f, -3.0f, 1.9f);
  EXPECT_EQ(run(person).segments.size(), 1u);
  Scene bicyclist;
  bicyclist.flat_ground();
  bicyclist.box(8.0f, 3.0f, 1.8f, 0.1f, 0.7f);               // wheels and frame
  bicyclist.box(8.3f, 3.0f, 0.1f, 0.5f, 1.0f, 0.05f, 0.9f);  // handlebar
  bicyclist.cylinder(7.9f, 3.0f, 0.2f, 1.5f, 0.05f, 0.8f);   // rider's legs and torso
  bicyclist.cylinder(8.0f, 3.0f, 0.1f, 1.75f, 0.05f, 1.5f);  // head
  EXPECT_EQ(run(bicyclist).segments.size(), 1u);
  Scene cars;
  cars.flat_ground();
  cars.sedan(10.0f, 0.0f);
  cars.box(-10.0f, 5.0f, 5.2f, 2.0f, 2.2f);  // a van: all of it high
  const Segments out = run(cars);
  EXPECT_EQ(out.segments.size(), 2u);
  EXPECT_EQ(out.counters.split_segments, 0u);
}

TEST(Segmenter, SplitLeavesACarSeenFromBehindAt30mWhole) {
  const Scene scene = far_car_with_road_under_its_body();  // its cabin's rear is high
  const Segments out = run(scene, overhang_config());
  ASSERT_EQ(out.segments.size(), 1u);
  EXPECT_EQ(out.counters.split_segments, 0u);
}

// The rotated car of the box tests: 4.5 x 1.8 m, centred at (7, -4), heading kCarYaw. A point
// (x, y, z) of the car's own frame is added to `scene` in the sensor frame.
constexpr float kCarYaw = 0.6f;
void add_car_point(Scene& scene, float x, float y, float z) {
  const float c = std::cos(kCarYaw), s = std::sin(kCarYaw);
  scene.add(7.0f + c * x - s * y, -4.0f + s * x + c * y, z);
}

// The box is that car's, heading within `yaw_tol`, size within `size_tol`, centre within
// `centre_tol`.
void expect_car_box(const OrientedBox& b, float yaw_tol, float size_tol, float centre_tol) {
  EXPECT_NEAR(b.yaw, kCarYaw, yaw_tol);
  EXPECT_NEAR(b.length, 4.5f, size_tol);
  EXPECT_NEAR(b.width, 1.8f, size_tol);
  EXPECT_NEAR(b.cx, 7.0f, centre_tol);
  EXPECT_NEAR(b.cy, -4.0f, centre_tol);
}

TEST(Segmenter, OrientedBoxFollowsARotatedCar) {
  Scene car;
  car.box(0.0f, 0.0f, 4.5f, 1.8f, 1.5f);
  Scene scene;
  scene.flat_ground();
  for (std::size_t i = 0; i < car.size(); ++i)
    add_car_point(scene, car.xyzi[4 * i], car.xyzi[4 * i + 1], car.xyzi[4 * i + 2]);
  const Segments out = run(scene);
  ASSERT_EQ(out.segments.size(), 1u);
  const OrientedBox& b = out.segments[0].box;
  expect_car_box(b, 0.05f, 0.2f, 0.1f);
  // Segments hold the points above the ground clearance: the box starts there.
  EXPECT_NEAR(b.height, 1.5f - static_cast<float>(test_config().ground_clearance_m), 0.06f);
}

TEST(Segmenter, BoxOfACarSeenAtACornerFollowsItsSidesNotTheDiagonal) {
  // A 4.5 x 1.8 m car at yaw 0.6 seen at a corner: only its left side and its rear return
  // points, an L. The principal axis of an L lies between its legs; the L-shape fit
  // (box_fit_points) finds the car's heading, size and centre.
  Scene scene;
  scene.flat_ground();
  const auto put = [&](float x, float y) {
    for (float z = 0.4f; z <= 1.41f; z += 0.1f) add_car_point(scene, x, y, z);
  };
  for (float x = -2.25f; x <= 2.251f; x += 0.05f) put(x, -0.9f);   // the side
  for (float y = -0.85f; y <= 0.901f; y += 0.05f) put(-2.25f, y);  // the rear
  SegmenterConfig fit = test_config();
  ASSERT_GT(fit.box_fit_points, 0u);  // the default
  const Segments out = run(scene, fit);
  ASSERT_EQ(out.segments.size(), 1u);
  expect_car_box(out.segments[0].box, 0.02f, 0.05f, 0.05f);
  // The principal axis (box_fit_points 0, the thesis) is diagonal: the box is off.
  SegmenterConfig pca = test_config();
  pca.box_fit_points = 0;
  const Segments by_axis = run(scene, pca);
  ASSERT_EQ(by_axis.segments.size(), 1u);
  const OrientedBox p = by_axis.segments[0].box;
  EXPECT_GT(std::abs(p.yaw - kCarYaw), 0.1f);
  EXPECT_GT(std::hypot(p.cx - 7.0f, p.cy + 4.0f), 0.2f);
  // Below box_fit_min_length_m (a person, a bicycle) the principal axis is kept.
  SegmenterConfig small = test_config();
  small.box_fit_min_length_m = 10.0;
  const Segments small_out = run(scene, small);
  ASSERT_EQ(small_out.segments.size(), 1u);
  const OrientedBox q = small_out.segments[0].box;
  EXPECT_EQ(q.yaw, p.yaw);
  EXPECT_EQ(q.cx, p.cx);
}

TEST(Segmenter, DropsClustersTooSmallAndTooLarge) {
  Scene scene;
  scene.flat_ground(25.0f);
  scene.add(5.0f, 5.0f, -1.0f);  // one stray point: too small
  scene.add(5.0f, 5.0f, -0.9f);
  scene.box(0.0f, -10.0f, 20.0f, 0.3f, 2.0f, 0.1f);  // a 20 m wall: too large (extent 15 m)
  scene.box(8.0f, 3.0f, 1.0f, 1.0f, 1.0f);
  const Segments out = run(scene);
  EXPECT_EQ(out.segments.size(), 1u);
  EXPECT_EQ(out.counters.clusters, 3u);
  EXPECT_EQ(out.counters.dropped_too_small, 1u);
  EXPECT_EQ(out.counters.dropped_too_large, 1u);
  EXPECT_EQ(accounted(out.counters), scene.size());
}

TEST(Segmenter, IgnoresPointsOutOfRangeInvalidAndOverhead) {
  Scene scene;
  scene.flat_ground(10.0f);
  std::uint64_t near = 0;  // ground inside min_range_m: the vehicle's own footprint
  for (std::size_t i = 0; i < scene.size(); ++i) {
    near +=
        std::hypot(scene.xyzi[4 * i], scene.xyzi[4 * i + 1]) < test_config().min_range_m ? 1 : 0;
  }
  scene.add(50.0f, 0.0f, -1.0f);                          // beyond range_m
  scene.add(0.2f, 0.1f, -1.0f);                           // inside min_range_m
  scene.add(std::nanf(""), 1.0f, 0.0f);                   // invalid
  scene.add(4.0f, 4.0f, -testing::kSensorHeight + 5.0f);  // overhead, above max_height_m
  const Segments out = run(scene);
  EXPECT_EQ(out.counters.ignored_out_of_range, near + 2);
  EXPECT_EQ(out.counters.ignored_invalid, 1u);
  EXPECT_EQ(out.counters.ignored_above, 1u);
  EXPECT_EQ(out.segments.size(), 0u);
  EXPECT_EQ(accounted(out.counters), scene.size());
}

TEST(Segmenter, ReturnsFromBelowTheRoadDoNotLowerTheGround) {
  Scene scene;
  scene.flat_ground();
  scene.box(10.0f, 0.0f, 4.5f, 1.8f, 1.5f);
  // Two reflections 2.7 m under the road beside the car (as in KITTI object frame 000003): taken
  // as ground they would lift the road around them into one obstacle blob.
  scene.add(10.0f, 1.5f, -testing::kSensorHeight - 2.7f);
  scene.add(10.1f, 1.5f, -testing::kSensorHeight - 2.7f);
  const Segments out = run(scene);
  EXPECT_EQ(out.counters.ignored_below, 2u);
  ASSERT_EQ(out.segments.size(), 1u);
  EXPECT_NEAR(out.segments[0].box.length, 4.5f, 0.2f);
  EXPECT_EQ(accounted(out.counters), scene.size());
}

// A fine cell that straddles two coarse cells (ground_cell_m not a multiple of cell_m) takes the
// ground of the one holding its centre, whichever of its points comes first. Here the fine cell
// x in [9.9, 10.05) m straddles x = 10 m, with a platform 0.5 m high on its centre's side
// ([9.5, 10) m) and the road beyond; its two points, 0.55 m up, are 5 cm above the platform:
// ground, in either order (taking the road's ground from a first point past 10 m made them a
// 0.55 m obstacle).
TEST(Segmenter, AFineCellTakesTheGroundOfTheCoarseCellHoldingItsCentre) {
  SegmenterConfig c = test_config();
  c.ground_cell_m = 0.5;
  c.ground_radius_m = 0.0;  // each coarse cell its own ground
  const float road = -testing::kSensorHeight, platform = road + 0.5f;
  for (const bool road_side_first : {true, false}) {
    Scene scene;
    for (float y = 0.02f; y < 0.5f; y += 0.05f) {
      for (float x = 9.52f; x < 9.89f; x += 0.05f) scene.add(x, y, platform);
      for (float x = 10.06f; x < 10.49f; x += 0.05f) scene.add(x, y, road);
    }
    const float xs[2] = {road_side_first ? 10.02f : 9.95f, road_side_first ? 9.95f : 10.02f};
    for (const float x : xs) scene.add(x, 0.07f, platform + 0.05f);
    const Segments out = run(scene, c);
    EXPECT_EQ(out.counters.obstacle_points, 0u) << "road side first: " << road_side_first;
    EXPECT_EQ(out.counters.ground_points, scene.size());
  }
}

TEST(Segmenter, CountsEveryCapacityOverflow) {
  Scene scene;
  scene.flat_ground();
  scene.box(8.0f, 0.0f, 2.0f, 1.0f, 1.2f);
  scene.box(8.0f, 4.0f, 2.0f, 1.0f, 1.2f);
  scene.box(-8.0f, 4.0f, 2.0f, 1.0f, 1.2f);
  {
    SegmenterConfig c = test_config();
    c.max_segments = 2;
    const Segments out = run(scene, c);
    EXPECT_EQ(out.segments.size(), 2u);
    EXPECT_EQ(out.counters.dropped_segment_overflow, 1u);
  }
  {
    SegmenterConfig c = test_config();
    c.max_points = 1000;
    const Segments out = run(scene, c);
    EXPECT_EQ(out.counters.ignored_over_capacity, scene.size() - 1000);
    EXPECT_EQ(accounted(out.counters), scene.size());
  }
  {
    SegmenterConfig c = test_config();
    c.max_occupied_cells = 500;
    const Segments out = run(scene, c);
    EXPECT_EQ(out.counters.occupied_cells, 500u);
    EXPECT_GT(out.counters.dropped_cell_overflow, 0u);
    EXPECT_EQ(accounted(out.counters), scene.size());
  }
}

TEST(Segmenter, StrideReadsTheDriversPointLayout) {
  Scene scene;
  scene.flat_ground();
  scene.box(8.0f, 0.0f, 2.0f, 1.0f, 1.2f);
  struct DriverLikePoint {  // the layout of drivers/velodyne/point.hpp: x, y, z first, 32 bytes
    float x, y, z, intensity, distance;
    std::int32_t time;
    std::uint32_t rest[2];
  };
  static_assert(sizeof(DriverLikePoint) == 32);
  std::vector<DriverLikePoint> pts(scene.size());
  for (std::size_t i = 0; i < pts.size(); ++i) {
    pts[i] = {scene.xyzi[4 * i], scene.xyzi[4 * i + 1], scene.xyzi[4 * i + 2], 0, 0, 0, {0, 0}};
  }
  Segmenter segmenter(test_config());
  Segments a = segmenter.make_segments(), b = segmenter.make_segments();
  segmenter.segment(scene.view(), a);
  segmenter.segment(PointView{&pts[0].x, pts.size(), sizeof(DriverLikePoint)}, b);
  ASSERT_EQ(a.segments.size(), 1u);
  ASSERT_EQ(b.segments.size(), 1u);
  EXPECT_EQ(a.segments[0].count, b.segments[0].count);
  EXPECT_FLOAT_EQ(a.segments[0].centroid[0], b.segments[0].centroid[0]);
}

TEST(Segmenter, RepeatedScansGiveIdenticalResultsWithoutAllocating) {
  Scene scene;
  scene.flat_ground();
  scene.box(8.0f, 0.0f, 2.0f, 1.0f, 1.2f);
  scene.cylinder(-5.0f, 3.0f, 0.25f, 1.7f);
  for (const float x : {-9.0f, -9.9f}) scene.walker(x, -4.0f);  // split in two
  Segmenter segmenter(test_config());
  Segments out = segmenter.make_segments();
  segmenter.segment(scene.view(), out);
  ASSERT_EQ(out.counters.split_segments, 1u);
  const std::size_t n = out.segments.size();
  const std::uint32_t first_count = out.segments[0].count;
  rt::testing::AllocationCounter counter;
  for (int i = 0; i < 5; ++i) segmenter.segment(scene.view(), out);
  counter.stop();
  EXPECT_EQ(counter.allocations(), 0u);
  ASSERT_EQ(out.segments.size(), n);
  EXPECT_EQ(out.segments[0].count, first_count);
}

TEST(Segmenter, EmptyScanGivesNoSegmentsAndClearsThePreviousOutput) {
  Scene scene;
  scene.flat_ground();
  scene.box(8.0f, 0.0f, 2.0f, 1.0f, 1.2f);
  Segmenter segmenter(test_config());
  Segments out = segmenter.make_segments();
  segmenter.segment(scene.view(), out);
  ASSERT_EQ(out.segments.size(), 1u);
  segmenter.segment(PointView{nullptr, 0, 16}, out);
  EXPECT_EQ(out.segments.size(), 0u);
  EXPECT_EQ(out.point_indices.size(), 0u);
  EXPECT_EQ(out.counters.points_in, 0u);
  segmenter.segment(scene.view(), out);  // the grids were left empty: same result again
  ASSERT_EQ(out.segments.size(), 1u);
}

TEST(Segmenter, RejectsInvalidConfiguration) {
  SegmenterConfig c;
  c.cell_m = 0.0;
  EXPECT_THROW(Segmenter{c}, std::invalid_argument);
  // Capacities are allocated at construction: each is bounded.
  c = SegmenterConfig{};
  c.max_occupied_cells = 100'000'000;
  EXPECT_STREQ(validate(c), "max_occupied_cells must be in 1..4194304");
  c = SegmenterConfig{};
  c.max_points = 10'000'001;
  EXPECT_STREQ(validate(c), "max_points must be in 1..10000000");
  c = SegmenterConfig{};
  c.max_segments = 1'000'001;
  EXPECT_STREQ(validate(c), "max_segments must be in 1..1000000");
  c = SegmenterConfig{};
  c.range_m = 500;  // 0.15 m cells: 6667 across
  EXPECT_STREQ(validate(c), "");
  c.cell_m = 0.1;  // 10000 across
  EXPECT_STRNE(validate(c), "");
  c = SegmenterConfig{};
  c.obstacle_height_m = 0.1;  // below the ground clearance
  EXPECT_STRNE(validate(c), "");
  c = SegmenterConfig{};
  c.overhang_m = 0.7;  // above overhang_max_m
  EXPECT_STREQ(validate(c), "overhang_max_m must be >= overhang_m");
  c = SegmenterConfig{};
  c.overhead_m = 3.0;  // above max_height_m (0 is off)
  EXPECT_STREQ(validate(c), "overhead_m must be 0 (off) or in (obstacle_height_m, max_height_m] m");
  c = SegmenterConfig{};
  c.split_height_m = 0.2;  // below obstacle_height_m (0 is off)
  EXPECT_STREQ(validate(c),
               "split_height_m must be 0 (off) or in (obstacle_height_m, max_height_m] m");
  c.split_height_m = 0.0;
  EXPECT_STREQ(validate(c), "");
  c.split_person_m = 0.1;  // below cell_m
  EXPECT_STRNE(validate(c), "");
  c = SegmenterConfig{};
  c.box_fit_min_length_m = -1;
  EXPECT_STREQ(validate(c), "box_fit_min_length_m must be in [0, 1000] m");
  EXPECT_STREQ(validate(SegmenterConfig{}), "");
}

}  // namespace
}  // namespace stac::segmentation
