#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "drivers/velodyne/calibration.hpp"
#include "ego/local_frame.hpp"
#include "evaluation/evaluation.hpp"
#include "evaluation/frames.hpp"
#include "evaluation/tracks_jsonl.hpp"
#include "perception/tracking/tracker.hpp"
#include "shared_data.hpp"
#include "sim/run.hpp"

namespace stac::evaluation {
namespace {

constexpr std::int64_t kStart = 1'767'268'800'000'000'000;
constexpr std::int64_t kScanNs = 100'000'000;

struct Object {
  std::uint32_t id;
  const char* cls;
  double x, y;
  std::uint32_t points = 100;
};

TruthScanRecord truth_scan(int k, const std::vector<Object>& objects) {
  TruthScanRecord s;
  s.scan = static_cast<std::uint64_t>(k);
  s.stamp_ns = kStart + k * kScanNs;
  for (const Object& o : objects) {
    TruthObjectRecord r;
    r.id = o.id;
    r.cls = o.cls;
    r.x = o.x;
    r.y = o.y;
    r.z = 0.8;
    r.length = std::string(o.cls) == "car" ? 4.5 : 0.6;
    r.width = std::string(o.cls) == "car" ? 1.8 : 0.6;
    r.height = 1.6;
    r.points = o.points;
    s.objects.push_back(r);
  }
  return s;
}

TrackRecord track(std::uint64_t id, double x, double y, const char* state = "confirmed",
                  std::int32_t segment = -1) {
  TrackRecord t;
  t.id = id;
  t.state = state;
  t.x = x;
  t.y = y;
  t.segment = segment;
  return t;
}

TracksScan output_scan(int k, std::vector<TrackRecord> tracks) {
  TracksScan s;
  s.scan = static_cast<std::uint64_t>(k);
  s.stamp_ns = kStart + k * kScanNs;
  s.tracks = std::move(tracks);
  return s;
}

// A car along y = 5 and a pedestrian along y = -3 for 10 scans.
std::vector<TruthScanRecord> two_objects() {
  std::vector<TruthScanRecord> truth;
  for (int k = 0; k < 10; ++k) {
    truth.push_back(
        truth_scan(k, {{1, "car", 10.0 + k, 5.0}, {2, "pedestrian", 3.0 + 0.1 * k, -3.0}}));
  }
  return truth;
}

TEST(Eval, PerfectTrackingScoresOne) {
  const auto truth = two_objects();
  std::vector<TracksScan> out;
  for (int k = 0; k < 10; ++k)
    out.push_back(output_scan(k, {track(7, 10.0 + k, 5.0), track(9, 3.0 + 0.1 * k, -3.0)}));
  const EvalResult r = evaluate(truth, out, EvalConfig{});
  EXPECT_EQ(r.paired_scans, 10u);
  EXPECT_EQ(r.clear.gt, 20u);
  EXPECT_EQ(r.clear.tp, 20u);
  EXPECT_DOUBLE_EQ(r.clear.mota(), 1.0);
  EXPECT_DOUBLE_EQ(r.clear.motp(), 1.0);
  EXPECT_NEAR(r.hota.hota(), 1.0, 1e-12);
  EXPECT_NEAR(r.hota.assa(), 1.0, 1e-12);
  EXPECT_EQ(r.clear.id_switches, 0u);
  EXPECT_EQ(r.clear_by_class.at("car").gt, 10u);
  EXPECT_EQ(r.clear_by_class.at("pedestrian").tp, 10u);
}

TEST(Eval, OneIdSwitchIsCountedAndLowersAssociation) {
  const auto truth = two_objects();
  std::vector<TracksScan> out;
  for (int k = 0; k < 10; ++k) {
    out.push_back(
        output_scan(k, {track(k < 5 ? 7 : 8, 10.0 + k, 5.0), track(9, 3.0 + 0.1 * k, -3.0)}));
  }
  const EvalResult r = evaluate(truth, out, EvalConfig{});
  EXPECT_EQ(r.clear.id_switches, 1u);
  EXPECT_EQ(r.clear_by_class.at("car").id_switches, 1u);
  EXPECT_DOUBLE_EQ(r.clear.mota(), 1.0 - 1.0 / 20.0);
  // Car: two halves, each with association IoU 5/10; pedestrian 1: AssA = (10*0.5 + 10*1) / 20.
  EXPECT_NEAR(r.hota.assa(), 0.75, 1e-12);
  EXPECT_NEAR(r.hota.deta(), 1.0, 1e-12);
  EXPECT_NEAR(r.hota.hota(), std::sqrt(0.75), 1e-12);
}

TEST(Eval, MissedObjectIsAFalseNegativeAndAFragmentation) {
  const auto truth = two_objects();
  std::vector<TracksScan> out;
  for (int k = 0; k < 10; ++k) {
    std::vector<TrackRecord> t = {track(9, 3.0 + 0.1 * k, -3.0)};
    if (k != 4 && k != 5) t.push_back(track(7, 10.0 + k, 5.0));
    out.push_back(output_scan(k, t));
  }
  const EvalResult r = evaluate(truth, out, EvalConfig{});
  EXPECT_EQ(r.clear.fn, 2u);
  EXPECT_EQ(r.clear.fp, 0u);
  EXPECT_EQ(r.clear.fragmentations, 1u);
  EXPECT_EQ(r.clear.id_switches, 0u);
  EXPECT_DOUBLE_EQ(r.clear.mota(), 1.0 - 2.0 / 20.0);
  EXPECT_EQ(r.clear_by_class.at("car").fn, 2u);
}

TEST(Eval, GhostIsAFalsePositiveButTracksOnBackgroundAreIgnored) {
  auto truth = two_objects();
  for (auto& s : truth) {
    TruthObjectRecord wall = truth_scan(0, {{50, "wall", 0.0, 20.0}}).objects[0];
    wall.length = 10.0;
    wall.width = 0.3;
    s.objects.push_back(wall);
  }
  std::vector<TracksScan> out;
  for (int k = 0; k < 10; ++k) {
    out.push_back(output_scan(k, {track(7, 10.0 + k, 5.0), track(9, 3.0 + 0.1 * k, -3.0),
                                  track(20, -20.0, -20.0),             // ghost: nothing there
                                  track(21, 3.0, 20.1),                // on the wall
                                  track(22, 12.0, -6.0, "tentative"),  // tentative: not counted
                                  track(23, 80.0, 0.0)}));             // beyond --max-range
  }
  const EvalResult r = evaluate(truth, out, EvalConfig{});
  EXPECT_EQ(r.clear.fp, 10u);
  EXPECT_EQ(r.ignored_tracks, 20u);
  EXPECT_DOUBLE_EQ(r.clear.mota(), 1.0 - 10.0 / 20.0);
  // HOTA: DetA = 20 / (20 + 10) at every threshold, AssA 1.
  EXPECT_NEAR(r.hota.hota(), std::sqrt(20.0 / 30.0), 1e-12);
}

// Issue 47: with only classified outputs scored (`eval --tracklets`), every false positive has
// the class its track was given, and counts against that class; with every track scored, an
// unclassified track's false positive belongs to no class and the per-class counts hold none.
TEST(Eval, FalsePositivesCountAgainstTheirTracksClassWhenEveryOutputIsClassified) {
  const auto truth = two_objects();
  std::vector<TracksScan> out;
  for (int k = 0; k < 10; ++k) {
    std::vector<TrackRecord> tracks = {track(7, 10.0 + k, 5.0), track(9, 3.0 + 0.1 * k, -3.0),
                                       track(20, -20.0, -20.0)};  // a ghost, called a pedestrian
    for (auto& [t, cls] : {std::pair{&tracks[0], "car"}, std::pair{&tracks[1], "pedestrian"},
                           std::pair{&tracks[2], "pedestrian"}}) {
      t->classified = true;
      t->cls = cls;
    }
    out.push_back(output_scan(k, tracks));
  }
  EvalConfig c;
  c.classified_outputs_only = true;
  const EvalResult r = evaluate(truth, out, c);
  EXPECT_TRUE(r.fp_by_class);
  EXPECT_EQ(r.clear.fp, 10u);
  EXPECT_EQ(r.clear_by_class.at("pedestrian").fp, 10u);
  EXPECT_EQ(r.clear_by_class.at("car").fp, 0u);
  EXPECT_DOUBLE_EQ(r.clear_by_class.at("pedestrian").mota(), 1.0 - 10.0 / 10.0);
  EXPECT_NEAR(r.hota_by_class.at("pedestrian").hota(), std::sqrt(10.0 / 20.0), 1e-12);
  const EvalResult every = evaluate(truth, out, EvalConfig{});
  EXPECT_FALSE(every.fp_by_class);
  EXPECT_EQ(every.clear.fp, 10u);
  EXPECT_EQ(every.clear_by_class.at("pedestrian").fp, 0u);
}

TEST(Eval, CoastingTracksCountOnlyWhenAsked) {
  const auto truth = two_objects();
  std::vector<TracksScan> out;
  for (int k = 0; k < 10; ++k) {
    // The pedestrian's track coasts in scans 5..9 (on target), a stale coasting track sits at (0,
    // 30).
    out.push_back(output_scan(k, {track(7, 10.0 + k, 5.0),
                                  track(9, 3.0 + 0.1 * k, -3.0, k < 5 ? "confirmed" : "coasting"),
                                  track(11, 0.0, 30.0, "coasting")}));
  }
  EvalConfig c;
  const EvalResult confirmed_only = evaluate(truth, out, c);
  EXPECT_EQ(confirmed_only.clear.fn, 5u);
  EXPECT_EQ(confirmed_only.clear.fp, 0u);
  c.count_coasting = true;
  const EvalResult with_coasting = evaluate(truth, out, c);
  EXPECT_EQ(with_coasting.clear.fn, 0u);
  EXPECT_EQ(with_coasting.clear.fp, 10u);
}

TEST(Eval, ObjectsBelowMinPointsOrOutOfRangeAreNotCountedNorTheirTracks) {
  std::vector<TruthScanRecord> truth;
  std::vector<TracksScan> out;
  for (int k = 0; k < 5; ++k) {
    truth.push_back(truth_scan(
        k, {{1, "car", 10, 0, 100}, {2, "car", 20, 0, 5}, {3, "pedestrian", 60, 0, 300}}));
    out.push_back(output_scan(k, {track(1, 10, 0), track(2, 20, 0), track(3, 60, 0)}));
  }
  const EvalResult r = evaluate(truth, out, EvalConfig{});
  EXPECT_EQ(r.clear.gt, 5u);
  EXPECT_EQ(r.clear.fp, 0u);
  EXPECT_EQ(r.ignored_tracks, 10u);
  EXPECT_DOUBLE_EQ(r.clear.mota(), 1.0);
}

TEST(Eval, MatchThresholdIsPerClass) {
  // 1.2 m off: a match for a car (2 m), not for a pedestrian (1 m).
  std::vector<TruthScanRecord> truth = {
      truth_scan(0, {{1, "car", 10, 0}, {2, "pedestrian", -10, 0}})};
  std::vector<TracksScan> out = {output_scan(0, {track(1, 11.2, 0), track(2, -11.2, 0)})};
  const EvalResult r = evaluate(truth, out, EvalConfig{});
  EXPECT_EQ(r.clear_by_class.at("car").tp, 1u);
  EXPECT_EQ(r.clear_by_class.at("pedestrian").fn, 1u);
  EXPECT_EQ(r.clear.fp, 1u);
  EXPECT_NEAR(r.clear.motp(), 1.0 - 1.2 / 4.0, 1e-9);
  EXPECT_NEAR(r.clear.motp_distance_m(), 1.2, 1e-9);
}

TEST(Eval, RangeBandsSplitTheCounts) {
  std::vector<TruthScanRecord> truth = {truth_scan(0, {{1, "car", 5, 0}, {2, "car", 35, 0}})};
  std::vector<TracksScan> out = {output_scan(0, {track(1, 5, 0), track(3, -25, 0)})};
  const EvalResult r = evaluate(truth, out, EvalConfig{});
  EXPECT_EQ(r.clear_by_band.at(0).tp, 1u);
  EXPECT_EQ(r.clear_by_band.at(3).fn, 1u);
  EXPECT_EQ(r.clear_by_band.at(2).fp, 1u);
  EXPECT_DOUBLE_EQ(r.clear_by_band.at(0).mota(), 1.0);
}

SegmentRecord segment(std::uint32_t id, std::vector<std::pair<std::int64_t, std::uint32_t>> truth) {
  SegmentRecord s;
  s.id = id;
  s.has_truth = true;
  for (const auto& [k, n] : truth) s.points += n;
  s.truth = std::move(truth);
  return s;
}

TEST(Eval, SegmentHoldingTwoObjectsIsUnderSegmentation) {
  std::vector<TruthScanRecord> truth = {
      truth_scan(0, {{1, "car", 10, 0, 1000}, {2, "pedestrian", 12, 2, 25}})};
  TracksScan o = output_scan(0, {});
  o.segments = {segment(0, {{1, 1000}, {2, 25}, {-1, 12}})};
  const EvalResult r = evaluate(truth, {o}, EvalConfig{});
  ASSERT_TRUE(r.has_segment_truth);
  // The pedestrian shares its segment with 1000 car points; the car's 25 foreign points are under
  // 5% of its own.
  EXPECT_DOUBLE_EQ(r.segmentation_by_class.at("pedestrian").under_rate(), 1.0);
  EXPECT_DOUBLE_EQ(r.segmentation_by_class.at("car").under_rate(), 0.0);
  EXPECT_EQ(r.segmentation.objects, 2u);
  EXPECT_EQ(r.segmentation.under, 1u);
  EXPECT_DOUBLE_EQ(r.segmentation.under_rate(), 0.5);
  EXPECT_DOUBLE_EQ(r.segmentation.over_rate(), 0.0);
}

TEST(Eval, ObjectSplitInTwoSegmentsIsOverSegmentation) {
  std::vector<TruthScanRecord> truth = {
      truth_scan(0, {{1, "car", 10, 0, 200}, {2, "car", -10, 0, 200}})};
  TracksScan o = output_scan(0, {});
  // Car 1 split 60/40; car 2 has a 5% sliver (below the 10% piece share), not over-segmented.
  o.segments = {segment(0, {{1, 120}}), segment(1, {{1, 80}}), segment(2, {{2, 190}}),
                segment(3, {{2, 10}})};
  const EvalResult r = evaluate(truth, {o}, EvalConfig{});
  EXPECT_EQ(r.segmentation.objects, 2u);
  EXPECT_EQ(r.segmentation.over, 1u);
  EXPECT_DOUBLE_EQ(r.segmentation.over_rate(), 0.5);
  EXPECT_EQ(r.segmentation.under, 0u);
}

TEST(Eval, ScansPairByTimeWithinTheTolerance) {
  const auto truth = two_objects();
  std::vector<TracksScan> out;
  for (int k = 0; k < 10; ++k) {
    TracksScan s = output_scan(k, {track(7, 10.0 + k, 5.0), track(9, 3.0 + 0.1 * k, -3.0)});
    s.scan += 100;                              // scan numbers need not agree: time pairs them
    s.stamp_ns += k < 5 ? 400'000 : 5'000'000;  // 0.4 ms pairs, 5 ms does not
    out.push_back(s);
  }
  const EvalResult r = evaluate(truth, out, EvalConfig{});
  EXPECT_EQ(r.paired_scans, 5u);
  EXPECT_EQ(r.clear.gt, 10u);
}

TEST(TracksJsonl, WrittenLinesReadBackAndTimeKeepsItsDigits) {
  TracksScan s =
      output_scan(42, {track(3, 1.25, -2.5, "coasting", -1), track(4, 7, 8, "confirmed", 0)});
  s.stamp_ns = kStart + 123'456'789;
  s.ego = {1, 2, 3, 0.5};
  s.segments = {segment(0, {{5, 30}, {-1, 2}})};
  std::string line;
  append_json_line(s, line);
  EXPECT_NE(line.find("\"time\":1767268800.123456789,"), std::string::npos) << line;
  ASSERT_EQ(line.back(), '\n');
  auto back = parse_tracks_line(line);
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_EQ(back->scan, 42u);
  EXPECT_NEAR(static_cast<double>(back->stamp_ns - s.stamp_ns), 0.0, 1000.0);
  ASSERT_EQ(back->tracks.size(), 2u);
  EXPECT_EQ(back->tracks[0].state, "coasting");
  EXPECT_EQ(back->tracks[0].segment, -1);
  EXPECT_DOUBLE_EQ(back->tracks[0].x, 1.25);
  ASSERT_EQ(back->segments.size(), 1u);
  EXPECT_EQ(back->segments[0].truth,
            (std::vector<std::pair<std::int64_t, std::uint32_t>>{{-1, 2}, {5, 30}}));
  EXPECT_DOUBLE_EQ(back->ego.yaw, 0.5);
  EXPECT_FALSE(back->tracks[0].classified);
}

// Issue 33: the frame a tracks file is written in goes on every line and reads back; what is not
// a frame is refused by name.
TEST(TracksJsonl, TheFrameIsRecordedAndReadBack) {
  TracksScan s = output_scan(5, {track(3, 1, 2)});
  s.frame = TracksFrame::kEnu;
  s.origin = {48.1234567891, 11.5, 520.25};
  std::string line;
  append_json_line(s, line);
  EXPECT_EQ(line.rfind("{\"frame\":\"enu\",\"origin\":[48.1234567891,11.5", 0), 0u) << line;
  auto back = parse_tracks_line(line);
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_EQ(back->frame, TracksFrame::kEnu);
  EXPECT_EQ(back->origin, s.origin);
  s.frame = TracksFrame::kVehicle;
  line.clear();
  append_json_line(s, line);
  back = parse_tracks_line(line);
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_EQ(back->frame, TracksFrame::kVehicle);
  s.frame = TracksFrame::kUnknown;  // a file from before: no key at all
  line.clear();
  append_json_line(s, line);
  EXPECT_EQ(line.find("frame"), std::string::npos) << line;
  back = parse_tracks_line(line);
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_EQ(back->frame, TracksFrame::kUnknown);

  const std::string rest = line.substr(1);  // after '{'
  const std::vector<std::pair<std::string, std::string>> bad = {
      {R"({"frame":"ned",)", "expected enu or vehicle"},
      {R"({"frame":7,)", "'frame' is not a string"},
      {R"({"frame":"enu",)", "missing key 'origin'"},
      {R"({"frame":"enu","origin":[1,2],)", "'origin' must be [lat, lon, alt]"},
      {R"({"frame":"enu","origin":[95,2,0],)", "not a place on Earth"},
      {R"({"frame":"enu","origin":[1,2,null],)", "'origin' must be [lat, lon, alt]"},
      {R"({"frame":"vehicle","origin":[1,2,3],)", "with frame 'vehicle'"},
      {R"({"origin":[1,2,3],)", "without 'frame'"}};
  for (const auto& [head, message] : bad) {
    auto r = parse_tracks_line(head + rest);
    ASSERT_FALSE(r) << head;
    EXPECT_NE(r.error().message.find(message), std::string::npos) << r.error().message;
  }
}

std::vector<TracksScan> tracks_in(TracksFrame frame, std::array<double, 3> origin = {}) {
  std::vector<TracksScan> tracks{output_scan(0, {}), output_scan(1, {})};
  for (TracksScan& t : tracks) t.frame = frame, t.origin = origin;
  return tracks;
}

// ENU at one origin into ENU at another, 2 km away: each box lands where the geodetic position
// says, its heading still points along the same line on the ground, its velocity turned with it.
TEST(EvalFrames, TruthInAnotherEnuFrameIsMovedThroughGeodeticCoordinates) {
  const std::array<double, 3> truth_origin{48.0, 11.0, 500.0}, tracks_origin{48.01, 11.02, 505.0};
  std::vector<TruthScanRecord> truth = two_objects();
  for (TruthScanRecord& s : truth) s.origin = truth_origin;
  truth[3].objects[0].yaw = 0.7;
  truth[3].objects[0].vx = 3.0;
  truth[3].objects[0].vy = 1.0;
  const TruthObjectRecord before = truth[3].objects[0];
  auto note = truth_in_tracks_frame(truth, tracks_in(TracksFrame::kEnu, tracks_origin));
  ASSERT_TRUE(note) << note.error().message;
  EXPECT_NE(note->find("the truth moved from ENU at 48.0000000, 11.0000000"), std::string::npos)
      << *note;

  const ego::LocalFrame from(ego::Geodetic{48.0, 11.0, 500.0});
  ego::LocalFrame to(ego::Geodetic{48.01, 11.02, 505.0});
  const auto moved = [&](double x, double y, double z) {
    return to.to_local(from.to_geodetic(Eigen::Vector3d(x, y, z)));
  };
  const TruthObjectRecord& after = truth[3].objects[0];
  const Eigen::Vector3d expected = moved(before.x, before.y, before.z);
  EXPECT_NEAR(after.x, expected.x(), 1e-6);
  EXPECT_NEAR(after.y, expected.y(), 1e-6);
  EXPECT_NEAR(after.z, expected.z(), 1e-6);
  EXPECT_GT(std::hypot(after.x - before.x, after.y - before.y), 1000.0);
  // 20 m ahead along the old heading is 20 m ahead along the new one (within 2 mm).
  const Eigen::Vector3d ahead =
      moved(before.x + 20 * std::cos(before.yaw), before.y + 20 * std::sin(before.yaw), before.z);
  EXPECT_NEAR(ahead.x(), after.x + 20 * std::cos(after.yaw), 2e-3);
  EXPECT_NEAR(ahead.y(), after.y + 20 * std::sin(after.yaw), 2e-3);
  EXPECT_NE(after.yaw, before.yaw);  // the frames' north differs by 0.015 deg here
  EXPECT_NEAR(std::hypot(after.vx, after.vy), std::hypot(3.0, 1.0), 1e-9);
  EXPECT_NEAR(std::atan2(after.vy, after.vx) - std::atan2(1.0, 3.0), after.yaw - before.yaw, 1e-12);
  const Eigen::Vector3d ego = moved(0, 0, 0);
  EXPECT_NEAR(truth[3].ego.x, ego.x(), 1e-6);

  // The same origin: untouched.
  std::vector<TruthScanRecord> same = two_objects();
  for (TruthScanRecord& s : same) s.origin = truth_origin;
  note = truth_in_tracks_frame(same, tracks_in(TracksFrame::kEnu, truth_origin));
  ASSERT_TRUE(note);
  EXPECT_NE(note->find("frames: the same"), std::string::npos) << *note;
  EXPECT_EQ(same[3].objects[0].x, two_objects()[3].objects[0].x);

  // Another continent: not the same drive.
  note = truth_in_tracks_frame(same, tracks_in(TracksFrame::kEnu, {35.0, 139.0, 10.0}));
  ASSERT_FALSE(note);
  EXPECT_NE(note.error().message.find("km from the tracks'"), std::string::npos)
      << note.error().message;
}

TEST(EvalFrames, VehicleFrameTracksTakeTheParkedTruthIntoItAndRefuseAMovingOne) {
  std::vector<TruthScanRecord> truth = two_objects();
  for (TruthScanRecord& s : truth) s.ego = {100.0, 50.0, 2.0, std::numbers::pi / 2};
  truth[2].objects[0].vx = 4.0;  // moving east; the vehicle faces north
  auto note = truth_in_tracks_frame(truth, tracks_in(TracksFrame::kVehicle));
  ASSERT_TRUE(note) << note.error().message;
  EXPECT_NE(note->find("vehicle frame of its first scan"), std::string::npos) << *note;
  const TruthObjectRecord& car = truth[2].objects[0];  // was at (12, 5): 88 m west, 45 m south
  EXPECT_NEAR(car.x, -45.0, 1e-9);                     // behind
  EXPECT_NEAR(car.y, 88.0, 1e-9);                      // to the left
  EXPECT_NEAR(car.z, 0.8 - 2.0, 1e-9);
  EXPECT_NEAR(car.yaw, -std::numbers::pi / 2, 1e-9);
  EXPECT_NEAR(car.vx, 0.0, 1e-9);
  EXPECT_NEAR(car.vy, -4.0, 1e-9);  // east is to the right
  EXPECT_NEAR(truth[5].ego.x, 0.0, 1e-9);

  std::vector<TruthScanRecord> driving = two_objects();
  for (int k = 0; k < 10; ++k) driving[static_cast<std::size_t>(k)].ego.x = 0.5 * k;
  note = truth_in_tracks_frame(driving, tracks_in(TracksFrame::kVehicle));
  ASSERT_FALSE(note);
  EXPECT_NE(note.error().message.find("the ego moves in the truth (1.0 m by scan 2)"),
            std::string::npos)
      << note.error().message;
}

TEST(EvalFrames, AnUnrecordedFrameIsAssumedAndSaidAndAMixedFileIsRefused) {
  std::vector<TruthScanRecord> truth = two_objects();
  auto note = truth_in_tracks_frame(truth, tracks_in(TracksFrame::kUnknown));
  ASSERT_TRUE(note);
  EXPECT_NE(note->find("does not record its frame"), std::string::npos) << *note;
  note = truth_in_tracks_frame(truth, tracks_in(TracksFrame::kEnu, {48, 11, 0}));
  ASSERT_TRUE(note);
  EXPECT_NE(note->find("the truth does not record its origin"), std::string::npos) << *note;
  EXPECT_EQ(truth[3].objects[0].x, two_objects()[3].objects[0].x);

  std::vector<TracksScan> mixed = tracks_in(TracksFrame::kEnu, {48, 11, 0});
  mixed[1].frame = TracksFrame::kVehicle;
  note = truth_in_tracks_frame(truth, mixed);
  ASSERT_FALSE(note);
  EXPECT_NE(note.error().message.find("changes its frame at scan 1"), std::string::npos)
      << note.error().message;
}

// Issue 31: a number that is not finite is written as null, never as "nan" (not JSON), and the
// reader refuses the line naming the field; the simulator's truth lines likewise. Huge finite
// numbers stay numbers.
TEST(TracksJsonl, NumbersThatAreNotFiniteAreWrittenAsNullAndRefusedByName) {
  TracksScan s = output_scan(1, {track(3, 1, 2), track(4, 7, 8)});
  s.tracks[1].vx = std::numeric_limits<double>::quiet_NaN();
  s.tracks[0].classified = true;
  s.tracks[0].cls = "car";
  s.tracks[0].log_odds = {std::numeric_limits<double>::infinity(), 1.0, -1.0};
  s.ego.x = 3e20;
  std::string line;
  append_json_line(s, line);
  EXPECT_EQ(line.find("nan"), std::string::npos) << line;
  EXPECT_EQ(line.find("inf"), std::string::npos) << line;
  EXPECT_NE(line.find("\"vx\":null"), std::string::npos) << line;
  EXPECT_NE(line.find("\"log_odds\":[null,1.0000,-1.0000]"), std::string::npos) << line;
  EXPECT_NE(line.find("\"x\":3e+20,"), std::string::npos) << line;
  auto back = parse_tracks_line(line);
  ASSERT_FALSE(back);
  EXPECT_NE(back.error().message.find("log_odds"), std::string::npos) << back.error().message;
  s.tracks[0].log_odds = {2.0, 1.0, -1.0};
  line.clear();
  append_json_line(s, line);
  back = parse_tracks_line(line);
  ASSERT_FALSE(back);
  EXPECT_NE(back.error().message.find("vx"), std::string::npos) << back.error().message;

  sim::TruthScan truth;
  truth.ego.yaw = std::numeric_limits<double>::quiet_NaN();
  const std::string t = sim::to_json(truth, nullptr);
  EXPECT_EQ(t.find("nan"), std::string::npos) << t;
  EXPECT_NE(t.find("\"yaw\":null"), std::string::npos) << t;
  auto truth_back = parse_truth_line(t);
  ASSERT_FALSE(truth_back);
  EXPECT_NE(truth_back.error().message.find("yaw"), std::string::npos)
      << truth_back.error().message;
}

TEST(TracksJsonl, ClassifiedTracksCarryTheirClassAndLogOdds) {
  TracksScan s = output_scan(1, {track(3, 1, 2), track(4, 7, 8)});
  s.tracks[1].classified = true;
  s.tracks[1].cls = "pedestrian";
  s.tracks[1].log_odds = {-2.5, 1.25, -0.5};
  std::string line;
  append_json_line(s, line);
  auto back = parse_tracks_line(line);
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_FALSE(back->tracks[0].classified);
  ASSERT_TRUE(back->tracks[1].classified);
  EXPECT_EQ(back->tracks[1].cls, "pedestrian");
  EXPECT_EQ(back->tracks[1].log_odds, (std::vector<double>{-2.5, 1.25, -0.5}));
  const std::string no_odds = "\"class\":\"pedestrian\",\"log_odds\":[-2.5000,1.2500,-0.5000]";
  ASSERT_NE(line.find(no_odds), std::string::npos) << line;
  std::string broken = line;
  broken.replace(broken.find(no_odds), no_odds.size(), "\"class\":\"pedestrian\"");
  auto bad = parse_tracks_line(broken);
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("log_odds"), std::string::npos) << bad.error().message;

  // A model's own classes: any class name, one log odds per class.
  s.tracks[1].cls = "pole";
  s.tracks[1].log_odds = {-2.5, 1.25, -0.5, 3.0};
  line.clear();
  append_json_line(s, line);
  ASSERT_NE(line.find("\"class\":\"pole\",\"log_odds\":[-2.5000,1.2500,-0.5000,3.0000]"),
            std::string::npos)
      << line;
  back = parse_tracks_line(line);
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_EQ(back->tracks[1].cls, "pole");
  EXPECT_EQ(back->tracks[1].log_odds, (std::vector<double>{-2.5, 1.25, -0.5, 3.0}));
}

TEST(TracksJsonl, ReadsTheSimulatorsTruthLines) {
  sim::TruthScan s;
  s.scan = 3;
  s.start_ns = kStart + 300'000'000;
  s.end_ns = s.start_ns + 99'000'000;
  s.ego.x = 1;
  s.objects.push_back(
      {17, sim::ObjectClass::kBicyclist, 5, 6, 0.9, 1.8, 0.6, 1.7, 0.3, 4, 0, 77, 0.35});
  auto r = parse_truth_line(sim::to_json(s));
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r->scan, 3u);
  EXPECT_EQ(r->stamp_ns, s.start_ns);
  ASSERT_EQ(r->objects.size(), 1u);
  EXPECT_EQ(r->objects[0].cls, "bicyclist");
  EXPECT_EQ(r->objects[0].points, 77u);
  EXPECT_DOUBLE_EQ(r->objects[0].x, 5.0);
  EXPECT_DOUBLE_EQ(r->objects[0].vx, 4.0);
}

TEST(TracksJsonl, MalformedFilesNameFileLineAndKey) {
  const auto dir = std::filesystem::temp_directory_path() / "stac_eval_malformed";
  std::filesystem::create_directories(dir);
  sim::TruthScan s;
  s.start_ns = kStart;
  {
    std::ofstream f(dir / "truth.jsonl");
    f << sim::to_json(s)
      << "\n\n{\"scan\":1,\"time\":1.5,\"ego\":{\"x\":0,\"y\":0,\"z\":0,\"yaw\":0}}\n";
  }
  auto t = read_truth_file(dir / "truth.jsonl");
  ASSERT_FALSE(t);
  EXPECT_NE(t.error().message.find("truth.jsonl:3: missing key 'objects'"), std::string::npos)
      << t.error().message;
  {
    std::ofstream f(dir / "tracks.jsonl");
    f << "{\"scan\":0,\"time\":1.0,\"ego\":{\"x\":0,\"y\":0,\"z\":0,\"yaw\":0},\"segments\":[],"
         "\"tracks\":[]}\n"
      << "{\"scan\":1,\"time\":1.1,\"ego\":{\"x\":0,\"y\":0,\"z\":0,\"yaw\":0},\"segments\":[],"
         "\"tracks\":[{\"id\":1}]}\n";
  }
  auto k = read_tracks_file(dir / "tracks.jsonl");
  ASSERT_FALSE(k);
  EXPECT_NE(k.error().message.find("tracks.jsonl:2: missing key 'tracks[].state'"),
            std::string::npos)
      << k.error().message;
  {
    std::ofstream f(dir / "garbage.jsonl");
    f << "{\"scan\":0,\"ti";
  }
  auto g = read_tracks_file(dir / "garbage.jsonl");
  ASSERT_FALSE(g);
  EXPECT_NE(g.error().message.find("garbage.jsonl:1: not valid JSON"), std::string::npos)
      << g.error().message;
  auto none = read_tracks_file(dir / "absent.jsonl");
  ASSERT_FALSE(none);
  EXPECT_NE(none.error().message.find("absent.jsonl: cannot open"), std::string::npos);
}

// Files whose lines parse but do not fit together: a scan twice or out of order, a track twice in
// a scan, a track's segment that is none of the scan's, negative sizes, an unknown class.
TEST(TracksJsonl, InconsistentFilesAreRefusedNamingLineAndWhat) {
  const auto dir = std::filesystem::temp_directory_path() / "stac_eval_inconsistent";
  std::filesystem::create_directories(dir);
  const std::string head = R"("time":1.0,"ego":{"x":0,"y":0,"z":0,"yaw":0},)";
  const std::string segment =
      R"({"id":4,"points":9,"x":1,"y":2,"z":0,"length":1,"width":1,"height":1,"yaw":0})";
  const auto track = [](int id, int seg, const std::string& extra = "", double length = 4) {
    return R"({"id":)" + std::to_string(id) +
           R"(,"state":"confirmed","x":1,"y":2,"z":0,"vx":0,"vy":0,"length":)" +
           std::to_string(length) +
           R"(,"width":1,"height":1,"yaw":0,"points":9,"age":3,"segment":)" + std::to_string(seg) +
           extra + "}";
  };
  const auto scan = [&](int n, const std::string& tracks) {
    return R"({"scan":)" + std::to_string(n) + "," + head + R"("segments":[)" + segment +
           R"(],"tracks":[)" + tracks + "]}\n";
  };
  const std::pair<std::string, std::string> cases[] = {
      {scan(0, track(1, 4)) + scan(0, track(1, 4)),
       ":2: scan 0 after scan 0 (each scan once, in increasing order)"},
      {scan(3, track(1, 4)) + scan(2, track(1, 4)), ":2: scan 2 after scan 3"},
      {scan(0, track(1, 4) + "," + track(1, -1)), ":1: track 1 appears twice in the scan"},
      {scan(0, track(1, 7)),
       ":1: 'tracks[].segment' is 7, the id of no segment of the scan (-1: none)"},
      {scan(0, track(1, -2)), ":1: 'tracks[].segment' is -2"},
      {scan(0, track(1, 4, "", -4)), ":1: 'tracks[]' has a negative length, width or height"},
      {scan(0, track(1, 4, R"(,"class":"two words","log_odds":[0,0,0])")),
       ":1: 'tracks[].class' is 'two words'"},
      {scan(0, track(1, 4, R"(,"class":"car","log_odds":[0,0,0,0,0,0,0,0,0])")),
       ":1: 'tracks[].log_odds' must be 1..8 numbers"},
      {"[]\n", ":1: the line is not a JSON object (one scan per line)"},
  };
  for (const auto& [text, expected] : cases) {
    std::ofstream(dir / "tracks.jsonl") << text;
    auto k = read_tracks_file(dir / "tracks.jsonl");
    ASSERT_FALSE(k) << text;
    EXPECT_NE(k.error().message.find("tracks.jsonl" + expected), std::string::npos)
        << k.error().message;
  }
  std::ofstream(dir / "ok.jsonl") << scan(0, track(1, 4)) +
                                         scan(1, track(1, -1) + "," + track(2, 4));
  EXPECT_TRUE(read_tracks_file(dir / "ok.jsonl"));

  const std::string object =
      R"({"id":5,"class":"car","box":{"x":1,"y":2,"z":0,"length":-4,"width":1.8,)"
      R"("height":1.5,"yaw":0},"velocity":{"x":0,"y":0},"points":40})";
  std::ofstream(dir / "truth.jsonl") << R"({"scan":0,)" + head + R"("objects":[)" + object + "]}\n";
  auto t = read_truth_file(dir / "truth.jsonl");
  ASSERT_FALSE(t);
  EXPECT_NE(t.error().message.find("truth.jsonl:1: 'objects[].box' has a negative length"),
            std::string::npos)
      << t.error().message;
}

}  // namespace
}  // namespace stac::evaluation

namespace stac::evaluation {
namespace {

// The tracker on the simulator's urban drive, fed the truth boxes of every object that returned
// points (centres with 0.1 m noise, background included, as segments would be), evaluated by
// the same code as `stac eval`: the whole chain minus segmentation.
TEST(EvalEndToEnd, TrackerOnSimulatedUrbanTruthTracksWell) {
  constexpr const char* kCalib = "velodyne/calib/rosdrivers_64e_s2.1-sztaki.yaml";
  STAC_REQUIRE_SHARED_DATA(kCalib);
  auto cal = velodyne::load_calibration(stac::testing::shared_data(kCalib));
  ASSERT_TRUE(cal) << cal.error().message;
  sim::RunConfig rc;
  rc.scenario = "urban";
  rc.seed = 101;
  rc.duration_s = 6.0;
  rc.lidar.seed = 101;
  auto run = sim::SimRun::create(*cal, rc);
  ASSERT_TRUE(run) << run.error().message;

  tracking::Tracker tracker(tracking::TrackerConfig{});
  tracking::TrackerOutput out(tracker.config().max_tracks);
  std::mt19937 rng(4);
  std::normal_distribution<float> noise(0.0f, 0.1f);
  std::vector<TruthScanRecord> truth;
  std::vector<TracksScan> outputs;
  std::vector<tracking::Detection> dets;
  auto on_scan = [&](const sim::TruthScan& s) {
    auto parsed = parse_truth_line(sim::to_json(s));
    ASSERT_TRUE(parsed) << parsed.error().message;
    truth.push_back(*parsed);
    dets.clear();
    for (const sim::TruthObject& o : s.objects) {
      if (o.points < 5) continue;
      tracking::Detection d;
      d.centroid = Eigen::Vector3f(static_cast<float>(o.x) + noise(rng),
                                   static_cast<float>(o.y) + noise(rng), static_cast<float>(o.z));
      d.length = static_cast<float>(o.length);
      d.width = static_cast<float>(o.width);
      d.height = static_cast<float>(o.height);
      d.yaw = static_cast<float>(o.yaw);
      d.points = o.points;
      d.segment = static_cast<std::uint32_t>(dets.size());
      dets.push_back(d);
    }
    tracker.update(s.start_ns, dets, out);
    TracksScan line;
    line.scan = s.scan;
    line.stamp_ns = s.start_ns;
    for (const tracking::Track& t : out.tracks) line.tracks.push_back(track_record(t));
    std::string text;
    append_json_line(line, text);
    auto back = parse_tracks_line(text);
    ASSERT_TRUE(back) << back.error().message;
    outputs.push_back(*back);
  };
  std::array<std::uint8_t, velodyne::kPacketSize> bytes{};
  std::int64_t first = 0;
  for (std::uint32_t k = 0; k < (*run)->packet_count(); ++k)
    (*run)->packet(k, bytes, first, on_scan);
  ASSERT_GE(truth.size(), 50u);

  const EvalResult r = evaluate(truth, outputs, EvalConfig{});
  EXPECT_EQ(r.paired_scans, truth.size());
  EXPECT_GT(r.clear.gt, 200u) << "the urban drive should show objects";
  // The first confirm_hits - 1 scans of every object are tentative, hence the FN; the rest should
  // be close to perfect.
  // Measured: GT 1412, FN 48, FP 0, IDSW 0, MOTA 0.966, HOTA 0.961 - before the simulator's
  // traffic fix; since then pedestrians in groups stop and wait for the ego and for cars, and the
  // constant-velocity tracker swaps ids inside groups: GT 1639, FN 60, FP 2, IDSW 7 (all
  // pedestrians), MOTA 0.958. With fragments, overlapping tracks and people kept apart
  // (docs/tracking.md): FN 59, IDSW 7, MOTA 0.959. Bringing the switches down is open work.
  EXPECT_GE(r.clear.mota(), 0.95) << "FN " << r.clear.fn << " FP " << r.clear.fp << " IDSW "
                                  << r.clear.id_switches;
  for (const auto& [cls, c] : r.clear_by_class)
    RecordProperty("idsw_" + cls, static_cast<int>(c.id_switches));
  RecordProperty("mota_permille", static_cast<int>(std::lround(1000 * r.clear.mota())));
  RecordProperty("fn", static_cast<int>(r.clear.fn));
  EXPECT_LE(r.clear.id_switches, 7u)
      << "MOTA " << r.clear.mota() << " FN " << r.clear.fn << " FP " << r.clear.fp;
  EXPECT_EQ(r.clear_by_class.at("car").id_switches, 0u);
  EXPECT_GE(r.hota.hota(), 0.9);
  EXPECT_EQ(tracker.counters().pool_overflow, 0u);
}

}  // namespace
}  // namespace stac::evaluation
