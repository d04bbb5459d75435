#include "perception/tracking/tracker.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <stdexcept>
#include <vector>

#include "rt/testing/alloc_counter.hpp"

namespace stac::tracking {
namespace {

static_assert(noexcept(std::declval<Tracker&>().update(0, {}, std::declval<TrackerOutput&>())));

constexpr std::int64_t kScanNs = 100'000'000;  // 10 Hz

// A walker-sized detection (point targets of the filter and assignment tests: people may walk
// 1 m apart, cars may not).
Detection det(double x, double y, std::uint32_t segment, double z = 0.8) {
  Detection d;
  d.centroid = Eigen::Vector3f(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z));
  d.length = 0.6f;
  d.width = 0.5f;
  d.height = 1.7f;
  d.points = 100;
  d.segment = segment;
  return d;
}

const Track* by_segment(const TrackerOutput& out, std::uint32_t segment) {
  for (const Track& t : out.tracks) {
    if (t.segment == static_cast<std::int32_t>(segment)) return &t;
  }
  return nullptr;
}

const Track* by_id(const TrackerOutput& out, std::uint64_t id) {
  for (const Track& t : out.tracks) {
    if (t.id == id) return &t;
  }
  return nullptr;
}

TEST(Tracker, ConstantVelocityTargetsKeepStableIdsAndVelocities) {
  Tracker tracker(TrackerConfig{});
  TrackerOutput out(tracker.config().max_tracks);
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.08);
  struct Target {
    double x, y, vx, vy;
  };
  const std::vector<Target> targets = {
      {0, 5, 10, 0}, {10, -8, 0, 1.5}, {-15, -15, 0, 0}, {20, 20, -6, -6}};
  std::vector<std::uint64_t> ids(targets.size(), 0);
  std::vector<Detection> dets;
  for (int k = 0; k < 60; ++k) {
    const double t = k * 0.1;
    dets.clear();
    for (std::size_t i = 0; i < targets.size(); ++i) {
      const Target& g = targets[i];
      dets.push_back(det(g.x + g.vx * t + noise(rng), g.y + g.vy * t + noise(rng),
                         static_cast<std::uint32_t>(i)));
    }
    tracker.update(k * kScanNs, dets, out);
    for (std::size_t i = 0; i < targets.size(); ++i) {
      const Track* tr = by_segment(out, static_cast<std::uint32_t>(i));
      ASSERT_NE(tr, nullptr) << "target " << i << " scan " << k;
      if (ids[i] == 0) ids[i] = tr->id;
      EXPECT_EQ(tr->id, ids[i]) << "target " << i << " changed id at scan " << k;
      // 100-point detections: confirmed at the second hit (confirm_large_points).
      if (k >= 1)
        EXPECT_EQ(tr->state, TrackState::kConfirmed);
      else
        EXPECT_EQ(tr->state, TrackState::kTentative);
    }
  }
  EXPECT_EQ(out.tracks.size(), targets.size());
  for (std::size_t i = 0; i < targets.size(); ++i) {
    const Track* tr = by_id(out, ids[i]);
    EXPECT_NEAR(tr->velocity.x(), targets[i].vx, 0.4) << i;
    EXPECT_NEAR(tr->velocity.y(), targets[i].vy, 0.4) << i;
    EXPECT_EQ(tr->features.segment_count(), 60u);
    // Noise of 0.08 m over the 0.4 s window alone makes a still target read about 0.35 m/s.
    EXPECT_NEAR(tr->features.mean_speed_mps(), std::hypot(targets[i].vx, targets[i].vy), 0.5) << i;
    EXPECT_EQ(tr->age, 59u);
  }
  EXPECT_EQ(tracker.counters().spawned, targets.size());
}

TEST(Tracker, TargetsCrossingPathsKeepTheirIds) {
  // A walks along y = 0, B along x = 0; they pass the crossing 1 m apart in the same scan.
  Tracker tracker(TrackerConfig{});
  TrackerOutput out(tracker.config().max_tracks);
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.05);
  std::uint64_t id_a = 0, id_b = 0;
  for (int k = 0; k <= 100; ++k) {
    const double t = k * 0.1;
    const std::vector<Detection> dets = {det(-10 + 2 * t + noise(rng), noise(rng), 0),
                                         det(noise(rng), -9 + 2 * t + noise(rng), 1)};
    tracker.update(k * kScanNs, dets, out);
    const Track* a = by_segment(out, 0);
    const Track* b = by_segment(out, 1);
    ASSERT_TRUE(a != nullptr && b != nullptr) << k;
    if (k == 0) {
      id_a = a->id;
      id_b = b->id;
    }
    EXPECT_EQ(a->id, id_a) << "scan " << k;
    EXPECT_EQ(b->id, id_b) << "scan " << k;
  }
  EXPECT_EQ(tracker.counters().spawned, 2u);
}

TEST(Tracker, GlobalAssignmentKeepsIdsWhereGreedyWouldSwap) {
  // Two walkers side by side (y = 0 and y = 1) at 1.5 m/s. In scan 30 A's detection is pushed
  // 0.55 m towards B and B's 0.9 m away from A: the single cheapest pair is (B, A's detection),
  // and A cannot reach B's detection (gate 1.5 m), so greedy matching would hand A's detection
  // to B and drop A. The global solution keeps both.
  TrackerConfig c;
  c.gate.mahalanobis_sq = 1e6;  // Euclidean gate only, to make the geometry exact
  c.gate.distance_m = 1.5;
  Tracker tracker(c);
  TrackerOutput out(c.max_tracks);
  std::uint64_t id_a = 0, id_b = 0;
  for (int k = 0; k < 40; ++k) {
    const double x = 1.5 * k * 0.1;
    double ya = 0, yb = 1;
    if (k == 30) {
      ya += 0.55;
      yb += 0.9;
      // The trap is real: the cheapest pair is B with A's detection; A-to-B's is out of the gate.
      const Track* a = by_id(out, id_a);
      const Track* b = by_id(out, id_b);
      const double pa_da = std::abs(ya - a->position.y()), pb_da = std::abs(ya - b->position.y());
      const double pa_db = std::abs(yb - a->position.y()), pb_db = std::abs(yb - b->position.y());
      ASSERT_LT(pb_da, pa_da);
      ASSERT_LT(pb_da, pb_db);
      ASSERT_GT(pa_db, c.gate.distance_m);
    }
    tracker.update(k * kScanNs, std::vector<Detection>{det(x, ya, 0), det(x, yb, 1)}, out);
    const Track* a = by_segment(out, 0);
    const Track* b = by_segment(out, 1);
    ASSERT_TRUE(a != nullptr && b != nullptr) << k;
    if (k == 0) {
      id_a = a->id;
      id_b = b->id;
    }
    EXPECT_EQ(a->id, id_a) << "scan " << k;
    EXPECT_EQ(b->id, id_b) << "scan " << k;
  }
  EXPECT_EQ(tracker.counters().spawned, 2u);
}

TEST(Tracker, OccludedTargetCoastsAndIsReassociated) {
  Tracker tracker(TrackerConfig{});
  TrackerOutput out(tracker.config().max_tracks);
  std::uint64_t id = 0;
  for (int k = 0; k < 40; ++k) {
    const double x = 5.0 * k * 0.1;
    std::vector<Detection> dets;
    const bool occluded = k >= 20 && k < 25;
    if (!occluded) dets.push_back(det(x, 2.0, 0));
    tracker.update(k * kScanNs, dets, out);
    ASSERT_EQ(out.tracks.size(), 1u) << "scan " << k;
    const Track& t = out.tracks[0];
    if (k == 0) id = t.id;
    EXPECT_EQ(t.id, id) << "scan " << k;
    if (occluded) {
      EXPECT_EQ(t.state, TrackState::kCoasting) << k;
      EXPECT_EQ(t.segment, -1);
      EXPECT_EQ(t.misses, static_cast<std::uint32_t>(k - 19));
      EXPECT_NEAR(t.position.x(), x, 0.3) << "prediction during the occlusion, scan " << k;
    } else if (k >= 2) {
      EXPECT_EQ(t.state, TrackState::kConfirmed) << k;
    }
  }
  EXPECT_EQ(tracker.counters().spawned, 1u);
}

TEST(Tracker, TargetThatLeavesIsDeletedWhenUncertaintyPassesTheThreshold) {
  TrackerConfig c;
  c.life.max_coast_scans = 1000;  // only the uncertainty can end it
  Tracker tracker(c);
  TrackerOutput out(c.max_tracks);
  for (int k = 0; k < 20; ++k)
    tracker.update(k * kScanNs, std::vector<Detection>{det(k * 0.3, 0, 0)}, out);
  ASSERT_EQ(out.tracks.size(), 1u);
  float previous_std = out.tracks[0].position_std_m;
  int k = 20;
  for (; k < 200 && !out.tracks.empty(); ++k) {
    tracker.update(k * kScanNs, {}, out);
    if (out.tracks.empty()) break;
    EXPECT_EQ(out.tracks[0].state, TrackState::kCoasting);
    EXPECT_GT(out.tracks[0].position_std_m, previous_std) << "uncertainty grows while coasting";
    EXPECT_LE(out.tracks[0].position_std_m, c.life.max_position_std_m);
    previous_std = out.tracks[0].position_std_m;
  }
  EXPECT_TRUE(out.tracks.empty()) << "still alive after " << k - 20 << " missed scans";
  EXPECT_GT(k - 20, 3);
  EXPECT_EQ(tracker.counters().deleted_uncertain, 1u);
  EXPECT_EQ(tracker.counters().deleted_coasting, 0u);
  EXPECT_EQ(tracker.live_tracks(), 0u);
}

TEST(Tracker, CoastingTooLongDeletesTheTrack) {
  TrackerConfig c;
  c.life.max_coast_scans = 3;
  c.life.max_position_std_m = 100.0;
  Tracker tracker(c);
  TrackerOutput out(c.max_tracks);
  for (int k = 0; k < 10; ++k)
    tracker.update(k * kScanNs, std::vector<Detection>{det(0, 0, 0)}, out);
  for (int k = 10; k < 13; ++k) {
    tracker.update(k * kScanNs, {}, out);
    EXPECT_EQ(out.tracks.size(), 1u) << k;
  }
  tracker.update(13 * kScanNs, {}, out);
  EXPECT_TRUE(out.tracks.empty());
  EXPECT_EQ(tracker.counters().deleted_coasting, 1u);
}

// A track is confirmed at its confirm_hits-th hit, or at its confirm_large_hits-th when that
// hit's segment has at least confirm_large_points points (near, well-seen objects).
TEST(Tracker, LargeSegmentsConfirmAfterFewerHits) {
  struct Case {
    std::uint32_t points, large_points;
    int confirmed_at;  // scan index of the first confirmed state
  };
  for (const Case& k : {Case{60, 50, 1}, Case{49, 50, 2}, Case{500, 0, 2}}) {
    TrackerConfig c;
    c.life.confirm_large_points = k.large_points;
    Tracker tracker(c);
    TrackerOutput out(c.max_tracks);
    for (int s = 0; s < 4; ++s) {
      Detection d = det(10 + 0.1 * s, 5, 0);
      d.points = k.points;
      tracker.update(s * kScanNs, std::vector<Detection>{d}, out);
      ASSERT_EQ(out.tracks.size(), 1u);
      EXPECT_EQ(out.tracks[0].state,
                s >= k.confirmed_at ? TrackState::kConfirmed : TrackState::kTentative)
          << k.points << " points, confirm_large_points " << k.large_points << ", scan " << s;
    }
  }
}

TEST(Tracker, ClutterSpawnsTentativeTracksThatNeverConfirm) {
  Tracker tracker(TrackerConfig{});
  TrackerOutput out(tracker.config().max_tracks);
  std::mt19937 rng(99);
  std::uniform_real_distribution<double> where(-100.0, 100.0);
  std::set<std::uint64_t> ids;
  std::uint64_t max_id = 0;
  for (int k = 0; k < 200; ++k) {
    std::vector<Detection> dets;
    for (std::uint32_t i = 0; i < 10; ++i) {
      dets.push_back(det(where(rng), where(rng), i));
      dets.back().points = 12;  // noise blobs: below confirm_large_points
    }
    tracker.update(k * kScanNs, dets, out);
    for (const Track& t : out.tracks) {
      EXPECT_EQ(t.state, TrackState::kTentative) << "clutter confirmed at scan " << k;
      if (ids.insert(t.id).second) {
        EXPECT_GT(t.id, max_id) << "ids are never reused";
        max_id = t.id;
      }
    }
    EXPECT_LE(out.tracks.size(), 20u);
  }
  EXPECT_GE(tracker.counters().spawned, 1900u);
  EXPECT_EQ(tracker.counters().deleted_tentative + tracker.live_tracks(),
            tracker.counters().spawned);
}

TEST(Tracker, PoolOverflowIsCounted) {
  TrackerConfig c;
  c.max_tracks = 4;
  Tracker tracker(c);
  TrackerOutput out(c.max_tracks);
  std::vector<Detection> dets;
  for (std::uint32_t i = 0; i < 6; ++i) dets.push_back(det(20.0 * i, 0, i));
  tracker.update(0, dets, out);
  EXPECT_EQ(out.tracks.size(), 4u);
  EXPECT_EQ(out.counters.pool_overflow, 2u);
  tracker.update(kScanNs, dets, out);
  EXPECT_EQ(out.tracks.size(), 4u);
  EXPECT_EQ(out.counters.pool_overflow, 4u);
  for (const Track& t : out.tracks) EXPECT_LT(t.segment, 4) << "the first four keep their tracks";
}

TEST(Tracker, DetectionsBeyondCapacityAndStampRegressionsAreCounted) {
  TrackerConfig c;
  c.max_detections = 3;
  Tracker tracker(c);
  TrackerOutput out(c.max_tracks);
  std::vector<Detection> dets;
  for (std::uint32_t i = 0; i < 5; ++i) dets.push_back(det(20.0 * i, 0, i));
  tracker.update(kScanNs, dets, out);
  EXPECT_EQ(out.tracks.size(), 3u);
  EXPECT_EQ(out.counters.dropped_detections, 2u);
  tracker.update(0, dets, out);  // earlier stamp: no prediction, still associates
  EXPECT_EQ(out.counters.stamp_regressions, 1u);
  EXPECT_EQ(out.tracks.size(), 3u);
}

TEST(Tracker, NonFiniteDetectionsAreCountedAndIgnored) {
  Tracker tracker(TrackerConfig{});
  TrackerOutput out(tracker.config().max_tracks);
  for (int k = 0; k < 5; ++k) {
    std::vector<Detection> dets = {det(k * 0.5, 0, 0), det(std::nan(""), 1, 1),
                                   det(5, std::numeric_limits<double>::infinity(), 2)};
    tracker.update(k * kScanNs, dets, out);
    ASSERT_EQ(out.tracks.size(), 1u);
    EXPECT_TRUE(out.tracks[0].position.allFinite());
    EXPECT_EQ(out.tracks[0].segment, 0);
  }
  EXPECT_EQ(tracker.counters().invalid_detections, 10u);
}

TEST(Tracker, HolisticFeaturesOfATargetOnACircle) {
  // 5 m/s on a circle of radius 10 m: angular velocity 0.5 rad/s, centripetal accel 2.5 m/s^2.
  Tracker tracker(TrackerConfig{});
  TrackerOutput out(tracker.config().max_tracks);
  for (int k = 0; k < 100; ++k) {
    const double a = 0.5 * k * 0.1;
    tracker.update(k * kScanNs, std::vector<Detection>{det(10 * std::cos(a), 10 * std::sin(a), 0)},
                   out);
  }
  ASSERT_EQ(out.tracks.size(), 1u);
  const HolisticFeatures& f = out.tracks[0].features;
  EXPECT_EQ(f.segment_count(), 100u);
  EXPECT_NEAR(f.max_speed_mps(), 5.0, 0.05);
  EXPECT_NEAR(f.mean_speed_mps(), 5.0, 0.05);
  EXPECT_NEAR(f.max_angular_velocity_rps(), 0.5, 0.03);
  EXPECT_NEAR(f.mean_accel_mps2(), 2.5, 0.2);
  EXPECT_NEAR(f.smoothed_velocity().norm(), 5.0, 0.05);
}

TEST(Tracker, BoxIsSmoothedAndYawWrapsModuloPi) {
  TrackerConfig c;
  c.box_smoothing = 0.5;
  Tracker tracker(c);
  TrackerOutput out(c.max_tracks);
  Detection d = det(0, 0, 0);
  d.length = 4.0f;
  d.yaw = 1.5f;
  tracker.update(0, std::vector<Detection>{d}, out);
  d.yaw = -1.5f;  // the same box heading flipped by pi, about 0.14 rad away
  d.length = 5.0f;
  tracker.update(kScanNs, std::vector<Detection>{d}, out);
  ASSERT_EQ(out.tracks.size(), 1u);
  EXPECT_NEAR(out.tracks[0].length, 4.5f, 1e-5);
  const double yaw = out.tracks[0].yaw;
  EXPECT_NEAR(std::abs(std::remainder(yaw - 1.5 - 0.0708, 3.14159265)), 0.0, 1e-3) << yaw;
}

// A box detection: centre (x, y), size, heading; the centroid at the box centre.
Detection box(double x, double y, double length, double width, double height, double yaw,
              std::uint32_t segment) {
  Detection d = det(x, y, segment);
  d.box_center = Eigen::Vector2f(static_cast<float>(x), static_cast<float>(y));
  d.length = static_cast<float>(length);
  d.width = static_cast<float>(width);
  d.height = static_cast<float>(height);
  d.yaw = static_cast<float>(yaw);
  return d;
}

// Five scans of `piece` alone (its track confirms), then five of `piece` and `fragment`. Returns
// the ids of the tracks after the first five.
std::vector<std::uint64_t> piece_then_fragment(Tracker& tracker, TrackerOutput& out,
                                               const Detection& piece, const Detection& fragment) {
  for (int k = 0; k < 5; ++k) tracker.update(k * kScanNs, std::vector<Detection>{piece}, out);
  std::vector<std::uint64_t> ids;
  for (const Track& t : out.tracks) ids.push_back(t.id);
  for (int k = 5; k < 10; ++k) {
    tracker.update(k * kScanNs, std::vector<Detection>{piece, fragment}, out);
  }
  return ids;
}

TEST(Tracker, MeasuresTheBoxCentreOrTheCentroidAsConfigured) {
  for (const bool from_box : {true, false}) {
    TrackerConfig c;
    c.position_from_box = from_box;
    Tracker tracker(c);
    TrackerOutput out(c.max_tracks);
    Detection d = box(20, 5, 4.5, 1.8, 1.5, 0, 0);
    d.centroid = Eigen::Vector3f(18.5f, 5.0f, 0.8f);  // the points sit on the near side
    for (int k = 0; k < 5; ++k) tracker.update(k * kScanNs, std::vector<Detection>{d}, out);
    ASSERT_EQ(out.tracks.size(), 1u);
    EXPECT_NEAR(out.tracks[0].position.x(), from_box ? 20.0 : 18.5, 1e-3);
    EXPECT_NEAR(out.tracks[0].position.z(), 0.8, 1e-3);
  }
}

TEST(Tracker, FragmentBesideAMatchedTrackJoinsItsMeasurement) {
  // One car, 4.4 m long along x, seen as a rear part and a cabin part with road between them.
  TrackerConfig c;
  Tracker tracker(c);
  TrackerOutput out(c.max_tracks);
  const std::vector<std::uint64_t> before = piece_then_fragment(
      tracker, out, box(30.5, 0, 1.0, 1.8, 0.6, 0, 0), box(32.6, 0, 1.6, 1.8, 1.2, 0, 1));
  ASSERT_EQ(before.size(), 1u);
  ASSERT_EQ(out.tracks.size(), 1u);  // the cabin never spawned a track
  EXPECT_EQ(out.tracks[0].id, before[0]);
  EXPECT_EQ(tracker.counters().absorbed_detections, 5u);
  EXPECT_EQ(tracker.counters().spawned, 1u);
  // The measurement is the union 30.0..33.4 m: the filter moves towards its centre 31.7 m.
  EXPECT_GT(out.tracks[0].position.x(), 31.2f);
  EXPECT_GT(out.tracks[0].length, 2.0f);
}

// Two pieces moving together at 5 m/s: the older alone for 3 scans, then the younger 2.5 m
// ahead (gap beyond absorb_gap_m 2 m), the gap closing by `closing` m a scan (down to 1.5 m).
// Returns the older track's id.
std::uint64_t pieces_closing_in(Tracker& tracker, TrackerOutput& out, double closing, int scans) {
  for (int k = 0; k < 3; ++k) {
    tracker.update(k * kScanNs, std::vector<Detection>{box(20 + 0.5 * k, 0, 1.0, 1.8, 0.6, 0, 0)},
                   out);
  }
  EXPECT_EQ(out.tracks.size(), 1u);
  const std::uint64_t older = out.tracks.empty() ? 0 : out.tracks[0].id;
  for (int k = 3; k < scans; ++k) {
    const double x = 20 + 0.5 * k;
    const double gap_closed = std::min(1.0, closing * (k - 3));
    tracker.update(k * kScanNs,
                   std::vector<Detection>{box(x, 0, 1.0, 1.8, 0.6, 0, 0),
                                          box(x + 3.6 - gap_closed, 0, 1.2, 1.8, 1.2, 0, 1)},
                   out);
  }
  return older;
}

TEST(Tracker, YoungerTrackOfAFragmentMergesIntoTheOlderOne) {
  // The gap closes at 0.1 m a scan: below 2 m at scan 9, while the younger track has fewer than
  // absorb_established_hits (10) hits. It is merged into the older one, whose id lives on.
  TrackerConfig c;
  Tracker tracker(c);
  TrackerOutput out(c.max_tracks);
  const std::uint64_t older = pieces_closing_in(tracker, out, 0.1, 20);
  ASSERT_EQ(out.tracks.size(), 1u);
  EXPECT_EQ(out.tracks[0].id, older);
  EXPECT_GE(tracker.counters().deleted_merged, 1u);  // the first; a tentative may follow it
}

TEST(Tracker, AnEstablishedTrackBesideAnOlderOneKeepsItsOwnId) {
  // The same pieces, the gap closing at 0.03 m a scan: below 2 m at scan 20, when the younger
  // track has 18 hits. With absorb_established_hits (10) it is an object of its own (two cars
  // nose to tail, a person by a car) and is never joined; with the rule off it is merged.
  for (const std::uint32_t established : {10u, 0u}) {
    SCOPED_TRACE(established);
    TrackerConfig c;
    c.fragments.established_hits = established;
    Tracker tracker(c);
    TrackerOutput out(c.max_tracks);
    const std::uint64_t older = pieces_closing_in(tracker, out, 0.03, 40);
    if (established > 0) {
      ASSERT_EQ(out.tracks.size(), 2u);
      EXPECT_EQ(by_segment(out, 0)->id, older);
      EXPECT_NE(by_segment(out, 1), nullptr);
      EXPECT_EQ(tracker.counters().deleted_merged, 0u);
      EXPECT_EQ(tracker.counters().absorbed_detections, 0u);
    } else {
      ASSERT_EQ(out.tracks.size(), 1u);
      EXPECT_EQ(out.tracks[0].id, older);
      EXPECT_GE(tracker.counters().deleted_merged, 1u);
    }
  }
}

TEST(Tracker, PeopleAndWholeCarsAreNeverJoined) {
  TrackerConfig c;
  Tracker tracker(c);
  TrackerOutput out(c.max_tracks);
  for (int k = 0; k < 6; ++k) {
    tracker.update(k * kScanNs,
                   std::vector<Detection>{box(10, 5, 0.6, 0.5, 1.7, 0, 0),
                                          box(10.9, 5, 0.6, 0.5, 1.75, 0, 1),  // two walkers
                                          box(20, -5, 4.5, 1.8, 1.5, 0, 2),
                                          box(25, -5, 4.5, 1.8, 1.5, 0, 3)},  // parked cars
                   out);
  }
  EXPECT_EQ(out.tracks.size(), 4u);
  EXPECT_EQ(tracker.counters().absorbed_detections, 0u);
}

// A parked car seen end-on at 30 m: its front (1.5 x 2 m, too wide for a person), and its side
// as a flat strip (1.6 m x 2 cm, 1.4 m tall) beside it. The strip is as long, narrow and tall
// as a walker's box, but a box that flat is a surface (absorb_strip_*): it joins the front's
// measurement. With the rule off it is a "person" and gets a confirmed track of its own.
TEST(Tracker, AFlatStripBesideACarIsItsSideNotAPerson) {
  for (const double strip_width : {0.1, 0.0}) {
    TrackerConfig c;
    c.person.strip_width_m = strip_width;
    Tracker tracker(c);
    TrackerOutput out(c.max_tracks);
    piece_then_fragment(tracker, out, box(30.0, 0, 1.5, 2.0, 1.5, 0, 0),
                        box(31.55, 0.95, 1.6, 0.02, 1.4, 0, 1));
    if (strip_width > 0) {
      ASSERT_EQ(out.tracks.size(), 1u);
      // Joined to the face's measurement in most scans; the strip's odd track of a scan where it
      // was not is merged as it lies in the car's box (overlap merge).
      EXPECT_GE(tracker.counters().absorbed_detections, 3u);
      EXPECT_GT(out.tracks[0].length, 1.6f);  // the union 29.25..32.35 m, smoothed towards it
    } else {
      EXPECT_EQ(out.tracks.size(), 2u);
      EXPECT_EQ(tracker.counters().absorbed_detections, 0u);
    }
  }
}

// A 9 m truck seen as its cab and its cargo box (both tall, the segmenter clips them at 2.5 m)
// with road between them: one track, as absorb_tall_length_m allows; the same two pieces as
// low as a van's (two vans queueing, union 9 m > absorb_max_length_m) stay two tracks, and so
// do the truck's pieces with absorb_tall_height_m 0.
TEST(Tracker, TallPiecesOfATruckMakeOneTrackUpToTheTallLength) {
  struct Case {
    double height, tall_height;
    std::size_t tracks;
  };
  for (const Case& k : {Case{2.3, 2.1, 1}, Case{1.9, 2.1, 2}, Case{2.3, 0.0, 2}}) {
    TrackerConfig c;
    c.object.tall_height_m = k.tall_height;
    Tracker tracker(c);
    TrackerOutput out(c.max_tracks);
    for (int s = 0; s < 5; ++s)
      tracker.update(s * kScanNs, std::vector<Detection>{box(30, 0, 6.0, 2.4, k.height, 0, 0)},
                     out);
    for (int s = 5; s < 10; ++s) {
      tracker.update(s * kScanNs,
                     std::vector<Detection>{box(30, 0, 6.0, 2.4, k.height, 0, 0),
                                            box(34.4, 0, 1.8, 2.4, k.height, 0, 1)},
                     out);
      if (k.tracks == 1) {
        ASSERT_EQ(out.tracks.size(), 1u) << "scan " << s;
      }
    }
    EXPECT_EQ(out.tracks.size(), k.tracks) << "height " << k.height << " tall " << k.tall_height;
    if (k.tracks == 1) {
      EXPECT_GE(tracker.counters().absorbed_detections, 1u);
      // Longer than either piece: the union 27.0 .. 35.3 m (8.3 m) enters the smoothed box.
      EXPECT_GT(out.tracks[0].length, 6.5f);
    }
  }
}

TEST(Tracker, AbsorbingIsOffWithAZeroGap) {
  TrackerConfig c;
  c.fragments.gap_m = 0;
  Tracker tracker(c);
  TrackerOutput out(c.max_tracks);
  piece_then_fragment(tracker, out, box(30.5, 0, 1.0, 1.8, 0.6, 0, 0),
                      box(32.6, 0, 1.6, 1.8, 1.2, 0, 1));
  EXPECT_EQ(out.tracks.size(), 2u);
  EXPECT_EQ(tracker.counters().absorbed_detections, 0u);
}

TEST(CompleteEndOn, AVehicleFaceAcrossTheRayBecomesAVehicleLongBoxBeyondIt) {
  const TrackerConfig c;
  const Eigen::Vector2f sensor(10, 10);
  // The rear of a car 30 m ahead along +x: 1.8 m across the ray, 0.3 m deep, 1.4 m tall.
  Detection d = box(40, 10, 1.8, 0.3, 1.4, M_PI / 2, 0);
  ASSERT_TRUE(complete_end_on(c, sensor, d));
  EXPECT_NEAR(d.box_center.x(), 40 + (4.5 - 0.3) / 2, 1e-4);
  EXPECT_NEAR(d.box_center.y(), 10, 1e-4);
  EXPECT_FLOAT_EQ(d.length, 4.5f);
  EXPECT_FLOAT_EQ(d.width, 1.8f);
  EXPECT_NEAR(d.yaw, 0, 1e-6);
  // Behind the sensor (-y): the box extends further away, towards -y.
  Detection behind = box(10, -20, 2.0, 0.5, 1.5, 0.1, 0);
  ASSERT_TRUE(complete_end_on(c, sensor, behind));
  EXPECT_NEAR(behind.box_center.y(), -20 - 2.0, 1e-4);
}

TEST(CompleteEndOn, LeavesSidesPeopleLowWallsNearAndUnboxedDetectionsAlone) {
  const TrackerConfig c;
  const Eigen::Vector2f sensor(0, 0);
  const std::vector<Detection> untouched{
      box(30, 0, 1.8, 0.3, 1.4, 0, 0),         // long side along the ray: a side, not a face
      box(30, 0, 0.6, 0.4, 1.7, M_PI / 2, 0),  // a person
      box(30, 0, 1.1, 0.3, 0.6, M_PI / 2, 0),  // too narrow: a person or a post
      box(30, 0, 3.5, 0.3, 1.4, M_PI / 2, 0),  // too wide: a wall or a truck's side
      box(30, 0, 1.8, 1.7, 1.4, M_PI / 2, 0),  // too deep: its length is seen
      box(10, 0, 1.8, 0.3, 1.4, M_PI / 2, 0),  // nearer than end_on_min_range_m
      det(30, 0, 0),                           // no box centre
  };
  for (Detection d : untouched) {
    const Detection before = d;
    EXPECT_FALSE(complete_end_on(c, sensor, d)) << before.length << " x " << before.width;
    EXPECT_EQ(d.length, before.length);
  }
  TrackerConfig off;
  off.end_on.length_m = 0;
  Detection d = box(40, 0, 1.8, 0.3, 1.4, M_PI / 2, 0);
  EXPECT_FALSE(complete_end_on(off, sensor, d));
}

TEST(CompleteEndOn, ALowBumperFarAwayIsCompletedToo) {
  // Beyond 40 m a car may show only its bumper (0.3 m tall) or one ring on its roof (0 m).
  const TrackerConfig c;
  for (const double height : {0.3, 0.0}) {
    Detection d = box(45, 0, 1.7, 0.1, height, M_PI / 2, 0);
    ASSERT_TRUE(complete_end_on(c, Eigen::Vector2f(0, 0), d)) << height;
    EXPECT_NEAR(d.box_center.x(), 45 + (4.5 - 0.1) / 2, 1e-4);
  }
}

TEST(Tracker, AnEndOnFaceOfATruckSeenWholeBeforeIsMeasuredAtTheTrucksCentre) {
  // A 9 m truck (2.4 m tall) drives away along +x at 6 m/s from a sensor at the origin: seen
  // whole for 10 scans, then only its rear face (2.4 m across, 0.3 m deep), which
  // complete_end_on makes a 4.5 m car box, 2.25 m short of the truck's centre. The track
  // remembers the 9 m and measures the face as the rear of a 9 m box: it stays on the truck's
  // centre. With the memory off it falls 2.25 m behind it.
  const auto run = [](double memory_m, TrackerCounters& counters) {
    TrackerConfig c;
    c.body.memory_length_m = memory_m;
    Tracker tracker(c);
    TrackerOutput out(c.max_tracks);
    const Eigen::Vector2f sensor(0, 0);
    double worst = 0;
    for (int k = 0; k < 25; ++k) {
      const double centre = 25 + 0.6 * k;
      Detection d = k < 10 ? box(centre, 0, 9.0, 2.4, 2.4, 0, 0)
                           : box(centre - 4.5 + 0.15, 0, 2.4, 0.3, 2.4, M_PI / 2, 0);
      if (k >= 10) {
        EXPECT_TRUE(complete_end_on(c, sensor, d));
      }
      tracker.update(k * kScanNs, std::vector<Detection>{d}, out);
      EXPECT_EQ(out.tracks.size(), 1u) << "scan " << k;
      if (k >= 15 && !out.tracks.empty())
        worst = std::max(worst, std::abs(out.tracks[0].position.x() - centre));
    }
    counters = tracker.counters();
    return worst;
  };
  TrackerCounters counters;
  EXPECT_LT(run(TrackerConfig{}.body.memory_length_m, counters), 0.3);
  EXPECT_EQ(counters.anchored_detections, 15u);
  EXPECT_GT(run(0.0, counters), 2.0);
  EXPECT_EQ(counters.anchored_detections, 0u);
}

// A 9 m truck (2.4 m tall) driving away along +x at 6 m/s, centre at 25 + 0.6 k: seen whole for
// 10 scans, then as `pieces(centre)` for 15. Returns the largest distance of the first track
// (its id kept) from the truck's centre over the last 10 scans, infinity once that id is gone;
// `tracks` is the number of tracks at the end.
template <class Pieces>
double truck_then_pieces(const TrackerConfig& c, Pieces pieces, std::size_t& tracks) {
  Tracker tracker(c);
  TrackerOutput out(c.max_tracks);
  std::uint64_t id = 0;
  double worst = 0;
  for (int k = 0; k < 25; ++k) {
    const double centre = 25 + 0.6 * k;
    const std::vector<Detection> d =
        k < 10 ? std::vector<Detection>{box(centre, 0, 9.0, 2.4, 2.4, 0, 0)} : pieces(centre);
    tracker.update(k * kScanNs, d, out);
    if (k == 9 && !out.tracks.empty()) id = out.tracks[0].id;
    if (k < 15) continue;
    const auto it = std::find_if(out.tracks.begin(), out.tracks.end(),
                                 [&](const Track& t) { return t.id == id; });
    worst = it == out.tracks.end()
                ? std::numeric_limits<double>::infinity()
                : std::max(worst, static_cast<double>(std::abs(it->position.x() - centre)));
  }
  tracks = out.tracks.size();
  return worst;
}

TEST(Tracker, ATrucksCargoBoxSeenApartFromItsCabIsGatedAsAPieceOfTheTruck) {
  // The truck seen as its 6.4 m cargo box (the rear) and the near side of its 2.0 m cab (the
  // front, 1.1 m across, its box askew by 0.19 rad), 0.6 m apart: the cargo box's centre is 1.3
  // m behind the truck's, outside the gate of a track that has been measured well, and the
  // cab's 3.5 m ahead; their union is too wide for one object (as urban seed 5150's 9.3 m truck
  // driving away). Gated as pieces of the known 9 m body, the box is associated with the truck's
  // track and the cab joins it inside the body: the track stays on the truck. Without
  // (body_gating false) neither piece is in the gate and the track ends up on one of them.
  const auto pieces = [](double centre) {
    return std::vector<Detection>{box(centre - 4.5 + 3.2, 0, 6.4, 2.4, 2.4, 0, 1),
                                  box(centre + 4.5 - 1.0, -0.65, 2.0, 1.1, 2.3, 0.19, 2)};
  };
  TrackerConfig c;
  std::size_t tracks = 0;
  EXPECT_LT(truck_then_pieces(c, pieces, tracks), 0.3);
  EXPECT_EQ(tracks, 1u);
  c.body.gating = false;
  EXPECT_GT(truck_then_pieces(c, pieces, tracks), 1.0);
}

TEST(Tracker, APieceOfAKnownBodyMeasuresItsCentreWithTheSpreadOfWhereItLies) {
  // An 8 m truck (2.4 m wide and tall) driving along +x at 8 m/s, seen whole for 10 scans and
  // then, in every other scan, only as the side wall of its cargo box: a 5.5 m x 0.1 m strip 1.2
  // m behind and 1.15 m beside the truck's centre (as urban seed 5150's truck at 40-55 m). Where
  // in the body the strip lies is unknown, so it measures the truck's centre with that
  // uncertainty: the track stays within 0.5 m of the centre, and every whole view finds it in
  // its gate (one track, spawned once). Measured as if it were the centre (as before), the strip
  // pulled the track about 1 m aside.
  TrackerConfig c;
  Tracker tracker(c);
  TrackerOutput out(c.max_tracks);
  std::uint64_t id = 0;
  double worst = 0;
  for (int k = 0; k < 40; ++k) {
    const double centre = 20 + 0.8 * k;
    const Detection d = k < 10 || k % 2 == 0 ? box(centre, 0, 8.0, 2.4, 2.4, 0, 0)
                                             : box(centre - 1.2, 1.15, 5.5, 0.1, 2.4, 0, 1);
    tracker.update(k * kScanNs, std::vector<Detection>{d}, out);
    ASSERT_EQ(out.tracks.size(), 1u) << "scan " << k;
    if (k == 0) id = out.tracks[0].id;
    EXPECT_EQ(out.tracks[0].id, id);
    if (k < 10) continue;
    const Eigen::Vector3f& p = out.tracks[0].position;
    worst = std::max(worst, std::hypot(p.x() - centre, static_cast<double>(p.y())));
  }
  EXPECT_LT(worst, 0.5);  // 0.27 m
  EXPECT_EQ(tracker.counters().spawned, 1u);
}

TEST(Tracker, PiecesInsideATrucksKnownBodyJoinItAndAPersonBesideItDoesNot) {
  // The truck seen as its 6.4 m cargo box, a thin tall piece of its side 1.5 m ahead of the box
  // and its cab's corner (0.8 x 0.5 m, 2.3 m tall): the two small pieces are person-like, so
  // only the known body (absorb_known_margin_m) joins them to the truck's measurement, which
  // then spans the truck. A person walking 1.5 m beside the truck's side keeps a track of its
  // own. Off (absorb_known_margin_m < 0), the pieces make tracks of their own.
  const auto pieces = [](double centre) {
    return std::vector<Detection>{box(centre - 4.5 + 3.2, 0, 6.4, 2.4, 2.4, 0, 1),
                                  box(centre + 1.8, -1.15, 0.4, 0.05, 2.3, 0, 2),
                                  box(centre + 4.1, -0.9, 0.8, 0.5, 2.3, 0, 3),
                                  box(centre, -2.7, 0.5, 0.5, 1.7, 0, 4)};
  };
  TrackerConfig c;
  std::size_t tracks = 0;
  EXPECT_LT(truck_then_pieces(c, pieces, tracks), 0.3);
  EXPECT_EQ(tracks, 2u);  // the truck and the person
  c.fragments.known_margin_m = -1;
  (void)truck_then_pieces(c, pieces, tracks);
  EXPECT_EQ(tracks, 4u);
}

// A 9 m truck (2.4 m wide and tall) driving away along +x at 6 m/s, `lateral` m to the left
// of the sensor: seen whole for 10 scans (heading 0), then for 15 as its rear face end-on and a
// thin tall strip of its near side 3 m ahead of its centre (person-like: it joins only a known
// body it lies in). Expects the first track within 0.3 m of the truck's centre throughout, one
// track at the end, every face anchored and every strip joined.
void expect_face_and_strip_on_the_truck(double lateral) {
  TrackerConfig c;
  Tracker tracker(c);
  TrackerOutput out(c.max_tracks);
  double worst = 0;
  for (int k = 0; k < 25; ++k) {
    const double centre = 30 + 0.6 * k;
    std::vector<Detection> d;
    if (k < 10) {
      d.push_back(box(centre, lateral, 9.0, 2.4, 2.4, 0, 0));
    } else {
      Detection face = box(centre - 4.5 + 0.05, lateral, 2.4, 0.1, 2.4, M_PI / 2, 0);
      ASSERT_TRUE(complete_end_on(c, Eigen::Vector2f(0, 0), face));
      d.push_back(face);
      d.push_back(box(centre + 3.0, lateral - 1.15, 0.4, 0.05, 2.3, 0, 1));
    }
    tracker.update(k * kScanNs, d, out);
    ASSERT_FALSE(out.tracks.empty());
    const Eigen::Vector3f& p = out.tracks[0].position;
    worst = std::max(worst, std::hypot(p.x() - centre, p.y() - lateral));
  }
  EXPECT_LT(worst, 0.3);
  EXPECT_EQ(out.tracks.size(), 1u);
  EXPECT_EQ(tracker.counters().anchored_detections, 15u);
  EXPECT_EQ(tracker.counters().absorbed_detections, 15u);
}

TEST(Tracker, ATrucksEndOnFaceIsItsBodyBeforeItsSidePiecesJoinIt) {
  // Straight ahead (lateral 1 m): the strip lies inside the known body and joins the face's
  // measurement, which is the whole body (its face kept) before the strip joins it. Before,
  // the union of the face's 4.5 m car-sized completion and the strip was measured as it was,
  // no longer end-on: up to 0.8 m from the truck's centre.
  expect_face_and_strip_on_the_truck(1.0);
}

TEST(Tracker, AnOffAxisTrucksFaceIsMeasuredAlongItsBodysHeading) {
  // 10 m to the left, the end-on completion turns the face's box along the sensor's ray, 16-22
  // degrees off the truck's heading. From the face the body extends along the heading of the
  // truck's last whole view: the track stays on the truck and the strip joins it. Along the
  // ray (as before) the body's centre was 1.4 m beside the truck's, outside the gate: 2.8 m
  // off and two tracks.
  expect_face_and_strip_on_the_truck(10.0);
}

// An 8 m truck (2.4 m wide and tall) driving along +x at 8 m/s, 12 m to the left of the
// sensor, seen whole for 10 scans; then for 20 only its front 5 m (its rear hidden behind a car
// 6 m to the left of the sensor, when `occluder`). Returns the largest
// distance of the first track from the truck's centre over the last 10 scans; `sensor`: whether
// the tracker is told where the sensor is.
double truck_with_hidden_rear(bool occluder, bool sensor) {
  TrackerConfig c;
  Tracker tracker(c);
  TrackerOutput out(c.max_tracks);
  const Eigen::Vector2f origin(0, 0);
  std::uint64_t id = 0;
  double worst = 0;
  for (int k = 0; k < 30; ++k) {
    const double centre = -10 + 0.8 * k;
    std::vector<Detection> d;
    if (k < 10) {
      d.push_back(box(centre, 12, 8.0, 2.4, 2.4, 0, 0));
    } else {
      d.push_back(box(centre + 1.5, 12, 5.0, 2.4, 2.4, 0, 0));  // the front 5 m
      // Where the lines of sight to the truck's rear cross y = 6, not those to its front.
      if (occluder) d.push_back(box(0.5 * (centre - 3), 6, 4.0, 1.8, 1.5, 0, 1));
    }
    tracker.update(k * kScanNs, d, out, sensor ? &origin : nullptr);
    if (k == 0) id = out.tracks[0].id;
    if (k < 20) continue;
    const auto it = std::find_if(out.tracks.begin(), out.tracks.end(),
                                 [&](const Track& t) { return t.id == id; });
    if (it == out.tracks.end()) return std::numeric_limits<double>::infinity();
    worst = std::max(worst, std::hypot(it->position.x() - centre, it->position.y() - 12.0));
  }
  return worst;
}

TEST(Tracker, APieceWithOneEndHiddenIsAnchoredAtItsVisibleEnd) {
  // The rear hidden behind the car: the front end, in view, is the truck's, and the track stays
  // on the truck. Without knowing the sensor (nothing is known hidden) the piece measures the
  // body's centre loosely at its own centre, and the track drifts to the piece's centre, 1.5 m
  // ahead. With the sensor but no car, both ends are in view: not anchored either.
  EXPECT_LT(truck_with_hidden_rear(true, true), 0.3);
  EXPECT_GT(truck_with_hidden_rear(true, false), 1.0);
  EXPECT_GT(truck_with_hidden_rear(false, true), 1.0);
}

TEST(Tracker, ACarsFaceIsNotMeasuredWithAnyMemory) {
  // A 4.6 m car seen whole, then end-on: its memory (4.6 m, and not tall) is never used.
  TrackerConfig c;
  Tracker tracker(c);
  TrackerOutput out(c.max_tracks);
  for (int k = 0; k < 20; ++k) {
    const double centre = 25 + 0.6 * k;
    Detection d = k < 10 ? box(centre, 0, 4.6, 1.8, 1.5, 0, 0)
                         : box(centre - 2.3 + 0.15, 0, 1.8, 0.3, 1.5, M_PI / 2, 0);
    if (k >= 10) {
      EXPECT_TRUE(complete_end_on(c, Eigen::Vector2f(0, 0), d));
    }
    tracker.update(k * kScanNs, std::vector<Detection>{d}, out);
  }
  EXPECT_EQ(tracker.counters().anchored_detections, 0u);
}

TEST(Tracker, NewTrackInsideAnOlderTracksBoxMergesIntoItAndTheOldIdLivesOn) {
  // A car tracked for 10 scans is lost for 3 and comes back 1.2 m from its prediction, outside
  // the (narrowed) gate: the detection spawns a track, which lies inside the old track's box and
  // is merged into the old id at once. With the merge off, the return keeps a track of its own.
  const auto run = [](double overlap_margin_m, TrackerOutput& out) {
    TrackerConfig c;
    c.gate.distance_m = 1.0;
    c.fragments.overlap_margin_m = overlap_margin_m;
    Tracker tracker(c);
    for (int k = 0; k < 10; ++k)
      tracker.update(k * kScanNs, std::vector<Detection>{box(30, 5, 4.5, 1.8, 1.5, 0, 0)}, out);
    const std::uint64_t id = out.tracks[0].id;
    for (int k = 10; k < 13; ++k) tracker.update(k * kScanNs, std::vector<Detection>{}, out);
    tracker.update(13 * kScanNs, std::vector<Detection>{box(31.2, 5, 4.5, 1.8, 1.5, 0, 7)}, out);
    return std::pair{id, tracker.counters().deleted_overlap};
  };
  TrackerOutput out(TrackerConfig{}.max_tracks);
  const auto [id, merged] = run(TrackerConfig{}.fragments.overlap_margin_m, out);
  ASSERT_EQ(out.tracks.size(), 1u);
  EXPECT_EQ(out.tracks[0].id, id);
  EXPECT_EQ(out.tracks[0].state, TrackState::kConfirmed);
  EXPECT_EQ(out.tracks[0].segment, 7);
  EXPECT_GT(out.tracks[0].position.x(), 30.6f);  // corrected towards the new measurement
  EXPECT_EQ(merged, 1u);
  (void)run(-1, out);
  EXPECT_EQ(out.tracks.size(), 2u);
}

TEST(Tracker, ABicyclistPassingAParkedCarKeepsItsOwnTrack) {
  // Bicycle lane 1.6 m from parked cars (the simulator's street): the bicyclist is narrow and
  // tall, so it is neither absorbed into the car nor merged with the car's track.
  TrackerConfig c;
  Tracker tracker(c);
  TrackerOutput out(c.max_tracks);
  for (int k = 0; k < 30; ++k) {
    const double x = 10 + 0.5 * k;  // 5 m/s past a car at x = 20
    tracker.update(
        k * kScanNs,
        std::vector<Detection>{box(20, 8.2, 4.6, 2.0, 1.5, 0, 0), box(x, 6.6, 1.7, 0.5, 1.6, 0, 1)},
        out);
    ASSERT_TRUE(by_segment(out, 1) != nullptr) << "scan " << k;
  }
  EXPECT_EQ(out.tracks.size(), 2u);
  EXPECT_EQ(tracker.counters().spawned, 2u);
}

TEST(Tracker, APersonTakesItsLegsButNotItsNeighbour) {
  TrackerConfig c;
  Tracker tracker(c);
  TrackerOutput out(c.max_tracks);
  for (int k = 0; k < 6; ++k) {
    tracker.update(
        k * kScanNs,
        std::vector<Detection>{box(20, 5, 0.5, 0.35, 1.5, 0, 0),     // upper body
                               box(20.1, 5, 0.6, 0.05, 0.6, 0, 1),   // its legs, 0.1 m off
                               box(21.0, 5, 0.5, 0.35, 1.6, 0, 2),   // the next walker
                               box(22.0, 5, 0.6, 0.05, 0.6, 0, 3)},  // legs 0.45 m from them
        out);
  }
  EXPECT_EQ(out.tracks.size(), 3u);  // walker 1 (with legs), walker 2, the far legs
  EXPECT_TRUE(by_segment(out, 0) != nullptr && by_segment(out, 2) != nullptr);
  EXPECT_TRUE(by_segment(out, 1) == nullptr);
}

TEST(Tracker, NoHeapAllocationPerScanAfterWarmUp) {
  Tracker tracker(TrackerConfig{});
  TrackerOutput out(tracker.config().max_tracks);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> where(-60.0, 60.0);
  std::vector<Detection> dets;
  dets.reserve(200);
  auto scan = [&](int k) {
    dets.clear();
    for (std::uint32_t i = 0; i < 60; ++i)
      dets.push_back(det(-50.0 + 2.0 * i + 0.5 * k * 0.1, 3.0 * (i % 7), i));
    for (std::uint32_t i = 0; i < 40; ++i) dets.push_back(det(where(rng), where(rng), 60 + i));
    tracker.update(k * kScanNs, dets, out);
  };
  for (int k = 0; k < 20; ++k) scan(k);
  rt::testing::AllocationCounter counter;
  for (int k = 20; k < 120; ++k) scan(k);
  counter.stop();
  EXPECT_EQ(counter.allocations(), 0u) << counter.bytes() << " bytes";
  EXPECT_GE(out.tracks.size(), 60u);
}

TEST(Tracker, RejectsInvalidConfig) {
  TrackerConfig c;
  c.max_tracks = 0;
  EXPECT_THROW(Tracker{c}, std::invalid_argument);
  // Checked before anything is allocated: 4e9 tracks would be 16 GB of free list alone.
  c.max_tracks = 4'000'000'000;
  EXPECT_THROW(Tracker{c}, std::invalid_argument);
  c.max_tracks = 100'000;  // each within its range, the assignment's matrix 80 GB
  c.max_detections = 100'000;
  EXPECT_THROW(Tracker{c}, std::invalid_argument);
  c.max_detections = 41;  // 4.1 million pairs
  EXPECT_NO_THROW(Tracker{c});
  c = TrackerConfig{};
  c = TrackerConfig{};
  c.box_smoothing = 0;
  EXPECT_THROW(Tracker{c}, std::invalid_argument);
  c = TrackerConfig{};
  c.object.max_width_m = 7;  // wider than absorb_max_length_m
  EXPECT_THROW(Tracker{c}, std::invalid_argument);
  c = TrackerConfig{};
  c.end_on.min_width_m = 3;  // above end_on_max_width_m
  EXPECT_THROW(Tracker{c}, std::invalid_argument);
  c = TrackerConfig{};
  c.person.strip_width_m = -0.1;
  EXPECT_THROW(Tracker{c}, std::invalid_argument);
  c = TrackerConfig{};
  c.body.memory_length_m = -1;
  EXPECT_THROW(Tracker{c}, std::invalid_argument);
  c = TrackerConfig{};
  c.fragments.known_margin_m = 6;
  EXPECT_THROW(Tracker{c}, std::invalid_argument);
  c.fragments.known_margin_m = -1;  // off
  EXPECT_NO_THROW(Tracker{c});
}

}  // namespace
}  // namespace stac::tracking
