// The per-scan classification stage: one class per reported track, evidence kept per pool slot
// and forgotten when the slot holds a new track, the holistic descriptor's accumulated part
// (the first segment's, then the cloud described after every holistic_every segments), the same
// log odds as the model's own functions, the steps stac run takes, no allocation.
#include "perception/classification/track_classifier.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "rt/testing/alloc_counter.hpp"
#include "synthetic.hpp"

namespace stac::classification {
namespace {

// Two objects' points (x, y, z, intensity; stride 16): a car-sized box of `car_points` and a
// thin pole, both in front of the sensor; one segment each.
struct Scene {
  std::vector<float> xyzi;
  segmentation::Segments segments{8, 4096};

  explicit Scene(int frame) {
    const auto add_object = [&](float x0, float y0, float lx, float ly, float lz, int n) {
      segmentation::Segment* s = segments.segments.append();
      s->first = static_cast<std::uint32_t>(segments.point_indices.size());
      for (int i = 0; i < n; ++i) {
        const float u = static_cast<float>((i * 37 + frame * 11) % 101) / 101.0f;
        const float v = static_cast<float>((i * 53 + frame * 7) % 97) / 97.0f;
        const float w = static_cast<float>((i * 29) % 89) / 89.0f;
        const auto index = static_cast<std::uint32_t>(xyzi.size() / 4);
        xyzi.insert(xyzi.end(), {x0 + lx * u, y0 + ly * v, lz * w - 1.7f, 40.0f + 100.0f * w});
        (void)segments.point_indices.push_back(index);
      }
      s->count = static_cast<std::uint32_t>(n);
    };
    add_object(10.0f, -1.0f, 4.5f, 1.8f, 1.5f, 300 + 10 * frame);
    add_object(6.0f, 4.0f, 0.2f, 0.2f, 3.0f, 60);
  }
};

tracking::Track track(std::uint64_t id, std::uint32_t slot, std::int32_t segment) {
  tracking::Track t;
  t.id = id;
  t.slot = slot;
  t.segment = segment;
  t.length = 4.5f;
  t.width = 1.8f;
  t.height = 1.5f;
  return t;
}

TrackClassifierModel full_size_model() {
  const auto seg = testing::noisy(200, descriptors::kDimensions, 0.1, 3);
  const auto hol = testing::noisy(200, kHolisticDimensions, 0.1, 4);
  return {testing::trained(seg, segment_layout(), {.rounds = 30, .seed = 3}),
          testing::trained(hol, holistic_layout(), {.rounds = 30, .seed = 4}),
          {{0.5f, 1.0f, 2.0f}, {1.0f, 0.5f, 1.5f}, {2.0f, 1.0f, 0.5f}}};
}

TrackClassifierConfig small_config() {
  TrackClassifierConfig c;
  c.max_tracks = 4;
  c.accumulated_points = 1024;
  c.holistic_every = 3;
  return c;
}

class Recorder : public TrackClassifier::Observer {
 public:
  void on_update(const tracking::Track& t, std::span<const float> segment,
                 std::span<const float> holistic) noexcept override {
    ids.push_back(t.id);
    segments.emplace_back(segment.begin(), segment.end());
    holistics.emplace_back(holistic.begin(), holistic.end());
  }
  std::vector<std::uint64_t> ids;
  std::vector<std::vector<float>> segments, holistics;
};

// A stage without a model (descriptors only) and what it saw.
struct Observed {
  TrackClassifier stage{small_config(), nullptr};
  Recorder seen;
  tracking::TrackerOutput tracked{4};
  rt::FixedVector<TrackClass> out{4};
  Observed() { stage.set_observer(&seen); }
};

TEST(TrackClassifier, OneClassPerTrackAndTheModelsOwnLogOdds) {
  auto model = std::make_shared<const TrackClassifierModel>(full_size_model());
  TrackClassifier stage(small_config(), model);
  Recorder seen;
  stage.set_observer(&seen);
  tracking::TrackerOutput tracked(4);
  rt::FixedVector<TrackClass> out(4);
  TrackEvidence evidence;  // the model's own functions on the same descriptors, for track 1
  for (int frame = 0; frame < 7; ++frame) {
    const Scene scene(frame);
    tracked.tracks.clear();
    ASSERT_TRUE(tracked.tracks.push_back(track(1, 2, 0)));
    // Track 2 (the pole) coasts in frames 3 and 4: no segment.
    ASSERT_TRUE(tracked.tracks.push_back(track(2, 0, frame == 3 || frame == 4 ? -1 : 1)));
    const std::size_t before = seen.ids.size();
    stage.classify(scene.xyzi.data(), 16, scene.segments, tracked, out);
    ASSERT_EQ(out.size(), 2u);
    EXPECT_EQ(out[0].id, 1u);
    EXPECT_EQ(out[1].id, 2u);
    EXPECT_TRUE(out[0].classified);
    EXPECT_EQ(out[0].segments, static_cast<std::uint32_t>(frame + 1));
    std::size_t mine = before;  // track 1's update (the one with fewer segments comes first)
    while (mine < seen.ids.size() && seen.ids[mine] != 1u) ++mine;
    ASSERT_LT(mine, seen.ids.size());
    LogOdds hs{}, expected{};
    ASSERT_TRUE(add_segment(*model, seen.segments[mine], evidence, hs));
    ASSERT_TRUE(track_log_odds(*model, evidence, seen.holistics[mine], expected));
    // The holistic sum is kept in two parts (motion, accumulated cloud): float rounding only.
    for (std::size_t k = 0; k < kDefaultClassCount; ++k)
      EXPECT_NEAR(out[0].log_odds[k], expected[k], 1e-4f * (1.0f + std::fabs(expected[k])));
    EXPECT_EQ(out[0].label, predict(expected, kDefaultClassCount));
    if (frame == 3 || frame == 4) {  // coasting: no update, the class of frame 2 is kept
      EXPECT_EQ(seen.ids.size(), before + 1);
      EXPECT_EQ(out[1].segments, 3u);
    }
    EXPECT_EQ(out[1].age, frame == 3 ? 1u : frame == 4 ? 2u : 0u);  // scans since its segment
  }
  EXPECT_EQ(stage.counters().segments_described, 12u);
  EXPECT_EQ(stage.counters().slot_mismatch, 0u);
}

TEST(TrackClassifier, ASwappedInModelClassifiesFromTheNextScanWithoutAllocating) {
  auto a = std::make_shared<const TrackClassifierModel>(full_size_model());
  TrackClassifierModel other = full_size_model();
  other.adbf = {{2.0f, 0.5f, 1.0f}, {0.5f, 2.0f, 1.0f}, {1.0f, 1.0f, 3.0f}};  // other log odds
  auto b = std::make_shared<const TrackClassifierModel>(other);
  TrackClassifier stage(small_config(), a);
  Recorder seen;
  stage.set_observer(&seen);
  tracking::TrackerOutput tracked(4);
  rt::FixedVector<TrackClass> out(4);
  for (int frame = 0; frame < 6; ++frame) {
    if (frame == 3) {
      EXPECT_EQ(stage.check_swap(*b), "");
      rt::testing::AllocationCounter counter;
      stage.set_model(b);
      counter.stop();
      EXPECT_EQ(counter.allocations(), 0u);
      EXPECT_EQ(stage.model(), b.get());
    }
    const Scene scene(frame);
    tracked.tracks.clear();
    ASSERT_TRUE(tracked.tracks.push_back(track(1, 2, 0)));
    const std::size_t before = seen.ids.size();
    stage.classify(scene.xyzi.data(), 16, scene.segments, tracked, out);
    ASSERT_EQ(seen.ids.size(), before + 1);
    if (frame < 3) continue;
    // From the swap on: the new model's log odds on the segments since the swap (the evidence
    // restarted) and the holistic descriptor as it is.
    TrackEvidence evidence;
    LogOdds hs{}, expected{};
    for (std::size_t i = seen.ids.size() - static_cast<std::size_t>(frame - 2); i < seen.ids.size();
         ++i)
      ASSERT_TRUE(add_segment(*b, seen.segments[i], evidence, hs));
    ASSERT_TRUE(track_log_odds(*b, evidence, seen.holistics.back(), expected));
    for (std::size_t k = 0; k < kDefaultClassCount; ++k)
      EXPECT_NEAR(out[0].log_odds[k], expected[k], 1e-4f * (1.0f + std::fabs(expected[k])))
          << "frame " << frame;
  }
  // Other classes, or no model to replace: refused with what is wrong.
  TrackClassifierModel five = full_size_model();
  five.classes = {"car", "pedestrian", "tree"};
  EXPECT_NE(stage.check_swap(five).find("classes"), std::string::npos) << stage.check_swap(five);
  const TrackClassifier without(small_config(), nullptr);
  EXPECT_NE(without.check_swap(*b), "");
}

TEST(TrackClassifier, TracksClassifiedTogetherGetTheClassesOfEachAlone) {
  // classify() walks the tables once for all of a scan's tracks; every slot must come out
  // bit-identical to updating the tracks one call each, also when a slot shows up twice in a
  // scan (frame 5: track 7 takes track 1's slot, which then comes back in frame 6).
  auto model = std::make_shared<const TrackClassifierModel>(full_size_model());
  TrackClassifier together(small_config(), model), alone(small_config(), model);
  tracking::TrackerOutput tracked(4), one(4);
  rt::FixedVector<TrackClass> out(4), out_alone(4);
  for (int frame = 0; frame < 8; ++frame) {
    const Scene scene(frame);
    tracked.tracks.clear();
    ASSERT_TRUE(tracked.tracks.push_back(track(1, 2, 0)));
    ASSERT_TRUE(tracked.tracks.push_back(track(2, 0, 1)));
    if (frame == 5) {
      ASSERT_TRUE(tracked.tracks.push_back(track(7, 2, 1)));
    }
    together.classify(scene.xyzi.data(), 16, scene.segments, tracked, out);
    for (const tracking::Track& t : tracked.tracks) {
      one.tracks.clear();
      ASSERT_TRUE(one.tracks.push_back(t));
      alone.classify(scene.xyzi.data(), 16, scene.segments, one, out_alone);
    }
    alone.report(tracked, out_alone);
    ASSERT_EQ(out.size(), out_alone.size());
    for (std::size_t i = 0; i < out.size(); ++i) {
      EXPECT_EQ(out[i].id, out_alone[i].id);
      EXPECT_EQ(out[i].classified, out_alone[i].classified) << frame << " " << i;
      EXPECT_EQ(out[i].label, out_alone[i].label);
      EXPECT_EQ(out[i].log_odds, out_alone[i].log_odds) << frame << " " << i;
      EXPECT_EQ(out[i].segments, out_alone[i].segments);
    }
    EXPECT_TRUE(out[1].classified);
    EXPECT_EQ(out[0].classified, frame != 5);  // frame 5: the slot holds track 7 at the end
  }
  // Frame 5's track 1 is not classified together (the later track 7 holds its slot): one
  // segment less described, and the cloud it would have completed (6 segments) not described.
  EXPECT_EQ(together.counters().slot_mismatch, 1u);
  EXPECT_EQ(together.counters().segments_described + 1, alone.counters().segments_described);
  EXPECT_EQ(together.counters().holistic_described + 1, alone.counters().holistic_described);
}

TEST(TrackClassifier, AccumulatedPartIsTheFirstSegmentThenTheCloudDescribedAfterEveryN) {
  Observed o;
  auto& [stage, seen, tracked, out] = o;
  for (int frame = 0; frame < 8; ++frame) {
    const Scene scene(frame);
    tracked.tracks.clear();
    tracking::Track t = track(5, 1, 0);
    for (int k = 0; k <= frame; ++k)
      t.features.add_segment(Eigen::Vector3f(1.0f * static_cast<float>(k), 0, 0),
                             static_cast<std::int64_t>(k) * 100'000'000, 0.5);
    ASSERT_TRUE(tracked.tracks.push_back(t));
    stage.classify(scene.xyzi.data(), 16, scene.segments, tracked, out);
    ASSERT_EQ(out.size(), 1u);
    EXPECT_FALSE(out[0].classified);  // no model
  }
  ASSERT_EQ(seen.holistics.size(), 8u);
  const auto accumulated = [&](std::size_t i) {
    return std::vector<float>(seen.holistics[i].begin() + kHolisticMotionDimensions,
                              seen.holistics[i].end());
  };
  // The first segment's own descriptors, until the cloud of 3 segments is described (after
  // segments 3 and 6): it serves segments 4-6, the cloud of 6 segments 7 and 8.
  EXPECT_EQ(accumulated(0), seen.segments[0]);
  for (std::size_t i = 1; i < 8; ++i) {
    if (i == 3 || i == 6)
      EXPECT_NE(accumulated(i), accumulated(i - 1)) << i;
    else
      EXPECT_EQ(accumulated(i), accumulated(i - 1)) << i;
  }
  // The motion part is current every scan: segment count = frame + 1.
  for (std::size_t i = 0; i < 8; ++i) EXPECT_EQ(seen.holistics[i][5], static_cast<float>(i + 1));
  EXPECT_EQ(stage.counters().holistic_described, 2u);
  EXPECT_EQ(seen.segments[0].size(), descriptors::kDimensions);
}

TEST(TrackClassifier, ANewTrackInAReusedSlotStartsAfresh) {
  auto model = std::make_shared<const TrackClassifierModel>(full_size_model());
  TrackClassifier stage(small_config(), model);
  tracking::TrackerOutput tracked(4);
  rt::FixedVector<TrackClass> out(4);
  for (int frame = 0; frame < 4; ++frame) {
    const Scene scene(frame);
    tracked.tracks.clear();
    ASSERT_TRUE(tracked.tracks.push_back(track(7, 3, 0)));
    stage.classify(scene.xyzi.data(), 16, scene.segments, tracked, out);
  }
  EXPECT_EQ(out[0].segments, 4u);
  // Track 7 ended; track 9 takes slot 3 and is first seen without a segment (tentative coast).
  const Scene scene(4);
  tracked.tracks.clear();
  ASSERT_TRUE(tracked.tracks.push_back(track(9, 3, -1)));
  stage.classify(scene.xyzi.data(), 16, scene.segments, tracked, out);
  EXPECT_EQ(out[0].id, 9u);
  EXPECT_FALSE(out[0].classified);
  EXPECT_EQ(out[0].segments, 0u);
  tracked.tracks.clear();
  ASSERT_TRUE(tracked.tracks.push_back(track(9, 3, 1)));
  stage.classify(scene.xyzi.data(), 16, scene.segments, tracked, out);
  EXPECT_TRUE(out[0].classified);
  EXPECT_EQ(out[0].segments, 1u);
  // A slot beyond the pool is counted, reported unclassified, never read.
  tracked.tracks.clear();
  ASSERT_TRUE(tracked.tracks.push_back(track(11, 4, 0)));
  stage.classify(scene.xyzi.data(), 16, scene.segments, tracked, out);
  EXPECT_EQ(stage.counters().slot_mismatch, 1u);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].id, 11u);
  EXPECT_FALSE(out[0].classified);
}

TEST(TrackClassifier, ClassifyAllocatesNothing) {
  auto model = std::make_shared<const TrackClassifierModel>(full_size_model());
  TrackClassifier stage(small_config(), model);
  tracking::TrackerOutput tracked(4);
  rt::FixedVector<TrackClass> out(4);
  std::vector<Scene> scenes;
  for (int frame = 0; frame < 10; ++frame) scenes.emplace_back(frame);
  rt::testing::AllocationCounter counter;
  for (int frame = 0; frame < 10; ++frame) {
    tracked.tracks.clear();
    (void)tracked.tracks.push_back(track(1, 0, 0));
    (void)tracked.tracks.push_back(track(2, 1, 1));
    stage.classify(scenes[static_cast<std::size_t>(frame)].xyzi.data(), 16,
                   scenes[static_cast<std::size_t>(frame)].segments, tracked, out);
  }
  counter.stop();
  EXPECT_EQ(counter.allocations(), 0u) << counter.bytes() << " bytes";
  EXPECT_TRUE(out[0].classified);
  static_assert(noexcept(stage.classify(nullptr, 16, scenes[0].segments, tracked, out)));
}

// stac run's steps: begin() keeps what it needs (the scan's Segments change before finish()),
// update() takes the published tracks (not the tentative one) or, out of time, none and counts
// them late; report() then gives the tracks it took their classes of one call, the others the
// scan before's; after finish() every class is one call's.
TEST(TrackClassifier, StepsGiveTheClassesOfOneCallAndLeaveWhatTheLimitExcludesForFinish) {
  auto model = std::make_shared<const TrackClassifierModel>(full_size_model());
  TrackClassifier now(small_config(), model), steps(small_config(), model),
      timed(small_config(), model);
  tracking::TrackerOutput tracked(4);
  rt::FixedVector<TrackClass> immediate(4), out(4), previous(4);
  for (int frame = 0; frame < 6; ++frame) {
    Scene scene(frame);
    tracked.tracks.clear();
    tracking::Track confirmed = track(1, 0, 0);
    confirmed.state = tracking::TrackState::kConfirmed;
    (void)tracked.tracks.push_back(confirmed);
    (void)tracked.tracks.push_back(track(3, 2, 1));  // tentative
    now.classify(scene.xyzi.data(), 16, scene.segments, tracked, immediate);
    steps.begin(scene.segments, tracked);
    timed.begin(scene.segments, tracked);
    EXPECT_TRUE(steps.has_kept());
    const UpdateCount n = steps.update(scene.xyzi.data(), 16, {.tentative = false});
    EXPECT_EQ(n.classified, 1u);
    EXPECT_EQ(n.late, 0u);
    const UpdateCount m = timed.update(scene.xyzi.data(), 16, {.tentative = false, .until_ns = 0});
    EXPECT_EQ(m.classified, 0u);
    EXPECT_EQ(m.late, 1u);  // the confirmed track; the tentative one was not asked for
    steps.report(tracked, out);
    ASSERT_EQ(out.size(), 2u);
    EXPECT_EQ(out[0].log_odds, immediate[0].log_odds) << frame;
    EXPECT_EQ(out[0].segments, static_cast<std::uint32_t>(frame + 1));
    EXPECT_EQ(out[0].age, 0u);                         // this scan's segment is in it
    EXPECT_EQ(out[1].age, frame > 0 ? 1u : 0u);        // the scan before's
    EXPECT_EQ(out[1].classified, frame > 0) << frame;  // the tentative one: the scan before's
    if (frame > 0) {
      EXPECT_EQ(out[1].log_odds, previous[1].log_odds) << frame;
    }
    timed.report(tracked, out);
    for (std::size_t i = 0; i < 2; ++i) {
      EXPECT_EQ(out[i].classified, frame > 0) << frame;
      EXPECT_EQ(out[i].age, frame > 0 ? 1u : 0u) << frame;
      if (frame > 0) {
        EXPECT_EQ(out[i].log_odds, previous[i].log_odds) << frame;
      }
    }
    // The scan's own buffers change before finish(): begin() kept its own copy.
    std::fill(scene.segments.point_indices.data(),
              scene.segments.point_indices.data() + scene.segments.point_indices.size(), 0u);
    scene.segments.segments.clear();
    for (TrackClassifier* c : {&steps, &timed}) {
      c->finish(scene.xyzi.data(), 16);  // the points themselves are still there
      EXPECT_FALSE(c->has_kept());
      c->report(tracked, out);
      for (std::size_t i = 0; i < 2; ++i) {
        EXPECT_EQ(out[i].log_odds, immediate[i].log_odds) << frame << " " << i;
        EXPECT_EQ(out[i].segments, immediate[i].segments) << frame << " " << i;
        EXPECT_EQ(out[i].age, 0u);
      }
    }
    previous.clear();
    for (const TrackClass& c : immediate) (void)previous.push_back(c);
  }
  for (const TrackClassifier* c : {&steps, &timed}) {
    EXPECT_EQ(c->counters().kept_overflow, 0u);
    EXPECT_EQ(c->counters().segments_described, now.counters().segments_described);
    EXPECT_EQ(c->counters().holistic_described, now.counters().holistic_described);
  }
}

// update() takes the tracks with the fewest segments classified first (a new track's class
// matters most), in their order among equals: what a time limit leaves are the settled ones.
TEST(TrackClassifier, TracksWithFewerSegmentsAreClassifiedFirst) {
  Observed o;
  auto& [stage, seen, tracked, out] = o;
  for (int frame = 0; frame < 3; ++frame) {
    const Scene scene(frame);
    tracked.tracks.clear();
    (void)tracked.tracks.push_back(track(1, 0, 0));                  // from frame 0
    if (frame >= 1) (void)tracked.tracks.push_back(track(2, 1, 1));  // from frame 1
    if (frame == 2) (void)tracked.tracks.push_back(track(4, 3, 1));  // new in frame 2
    seen.ids.clear();
    stage.classify(scene.xyzi.data(), 16, scene.segments, tracked, out);
  }
  EXPECT_EQ(seen.ids, (std::vector<std::uint64_t>{4, 2, 1}));
}

TEST(TrackClassifier, AModelForOtherDescriptorsIsRefused) {
  const auto small = testing::noisy(100, 6, 0.1, 5);
  auto model = std::make_shared<const TrackClassifierModel>(TrackClassifierModel{
      testing::trained(small, testing::flat_layout(6), {.rounds = 5, .seed = 5}),
      testing::trained(small, testing::flat_layout(6), {.rounds = 5, .seed = 6}),
      {}});
  EXPECT_THROW(TrackClassifier(small_config(), model), std::invalid_argument);
}

TEST(TrackClassifier, BadConfigurationIsRefusedWithAMessage) {
  TrackClassifierConfig c = small_config();
  c.holistic_every = 0;
  EXPECT_NE(std::string(validate(c)), "");
  EXPECT_THROW(TrackClassifier(c, nullptr), std::invalid_argument);
  c = small_config();
  c.accumulated_points = 0;
  EXPECT_NE(std::string(validate(c)).find("accumulated_points"), std::string::npos);
  EXPECT_EQ(std::string(validate(small_config())), "");
  // Each within its range, together 8 GB of accumulated clouds: refused before allocating.
  c = small_config();
  c.max_tracks = 512;
  c.accumulated_points = 1'000'000;
  EXPECT_NE(std::string(validate(c)).find("max_tracks x accumulated_points"), std::string::npos);
  EXPECT_THROW(TrackClassifier(c, nullptr), std::invalid_argument);
}

}  // namespace
}  // namespace stac::classification
