// End to end on synthetic labelled tracks: train the segment and holistic classifiers and the
// augmented filter (held-out split), then classify unseen tracks through the per-scan calls.
#include "perception/learning/track_training.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "rt/testing/alloc_counter.hpp"
#include "synthetic.hpp"
#include "synthetic_tracks.hpp"

namespace stac::learning {
namespace {

using classification::ExpectedLayouts;
using classification::kDefaultClassCount;
using classification::LogOdds;
using classification::naive_dbf;
using classification::predict;
using classification::TrackClassifierModel;
using classification::TrackEvidence;
using classification::testing::layouts;
using classification::testing::synthetic_tracks;

TrackTrainingConfig config() {
  TrackTrainingConfig c;
  c.segment.rounds = 200;
  c.holistic.rounds = 100;
  return c;
}

struct Accuracy {
  double adbf = 0, segment_only = 0, holistic_only = 0;  // segment only: the naive filter on L0
};

Accuracy evaluate(const TrackClassifierModel& model, const std::vector<TrackExample>& tracks) {
  Accuracy a;
  for (const TrackExample& t : tracks) {
    TrackEvidence e;
    LogOdds h{}, track{}, hh{};
    for (std::size_t i = 0; i < t.segments.size(); i += 6)
      EXPECT_TRUE(add_segment(model, std::span(t.segments).subspan(i, 6), e, h));
    EXPECT_TRUE(track_log_odds(model, e, t.holistic, track));
    (void)model.holistic.classify(t.holistic, hh);
    a.adbf += predict(track, kDefaultClassCount) == t.label;
    a.segment_only +=
        predict(naive_dbf(e, model.segment.model().prior), kDefaultClassCount) == t.label;
    a.holistic_only += predict(hh, kDefaultClassCount) == t.label;
  }
  const double n = static_cast<double>(tracks.size());
  return {a.adbf / n, a.segment_only / n, a.holistic_only / n};
}

TEST(TrackTraining, TrainedModelClassifiesUnseenTracksBetterThanEitherPartAlone) {
  const auto train = synthetic_tracks(1500, 1), test = synthetic_tracks(1500, 2);
  auto model =
      train_track_classifier(train, classification::default_class_names(), layouts(), config());
  ASSERT_TRUE(model.has_value()) << model.error().message;
  const Accuracy a = evaluate(*model, test);
  RecordProperty("adbf", std::to_string(a.adbf));
  RecordProperty("segment_only", std::to_string(a.segment_only));
  RecordProperty("holistic_only", std::to_string(a.holistic_only));
  // Measured: ADBF 0.90, segment evidence alone 0.83, holistic alone 0.66.
  EXPECT_GT(a.adbf, a.segment_only);
  EXPECT_GT(a.adbf, a.holistic_only);
  EXPECT_GT(a.adbf, 0.7);  // chance: 0.25
}

TEST(TrackTraining, SameSeedsSameModelBytes) {
  const auto train = synthetic_tracks(300, 3);
  auto a =
      train_track_classifier(train, classification::default_class_names(), layouts(), config());
  auto b =
      train_track_classifier(train, classification::default_class_names(), layouts(), config());
  ASSERT_TRUE(a.has_value() && b.has_value());
  EXPECT_EQ(serialize(*a), serialize(*b));
}

TEST(TrackTraining, ProgressRisesToOneAndDoesNotChangeTheModel) {
  const auto train = synthetic_tracks(300, 3);
  TrackTrainingConfig c = config();
  std::vector<double> seen;
  c.progress = [&seen](double f) { seen.push_back(f); };
  auto a = train_track_classifier(train, classification::default_class_names(), layouts(), c);
  auto b =
      train_track_classifier(train, classification::default_class_names(), layouts(), config());
  ASSERT_TRUE(a.has_value() && b.has_value());
  EXPECT_EQ(serialize(*a), serialize(*b));
  ASSERT_GE(seen.size(), 2u);
  EXPECT_TRUE(std::is_sorted(seen.begin(), seen.end()));
  EXPECT_GT(seen.front(), 0.0);
  EXPECT_DOUBLE_EQ(seen.back(), 1.0);
}

TEST(TrackTraining, AnEnsembleIsTheMeanOfItsMembersSeeds) {
  const auto train = synthetic_tracks(300, 3);
  TrackTrainingConfig c = config();
  c.ensemble = 3;
  auto ensemble =
      train_track_classifier(train, classification::default_class_names(), layouts(), c);
  ASSERT_TRUE(ensemble.has_value()) << ensemble.error().message;
  auto single =
      train_track_classifier(train, classification::default_class_names(), layouts(), config());
  ASSERT_TRUE(single.has_value());
  // Same tables' size and layout (same classification cost), other responses.
  EXPECT_EQ(ensemble->segment.model().table.size(), single->segment.model().table.size());
  EXPECT_NE(ensemble->segment.model().table, single->segment.model().table);
  // Member k has seeds segment.seed + 2k and holistic.seed + 2k; their mean is the model's table.
  std::vector<GridClassifier> members;
  for (std::uint64_t k = 0; k < 3; ++k) {
    TrackTrainingConfig m = config();
    m.segment.seed += 2 * k;
    m.holistic.seed += 2 * k;
    auto one = train_track_classifier(train, classification::default_class_names(), layouts(), m);
    ASSERT_TRUE(one.has_value());
    members.push_back(one->segment);
  }
  auto mean = average_classifiers(members);
  ASSERT_TRUE(mean.has_value());
  EXPECT_EQ(mean->model().table, ensemble->segment.model().table);
  c.ensemble = 0;
  EXPECT_FALSE(train_track_classifier(train, classification::default_class_names(), layouts(), c)
                   .has_value());
}

TEST(TrackTraining, RefusesWrongSizesAndEmptySplits) {
  auto tracks = synthetic_tracks(50, 4);
  tracks[7].holistic.push_back(1.0f);
  auto r =
      train_track_classifier(tracks, classification::default_class_names(), layouts(), config());
  ASSERT_FALSE(r.has_value());
  EXPECT_NE(r.error().message.find("track 7"), std::string::npos) << r.error().message;
  tracks = synthetic_tracks(1, 5);
  EXPECT_FALSE(
      train_track_classifier(tracks, classification::default_class_names(), layouts(), config())
          .has_value());
}

TEST(TrackTraining, PerScanCallsAllocateNothing) {
  auto model = train_track_classifier(synthetic_tracks(300, 6),
                                      classification::default_class_names(), layouts(), config());
  ASSERT_TRUE(model.has_value());
  const auto tracks = synthetic_tracks(20, 7);
  TrackEvidence e;
  LogOdds h{}, track{};
  (void)add_segment(*model, std::span(tracks[0].segments).first(6), e, h);  // warm-up
  rt::testing::AllocationCounter counter;
  for (const TrackExample& t : tracks) {
    for (std::size_t i = 0; i < t.segments.size(); i += 6)
      (void)add_segment(*model, std::span(t.segments).subspan(i, 6), e, h);
    (void)track_log_odds(*model, e, t.holistic, track);
  }
  counter.stop();
  EXPECT_EQ(counter.allocations(), 0u);
}

}  // namespace
}  // namespace stac::learning
