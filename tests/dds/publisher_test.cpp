// The publishing edge against real Cyclone participants: every topic round trips with all fields,
// sequences at their IDL bounds, over-bound input is refused, QoS as documented.
#include "dds/publisher.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "dds/idl_types.hpp"
#include "dds_test_support.hpp"
#include "rt/testing/alloc_counter.hpp"

namespace stac::dds {
namespace {

using testing::TestReader;

std::unique_ptr<Publisher> make_publisher(std::uint32_t domain, bool ros2 = false) {
  PublisherConfig c;
  c.domain_id = domain;
  c.topic_prefix = "stac_test";
  c.ros2_names = ros2;
  c.config_uri = testing::loopback_uri();
  auto p = Publisher::create(c);
  EXPECT_TRUE(p) << (p ? "" : p.error().message);
  return p ? std::move(*p) : nullptr;
}

const std::vector<std::string> kDefaultNames = {"car", "pedestrian", "bicyclist"};

TrackedObjectIn object(std::uint64_t id) {
  TrackedObjectIn o;
  o.object_id = id;
  o.existence_probability = 0.75f;
  o.classified = true;
  o.class_names = kDefaultNames;
  o.class_log_odds = {2.0f, -1.0f, -3.0f, 0.5f};
  o.class_age = 1;
  o.position = {10.5, -3.25, 0.75};
  o.velocity = {4.0, 1.5, 0.0};
  for (int i = 0; i < 9; ++i) {
    o.position_covariance[static_cast<std::size_t>(i)] = 0.1f * static_cast<float>(i);
    o.velocity_covariance[static_cast<std::size_t>(i)] = 0.2f * static_cast<float>(i);
  }
  o.dimensions = {4.5, 1.8, 1.5};
  o.yaw = 0.3f;
  o.point_count = 321;
  o.age = 17;
  o.state = 1;
  return o;
}

TEST(DdsPublisher, TrackedObjectsRoundTripEveryFieldWithSequencesAtTheirBounds) {
  auto pub = make_publisher(101);
  ASSERT_NE(pub, nullptr);
  using T = IdlTypes<false>;
  TestReader reader(101, T::tracked_objects(), "stac_test/tracked_objects", Topic::kTrackedObjects);
  ASSERT_TRUE(reader.ok());
  ASSERT_TRUE(TestReader::wait_matched(pub->writer(Topic::kTrackedObjects)));

  std::vector<Point2> footprint(kMaxFootprint);
  for (std::size_t k = 0; k < footprint.size(); ++k)
    footprint[k] = {static_cast<float>(k), -static_cast<float>(k)};
  std::vector<TrackedObjectIn> objects;
  for (std::uint64_t id = 0; id < kMaxObjects; ++id) objects.push_back(object(1000 + id));
  objects[1].classified = false;
  objects[0].footprint = footprint;
  // A model of 8 user-named classes (the maximum): every class by name, background last.
  const std::vector<std::string> eight = {"car",  "pedestrian", "bicyclist", "pole",
                                          "sign", "tree",       "bin",       std::string(31, 'n')};
  objects[2].class_names = eight;
  objects[2].class_log_odds = {-5, -4, -3, -2, -1, 3, -6, -7, -3};
  const ScanStamp scan{1'700'000'000'123'456'789, 42};
  auto ok = pub->publish_tracked_objects(scan, objects);
  ASSERT_TRUE(ok) << ok.error().message;

  const auto* s = reader.take<T::TrackedObjects>();
  ASSERT_NE(s, nullptr);
  EXPECT_EQ(s->stamp.sec, 1'700'000'000);
  EXPECT_EQ(s->stamp.nanosec, 123'456'789u);
  EXPECT_STREQ(s->frame_id, "map");
  EXPECT_EQ(s->scan_index, 42u);
  ASSERT_EQ(s->objects._length, kMaxObjects);
  const auto& o = s->objects._buffer[0];
  EXPECT_EQ(o.object_id, 1000u);
  EXPECT_FLOAT_EQ(o.existence_probability, 0.75f);
  EXPECT_FLOAT_EQ(o.class_log_odds[0], 2.0f);
  EXPECT_FLOAT_EQ(o.class_log_odds[3], 0.5f);
  EXPECT_EQ(o.class_age, 1u);
  EXPECT_FLOAT_EQ(o.class_log_odds[4], 0.0f);
  ASSERT_EQ(o.classification._length, 4u);
  EXPECT_EQ(o.classification._buffer[0].label, 1);  // car, log odds 2
  EXPECT_STREQ(o.classification._buffer[0].name, "car");
  EXPECT_NEAR(o.classification._buffer[0].probability, 0.8808f, 1e-4);
  EXPECT_EQ(o.classification._buffer[1].label, 4);  // background, 0.5
  EXPECT_STREQ(o.classification._buffer[1].name, "background");
  EXPECT_EQ(o.classification._buffer[3].label, 3);  // bicyclist, -3
  EXPECT_STREQ(o.classification._buffer[3].name, "bicyclist");
  const auto& taught = s->objects._buffer[2];
  ASSERT_EQ(taught.classification._length, kMaxClassifications);
  EXPECT_EQ(taught.classification._buffer[0].label, 6);  // "tree", log odds 3
  EXPECT_STREQ(taught.classification._buffer[0].name, "tree");
  EXPECT_EQ(taught.classification._buffer[1].label, 5);  // "sign", -1
  EXPECT_EQ(taught.classification._buffer[2].label, 4);  // "pole", -2
  EXPECT_EQ(taught.classification._buffer[3].label, 3);  // "bicyclist", -3
  EXPECT_EQ(taught.classification._buffer[4].label, 9);  // background, -3: after it (stable)
  EXPECT_STREQ(taught.classification._buffer[4].name, "background");
  EXPECT_EQ(std::string(taught.classification._buffer[8].name), std::string(31, 'n'));
  EXPECT_FLOAT_EQ(taught.class_log_odds[8], -3.0f);
  EXPECT_DOUBLE_EQ(o.kinematics.position.x, 10.5);
  EXPECT_DOUBLE_EQ(o.kinematics.position.y, -3.25);
  EXPECT_DOUBLE_EQ(o.kinematics.velocity.y, 1.5);
  EXPECT_FLOAT_EQ(o.kinematics.position_covariance[8], 0.8f);
  EXPECT_FLOAT_EQ(o.kinematics.velocity_covariance[4], 0.8f);
  EXPECT_DOUBLE_EQ(o.shape.dimensions.x, 4.5);
  EXPECT_FLOAT_EQ(o.shape.yaw, 0.3f);
  ASSERT_EQ(o.shape.footprint._length, kMaxFootprint);
  EXPECT_FLOAT_EQ(o.shape.footprint._buffer[7].x, 7.0f);
  EXPECT_FLOAT_EQ(o.shape.footprint._buffer[7].y, -7.0f);
  EXPECT_EQ(o.point_count, 321u);
  EXPECT_EQ(o.age, 17u);
  EXPECT_EQ(o.state, 1);
  // Not classified (no model, or no segment yet): one entry, label 0 (unknown), probability 1.
  const auto& unknown = s->objects._buffer[1];
  ASSERT_EQ(unknown.classification._length, 1u);
  EXPECT_EQ(unknown.classification._buffer[0].label, 0);
  EXPECT_FLOAT_EQ(unknown.classification._buffer[0].probability, 1.0f);
  EXPECT_STREQ(unknown.classification._buffer[0].name, "unknown");
  // Without a footprint the box's corners are published, centred on the position.
  const auto& last = s->objects._buffer[kMaxObjects - 1];
  EXPECT_EQ(last.object_id, 1000u + kMaxObjects - 1);
  ASSERT_EQ(last.shape.footprint._length, 4u);
  float cx = 0, cy = 0;
  for (int k = 0; k < 4; ++k) {
    cx += last.shape.footprint._buffer[k].x / 4;
    cy += last.shape.footprint._buffer[k].y / 4;
  }
  EXPECT_NEAR(cx, 10.5f, 1e-4);
  EXPECT_NEAR(cy, -3.25f, 1e-4);
}

TEST(DdsPublisher, OverBoundInputIsRefusedWithAClearError) {
  auto pub = make_publisher(102);
  ASSERT_NE(pub, nullptr);
  std::vector<TrackedObjectIn> objects(kMaxObjects + 1);
  auto r = pub->publish_tracked_objects({0, 1}, objects);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("tracked objects: 513 elements exceed the bound of 512"),
            std::string::npos)
      << r.error().message;

  std::vector<Point2> footprint(kMaxFootprint + 1);
  std::vector<TrackedObjectIn> one(1);
  one[0].footprint = footprint;
  r = pub->publish_tracked_objects({0, 1}, one);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("footprint: 9 elements exceed the bound of 8"),
            std::string::npos);

  std::vector<SegmentIn> segments(kMaxSegments + 1);
  r = pub->publish_segments({0, 1}, segments);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("bound of 2048"), std::string::npos);

  const StageLatencyIn stage{"a_stage_name_longer_than_23", 5};
  HealthIn h;
  h.stages = {&stage, 1};
  r = pub->publish_health(h);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("longer than its bound of 23 characters"), std::string::npos)
      << r.error().message;

  std::vector<LabeledPointIn> points(kMaxCloudPoints + 1);
  r = pub->publish_point_cloud({{0, 1}, {}, 0.01f, points});
  ASSERT_FALSE(r);
  EXPECT_NE(
      r.error().message.find("point cloud points: 131073 elements exceed the bound of 131072"),
      std::string::npos)
      << r.error().message;
}

// Both naming modes: a full cloud, every field of a point, and an empty one.
TEST(DdsPublisher, PointCloudRoundTripsEveryFieldAtItsBoundInBothNamingModes) {
  for (const bool ros2 : {false, true}) {
    const std::uint32_t domain = ros2 ? 110 : 109;
    auto pub = make_publisher(domain, ros2);
    ASSERT_NE(pub, nullptr);
    const std::string name = std::string(ros2 ? "rt/" : "") + "stac_test/point_cloud";
    const auto* descriptor = ros2 ? IdlTypes<true>::point_cloud() : IdlTypes<false>::point_cloud();
    TestReader reader(domain, descriptor, name.c_str(), Topic::kPointCloud);
    ASSERT_TRUE(reader.ok());
    ASSERT_TRUE(TestReader::wait_matched(pub->writer(Topic::kPointCloud)));
    std::vector<LabeledPointIn> points(kMaxCloudPoints);
    for (std::size_t i = 0; i < points.size(); ++i) {
      const auto v = static_cast<std::int16_t>(static_cast<int>(i % 65536) - 32768);
      points[i] = {v, static_cast<std::int16_t>(-1 - v), static_cast<std::int16_t>(i % 1000),
                   static_cast<std::uint8_t>(i % 256), static_cast<std::uint8_t>(i % 6)};
    }
    const PointCloudIn cloud{{2'000'000'000'000'000'001, 9}, {100.5, -20.25, 1.75}, 0.01f, points};
    auto ok = pub->publish_point_cloud(cloud);
    ASSERT_TRUE(ok) << ok.error().message;
    auto check = [&](const auto* s) {
      ASSERT_NE(s, nullptr);
      EXPECT_EQ(s->stamp.sec, 2'000'000'000);
      EXPECT_EQ(s->stamp.nanosec, 1u);
      EXPECT_STREQ(s->frame_id, "map");
      EXPECT_EQ(s->scan_index, 9u);
      EXPECT_DOUBLE_EQ(s->origin.x, 100.5);
      EXPECT_DOUBLE_EQ(s->origin.y, -20.25);
      EXPECT_DOUBLE_EQ(s->origin.z, 1.75);
      EXPECT_FLOAT_EQ(s->resolution, 0.01f);
      ASSERT_EQ(s->points._length, kMaxCloudPoints);
      for (const std::size_t i : {std::size_t{0}, std::size_t{1}, std::size_t{32768},
                                  std::size_t{70001}, std::size_t{kMaxCloudPoints - 1}}) {
        const auto& p = s->points._buffer[i];
        EXPECT_EQ(p.x, points[i].x) << i;
        EXPECT_EQ(p.y, points[i].y) << i;
        EXPECT_EQ(p.z, points[i].z) << i;
        EXPECT_EQ(p.intensity, points[i].intensity) << i;
        EXPECT_EQ(p.label, points[i].label) << i;
      }
    };
    if (ros2) {
      check(reader.take<IdlTypes<true>::LabeledPointCloud>());
    } else {
      check(reader.take<IdlTypes<false>::LabeledPointCloud>());
    }
    ASSERT_TRUE(pub->publish_point_cloud({{5, 10}, {}, 0.01f, {}}));
    if (ros2) {
      const auto* e = reader.take<IdlTypes<true>::LabeledPointCloud>();
      ASSERT_NE(e, nullptr);
      EXPECT_EQ(e->points._length, 0u);
    } else {
      const auto* e = reader.take<IdlTypes<false>::LabeledPointCloud>();
      ASSERT_NE(e, nullptr);
      EXPECT_EQ(e->points._length, 0u);
    }
  }
}

TEST(DdsPublisher, SegmentsEgoPoseAndHealthRoundTripInRos2NamingMode) {
  auto pub = make_publisher(103, /*ros2=*/true);
  ASSERT_NE(pub, nullptr);
  using T = IdlTypes<true>;
  TestReader segs(103, T::segments(), "rt/stac_test/segments", Topic::kSegments);
  TestReader pose(103, T::ego_pose(), "rt/stac_test/ego_pose", Topic::kEgoPose);
  TestReader health(103, T::health(), "rt/stac_test/health", Topic::kHealth);
  ASSERT_TRUE(segs.ok() && pose.ok() && health.ok());
  ASSERT_TRUE(TestReader::wait_matched(pub->writer(Topic::kSegments)));
  ASSERT_TRUE(TestReader::wait_matched(pub->writer(Topic::kEgoPose)));
  ASSERT_TRUE(TestReader::wait_matched(pub->writer(Topic::kHealth)));

  std::vector<SegmentIn> in(kMaxSegments);
  for (std::uint32_t i = 0; i < kMaxSegments; ++i)
    in[i] = {i, {1.0 * i, 2, 3}, {4, 5, 6}, 0.5f, 100 + i};
  ASSERT_TRUE(pub->publish_segments({-1'500'000'000, 7}, in));  // before the epoch: sec -2, +0.5 s
  const auto* s = segs.take<T::ScanSegments>();
  ASSERT_NE(s, nullptr);
  EXPECT_EQ(s->stamp.sec, -2);
  EXPECT_EQ(s->stamp.nanosec, 500'000'000u);
  ASSERT_EQ(s->segments._length, kMaxSegments);
  EXPECT_EQ(s->segments._buffer[2047].segment_id, 2047u);
  EXPECT_DOUBLE_EQ(s->segments._buffer[2047].centroid.x, 2047.0);
  EXPECT_DOUBLE_EQ(s->segments._buffer[5].dimensions.z, 6.0);
  EXPECT_FLOAT_EQ(s->segments._buffer[5].yaw, 0.5f);
  EXPECT_EQ(s->segments._buffer[5].point_count, 105u);

  EgoPoseIn p;
  p.stamp_ns = 5'000'000'001;
  p.position = {1, 2, 3};
  p.orientation = {0, 0, 0.7071, 0.7071};
  p.velocity = {7, 8, 9};
  p.yaw_rate = 0.25f;
  p.source = 1;
  ASSERT_TRUE(pub->publish_ego_pose(p));
  const auto* e = pose.take<T::EgoPose>();
  ASSERT_NE(e, nullptr);
  EXPECT_EQ(e->stamp.sec, 5);
  EXPECT_EQ(e->stamp.nanosec, 1u);
  EXPECT_STREQ(e->frame_id, "map");
  EXPECT_DOUBLE_EQ(e->position.z, 3);
  EXPECT_DOUBLE_EQ(e->orientation[3], 0.7071);
  EXPECT_DOUBLE_EQ(e->velocity.x, 7);
  EXPECT_FLOAT_EQ(e->yaw_rate, 0.25f);
  EXPECT_EQ(e->source, 1);

  std::vector<StageLatencyIn> stages(kMaxStages, StageLatencyIn{"23_characters_exactly_x", 9});
  stages[0] = {"decode", 1500};
  const DropCountIn drops[] = {{"velodyne.ring_full", 3}, {"tracking.pool_full", 0}};
  const SensorStatusIn sensors[] = {{"lidar", 0, 0.01f}, {"ins", 1, 2.5f}, {"can", 3, 0}};
  HealthIn h{{123, 8}, stages, 4200, 2, drops, sensors};
  auto ok = pub->publish_health(h);
  ASSERT_TRUE(ok) << ok.error().message;
  const auto* hs = health.take<T::Health>();
  ASSERT_NE(hs, nullptr);
  EXPECT_EQ(hs->scan_index, 8u);
  ASSERT_EQ(hs->stages._length, kMaxStages);
  EXPECT_STREQ(hs->stages._buffer[0].stage, "decode");
  EXPECT_EQ(hs->stages._buffer[0].latency_us, 1500u);
  EXPECT_STREQ(hs->stages._buffer[11].stage, "23_characters_exactly_x");
  EXPECT_EQ(hs->end_to_end_latency_us, 4200u);
  EXPECT_EQ(hs->deadline_misses, 2u);
  ASSERT_EQ(hs->drops._length, 2u);
  EXPECT_STREQ(hs->drops._buffer[0].cause, "velodyne.ring_full");
  EXPECT_EQ(hs->drops._buffer[0].count, 3u);
  ASSERT_EQ(hs->sensors._length, 3u);
  EXPECT_STREQ(hs->sensors._buffer[1].name, "ins");
  EXPECT_EQ(hs->sensors._buffer[1].status, 1);
  EXPECT_FLOAT_EQ(hs->sensors._buffer[1].age_s, 2.5f);
}

TEST(DdsPublisher, Ros2NamingModeUsesRmwTypeAndTopicNames) {
  auto pub = make_publisher(104, /*ros2=*/true);
  ASSERT_NE(pub, nullptr);
  const dds_entity_t topic = dds_get_topic(pub->writer(Topic::kTrackedObjects));
  char name[128], type[128];
  ASSERT_GE(dds_get_name(topic, name, sizeof(name)), 0);
  ASSERT_GE(dds_get_type_name(topic, type, sizeof(type)), 0);
  EXPECT_STREQ(name, "rt/stac_test/tracked_objects");
  EXPECT_STREQ(type, "stac_msgs::msg::dds_::TrackedObjects_");
  auto native = make_publisher(105, false);
  ASSERT_NE(native, nullptr);
  const dds_entity_t t2 = dds_get_topic(native->writer(Topic::kHealth));
  ASSERT_GE(dds_get_name(t2, name, sizeof(name)), 0);
  ASSERT_GE(dds_get_type_name(t2, type, sizeof(type)), 0);
  EXPECT_STREQ(name, "stac_test/health");
  EXPECT_STREQ(type, "stac_msgs::msg::Health");
}

TEST(DdsPublisher, WriterQosIsReliableKeepLastTenWithDeadlineForTracksReadersKeepTheLatest) {
  auto pub = make_publisher(106);
  ASSERT_NE(pub, nullptr);
  auto qos = [&](Topic t) {
    QosPtr q(dds_create_qos());
    EXPECT_EQ(dds_get_qos(pub->writer(t), q.get()), 0);
    return q;
  };
  dds_history_kind_t hk{};
  int32_t depth = 0;
  dds_reliability_kind_t rk{};
  dds_duration_t blocking = 0, deadline = 0;
  auto tracks = qos(Topic::kTrackedObjects);
  ASSERT_TRUE(dds_qget_history(tracks.get(), &hk, &depth));
  EXPECT_EQ(hk, DDS_HISTORY_KEEP_LAST);
  EXPECT_EQ(depth, 10);  // a second of scans a stalled reader can still be resent
  auto tracks_reader = reader_qos(Topic::kTrackedObjects);
  ASSERT_TRUE(dds_qget_history(tracks_reader.get(), &hk, &depth));
  EXPECT_EQ(depth, 1);  // the reader keeps the latest
  ASSERT_TRUE(dds_qget_reliability(tracks.get(), &rk, &blocking));
  EXPECT_EQ(rk, DDS_RELIABILITY_RELIABLE);
  ASSERT_TRUE(dds_qget_deadline(tracks.get(), &deadline));
  EXPECT_EQ(deadline, DDS_MSECS(100));
  auto segs = qos(Topic::kSegments);
  ASSERT_TRUE(dds_qget_reliability(segs.get(), &rk, &blocking));
  EXPECT_EQ(rk, DDS_RELIABILITY_BEST_EFFORT);
  auto health = qos(Topic::kHealth);
  ASSERT_TRUE(dds_qget_reliability(health.get(), &rk, &blocking));
  EXPECT_EQ(rk, DDS_RELIABILITY_RELIABLE);
  ASSERT_TRUE(dds_qget_deadline(health.get(), &deadline));
  EXPECT_EQ(deadline, DDS_INFINITY);
}

TEST(DdsPublisher, StartUpErrorsNameWhatToFix) {
  PublisherConfig c;
  c.domain_id = 107;
  c.config_uri = "file:///nonexistent/stac/cyclone.xml";
  auto p = Publisher::create(c);
  ASSERT_FALSE(p);
  EXPECT_NE(
      p.error().message.find(
          "DDS domain 107: the Cyclone DDS configuration file:///nonexistent/stac/cyclone.xml "
          "cannot be used"),
      std::string::npos)
      << p.error().message;
  c.domain_id = 999;
  p = Publisher::create(c);
  ASSERT_FALSE(p);
  EXPECT_NE(p.error().message.find("0..230"), std::string::npos);
}

// Allocations while publishing a full tracked-objects sample, after a warm-up. STAC's conversion
// writes only into preallocated storage; Cyclone's dds_write serializes into buffers it allocates
// (measured and reported here, see docs/dds.md), so this bounds rather than zeroes the count.
TEST(DdsPublisher, PublishAllocationsAreCyclonesSerializationOnly) {
  auto pub = make_publisher(108);
  ASSERT_NE(pub, nullptr);
  std::vector<TrackedObjectIn> objects;
  for (std::uint64_t id = 0; id < 64; ++id) objects.push_back(object(id));
  for (int i = 0; i < 10; ++i) ASSERT_TRUE(pub->publish_tracked_objects({i, 0}, objects));
  rt::testing::AllocationCounter counter;
  for (int i = 0; i < 100; ++i) {
    auto r = pub->publish_tracked_objects({i, 0}, objects);
    if (!r) ADD_FAILURE() << r.error().message;
  }
  counter.stop();
  std::printf("allocations in 100 publishes of 64 objects (no reader): %llu (%llu bytes)\n",
              static_cast<unsigned long long>(counter.allocations()),
              static_cast<unsigned long long>(counter.bytes()));
  RecordProperty("allocations_per_100_publishes", static_cast<int>(counter.allocations()));
  // Measured here (Cyclone 0.10.2): 6 per publish, the serialized sample's buffers. A bound, so a
  // conversion that starts allocating per object (64 per publish) fails.
  EXPECT_LE(counter.allocations(), 100u * 8u);
}

}  // namespace
}  // namespace stac::dds
