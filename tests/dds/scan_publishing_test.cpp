// ScanPublishing's point-cloud labels: each segment takes the class of the track it updated.
#include "dds/scan_publishing.hpp"

#include <gtest/gtest.h>

#include <array>

#include "dds/dds_test_support.hpp"
#include "dds/idl_types.hpp"

namespace stac::dds {
namespace {

TEST(ScanPublishing, SegmentLabelsAreTheClassesOfTheTracksTheyUpdated) {
  pipeline::ScanResult r(8, 100, 8);
  for (int i = 0; i < 5; ++i) *r.segments.segments.append() = segmentation::Segment{};
  const auto track = [&](std::int32_t segment, bool classified, classification::ClassIndex c) {
    tracking::Track* t = r.tracked.tracks.append();
    *t = tracking::Track{};
    t->segment = segment;
    classification::TrackClass* k = r.classes.append();
    *k = classification::TrackClass{};
    k->classified = classified;
    k->label = c;
  };
  track(0, true, classification::kCar);
  track(1, true, classification::kPedestrian);
  track(-1, true, classification::kCar);  // coasting: no segment
  track(3, true, classification::kBackground);
  track(4, false, classification::kCar);  // not classified yet
  track(2, true, classification::kBicyclist);
  std::array<std::uint8_t, 8> labels{};
  labels.fill(99);
  ScanPublishing::segment_labels(r, classification::kDefaultClassCount, labels);
  EXPECT_EQ(labels[0], 1);   // car
  EXPECT_EQ(labels[1], 2);   // pedestrian
  EXPECT_EQ(labels[2], 3);   // bicyclist
  EXPECT_EQ(labels[3], 4);   // background
  EXPECT_EQ(labels[4], 5);   // a track, not classified
  EXPECT_EQ(labels[5], 99);  // beyond the scan's segments: untouched

  r.tracked.tracks.clear();  // no tracks at all: every segment an unclassified object
  r.classes.clear();
  ScanPublishing::segment_labels(r, classification::kDefaultClassCount, labels);
  for (std::size_t i = 0; i < 5; ++i) EXPECT_EQ(labels[i], 5) << i;

  // A model of 5 classes: class k is k + 1, background 6, not classified 7.
  track(0, true, 4);
  track(1, true, classification::kBackground);
  track(2, false, 0);
  ScanPublishing::segment_labels(r, 5, labels);
  EXPECT_EQ(labels[0], 5);
  EXPECT_EQ(labels[1], 6);
  EXPECT_EQ(labels[2], 7);
  EXPECT_EQ(labels[3], 7);
}

// The cloud goes out only to a reader (nobody reading: not even serialized), labelled by
// segment; a result without a cloud writes nothing.
TEST(ScanPublishing, PointCloudIsWrittenForAReaderOnlyWithItsSegmentsLabels) {
  dds::PublisherConfig c;
  c.domain_id = 112;
  c.topic_prefix = "stac_test";
  c.config_uri = stac::testing::loopback_uri();
  auto publisher = dds::Publisher::create(c);
  ASSERT_TRUE(publisher) << publisher.error().message;
  ScanPublishing scans(**publisher, false, classification::default_class_names());

  pipeline::ScanResult r(8, 100, 8, 16);
  for (int i = 0; i < 2; ++i) *r.segments.segments.append() = segmentation::Segment{};
  tracking::Track* t = r.tracked.tracks.append();
  *t = tracking::Track{};
  t->segment = 1;
  classification::TrackClass* k = r.classes.append();
  *k = classification::TrackClass{};
  k->classified = true;
  k->label = classification::kPedestrian;
  *r.cloud.append() = {100, -200, 150, 7, pipeline::kNoSegment};  // ground
  *r.cloud.append() = {1, 2, 3, 40, 0};                           // segment 0: no track
  *r.cloud.append() = {-5, 6, -7, 255, 1};                        // segment 1: a pedestrian
  r.cloud_origin = {10, 20, 1.9};
  r.has_cloud = true;
  r.stamp_ns = 3'000'000'000;

  auto skipped = scans.publish_cloud(r, 4);  // no reader yet
  ASSERT_TRUE(skipped) << skipped.error().message;
  EXPECT_FALSE(*skipped);
  EXPECT_FALSE(scans.cloud_reader());  // the pipeline stops building it

  using T = dds::IdlTypes<false>;
  stac::testing::TestReader reader(112, T::point_cloud(), "stac_test/point_cloud",
                                   dds::Topic::kPointCloud);
  ASSERT_TRUE(reader.ok());
  ASSERT_TRUE(
      stac::testing::TestReader::wait_matched((*publisher)->writer(dds::Topic::kPointCloud)));
  auto written = scans.publish_cloud(r, 5);
  ASSERT_TRUE(written) << written.error().message;
  EXPECT_TRUE(*written);
  EXPECT_TRUE(scans.cloud_reader());
  const auto* s = reader.take<T::LabeledPointCloud>();
  ASSERT_NE(s, nullptr);
  EXPECT_EQ(s->scan_index, 5u);  // the one written, not the skipped one
  EXPECT_EQ(s->stamp.sec, 3);
  EXPECT_DOUBLE_EQ(s->origin.z, 1.9);
  ASSERT_EQ(s->points._length, 3u);
  EXPECT_EQ(s->points._buffer[0].x, 100);
  EXPECT_EQ(s->points._buffer[0].y, -200);
  EXPECT_EQ(s->points._buffer[0].label, 0);  // no object
  EXPECT_EQ(s->points._buffer[1].label, 5);  // an object no track classified
  EXPECT_EQ(s->points._buffer[2].label, 2);  // the pedestrian's
  EXPECT_EQ(s->points._buffer[2].z, -7);
  EXPECT_EQ(s->points._buffer[2].intensity, 255);

  pipeline::ScanResult none(8, 100, 8);  // no cloud capacity: cloud_stride 0
  auto nothing = scans.publish_cloud(none, 6);
  ASSERT_TRUE(nothing);
  EXPECT_FALSE(*nothing);
  // A scan whose cloud was not built (nobody read the one before) sends no empty cloud to the
  // reader that has just come: the next sample it sees is a full one.
  r.has_cloud = false;
  auto unbuilt = scans.publish_cloud(r, 7);
  ASSERT_TRUE(unbuilt);
  EXPECT_FALSE(*unbuilt);
  EXPECT_TRUE(scans.cloud_reader());  // a reader is there: the pipeline builds the next one
  r.has_cloud = true;
  ASSERT_TRUE(scans.publish_cloud(r, 8));
  const auto* next = reader.take<T::LabeledPointCloud>();
  ASSERT_NE(next, nullptr);
  EXPECT_EQ(next->scan_index, 8u);
  EXPECT_EQ(next->points._length, 3u);
}

}  // namespace
}  // namespace stac::dds
