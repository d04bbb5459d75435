// ScanPublishing's point-cloud labels: each segment takes the class of the track it updated.
#include "tools/scan_publishing.hpp"

#include <gtest/gtest.h>

#include <array>

namespace stac::tools {
namespace {

TEST(ScanPublishing, SegmentLabelsAreTheClassesOfTheTracksTheyUpdated) {
  pipeline::ScanResult r(8, 100, 8);
  for (int i = 0; i < 5; ++i) *r.segments.segments.append() = segmentation::Segment{};
  const auto track = [&](std::int32_t segment, bool classified, classification::ObjectClass c) {
    tracking::Track* t = r.tracked.tracks.append();
    *t = tracking::Track{};
    t->segment = segment;
    classification::TrackClass* k = r.classes.append();
    *k = classification::TrackClass{};
    k->classified = classified;
    k->label = c;
  };
  track(0, true, classification::ObjectClass::kCar);
  track(1, true, classification::ObjectClass::kPedestrian);
  track(-1, true, classification::ObjectClass::kCar);  // coasting: no segment
  track(3, true, classification::ObjectClass::kBackground);
  track(4, false, classification::ObjectClass::kCar);  // not classified yet
  track(2, true, classification::ObjectClass::kBicyclist);
  std::array<std::uint8_t, 8> labels{};
  labels.fill(99);
  ScanPublishing::segment_labels(r, labels);
  EXPECT_EQ(labels[0], 1);  // car
  EXPECT_EQ(labels[1], 2);  // pedestrian
  EXPECT_EQ(labels[2], 3);  // bicyclist
  EXPECT_EQ(labels[3], 4);  // background
  EXPECT_EQ(labels[4], 5);  // a track, not classified
  EXPECT_EQ(labels[5], 99);  // beyond the scan's segments: untouched

  r.tracked.tracks.clear();  // no tracks at all: every segment an unclassified object
  r.classes.clear();
  ScanPublishing::segment_labels(r, labels);
  for (std::size_t i = 0; i < 5; ++i) EXPECT_EQ(labels[i], 5) << i;
}

}  // namespace
}  // namespace stac::tools
