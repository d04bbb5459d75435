// Discrete Bayes filters on hand-computed numbers, logistic regression recovering known
// coefficients, the fitted ADBF against the naive and normalized filters on tracks whose segment
// evidence is noisy and correlated, and allocation-free updates.
#include "perception/classification/track_filter.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "perception/learning/logistic.hpp"
#include "rt/testing/alloc_counter.hpp"
#include "synthetic.hpp"

namespace stac::classification {
namespace {

static_assert(noexcept(std::declval<TrackEvidence&>().add_segment(std::declval<const LogOdds&>(),
                                                                  std::declval<const LogOdds&>())));
static_assert(noexcept(augmented_dbf(std::declval<const TrackEvidence&>(),
                                     std::declval<const LogOdds&>(), std::declval<const LogOdds&>(),
                                     std::declval<const AdbfParams&>())));
static_assert(sizeof(TrackEvidence) <= 8 * (kMaxClasses + 1),
              "per-track filter state stays small and fixed");

// L0_S = (-1, -2, -3); H_S - L0_S = (2, 0, -1), (1, 1, 0), (3, -1, 1): sum (6, 0, 0), mean (2, 0,
// 0).
TrackEvidence three_segments() {
  const LogOdds prior{-1.0f, -2.0f, -3.0f};
  TrackEvidence e;
  e.add_segment({1.0f, -2.0f, -4.0f}, prior);
  e.add_segment({0.0f, -1.0f, -3.0f}, prior);
  e.add_segment({2.0f, -3.0f, -2.0f}, prior);
  return e;
}

TEST(DiscreteBayesFilter, RunningSumAndMeanOfSegmentEvidence) {
  const TrackEvidence e = three_segments();
  EXPECT_EQ(e.segments, 3u);
  EXPECT_DOUBLE_EQ(e.segment_sum[0], 6.0);
  EXPECT_DOUBLE_EQ(e.segment_sum[1], 0.0);
  EXPECT_DOUBLE_EQ(e.segment_sum[2], 0.0);
  EXPECT_EQ(e.segment_mean(), (LogOdds{2.0f, 0.0f, 0.0f}));
  EXPECT_EQ(TrackEvidence{}.segment_mean(), (LogOdds{0.0f, 0.0f, 0.0f}));  // no segment yet
}

TEST(DiscreteBayesFilter, NaiveAddsTheSumToTheBase) {
  EXPECT_EQ(naive_dbf(three_segments(), {0.5f, -0.5f, -1.0f}), (LogOdds{6.5f, -0.5f, -1.0f}));
}

TEST(DiscreteBayesFilter, NormalizedAddsTheMeanToTheBase) {
  EXPECT_EQ(normalized_dbf(three_segments(), {0.5f, -0.5f, -1.0f}), (LogOdds{2.5f, -0.5f, -1.0f}));
}

TEST(DiscreteBayesFilter, AugmentedWeighsPriorHolisticAndSegmentTerms) {
  const AdbfParams p{{2.0f, 1.0f, 0.0f}, {0.5f, 1.0f, 1.0f}, {0.25f, 2.0f, 1.0f}};
  const LogOdds l0h{-1.0f, -1.0f, -2.0f}, hh{1.0f, 0.0f, -4.0f};
  const LogOdds out = augmented_dbf(three_segments(), l0h, hh, p);
  EXPECT_FLOAT_EQ(out[0], 2.0f * -1.0f + 0.5f * 2.0f + 0.25f * 2.0f);  // -0.5
  EXPECT_FLOAT_EQ(out[1], 0.0f);                                       // -1 + 1 + 0
  EXPECT_FLOAT_EQ(out[2], -2.0f);                                      // 0 - 2 + 0
  EXPECT_EQ(predict(out, kDefaultClassCount), kPedestrian);
  // Default parameters are the normalized filter with the holistic log odds as base.
  EXPECT_EQ(augmented_dbf(three_segments(), l0h, hh, AdbfParams{}),
            normalized_dbf(three_segments(), hh));
}

TEST(LogisticRegression, RecoversKnownCoefficients) {
  std::mt19937 rng(11);
  std::normal_distribution<double> g(0.0, 1.0);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const Eigen::Vector3d truth(0.8, -1.5, 2.0);
  const int n = 20000;
  Eigen::MatrixXd x(n, 3);
  std::vector<double> y(n);
  for (int m = 0; m < n; ++m) {
    x.row(m) << 1.0, g(rng), g(rng);
    const double p = 1.0 / (1.0 + std::exp(-x.row(m).dot(truth)));
    y[static_cast<std::size_t>(m)] = u(rng) < p ? 1.0 : -1.0;
  }
  auto theta = learning::fit_logistic(x, y, {.l2 = 1e-6});
  ASSERT_TRUE(theta.has_value()) << theta.error().message;
  for (int i = 0; i < 3; ++i) EXPECT_NEAR((*theta)[i], truth[i], 0.1) << "coefficient " << i;
  EXPECT_FALSE(learning::fit_logistic(x, std::vector<double>(3, 1.0), {}).has_value());
}

// Tracks whose segment evidence is weak per frame and shares a per-track bias (segments of one
// track are not independent), with an informative holistic classifier.
struct SyntheticTracks {
  std::vector<learning::TrackSample> samples;
  std::vector<TrackEvidence> evidence;
};
constexpr LogOdds kHolisticPrior{-1.1f, -1.1f, -1.1f};  // about log(1/3): 4 balanced labels

SyntheticTracks synthetic_tracks(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> g(0.0f, 1.0f);
  std::uniform_int_distribution<int> label(0, 3), length(10, 60);
  const LogOdds segment_prior{-1.0f, -1.0f, -1.0f};
  SyntheticTracks t;
  for (int m = 0; m < n; ++m) {
    learning::TrackSample s;
    s.label = testing::label_of(label(rng));
    LogOdds bias{};
    for (std::size_t k = 0; k < kDefaultClassCount; ++k) {
      const float y = s.label == k ? 1.0f : -1.0f;
      s.holistic[k] = kHolisticPrior[k] + 1.5f * y + 1.5f * g(rng);
      bias[k] = 1.2f * g(rng);
    }
    TrackEvidence e;
    for (int f = length(rng); f > 0; --f) {
      LogOdds h{};
      for (std::size_t k = 0; k < kDefaultClassCount; ++k) {
        const float y = s.label == k ? 1.0f : -1.0f;
        h[k] = segment_prior[k] + 0.6f * y + bias[k] + 2.0f * g(rng);
      }
      e.add_segment(h, segment_prior);
    }
    s.segment_mean = e.segment_mean();
    t.samples.push_back(s);
    t.evidence.push_back(e);
  }
  return t;
}

template <class F>
double track_accuracy(const SyntheticTracks& t, F filter) {
  int right = 0;
  for (std::size_t m = 0; m < t.samples.size(); ++m)
    right += predict(filter(t.samples[m], t.evidence[m]), kDefaultClassCount) == t.samples[m].label;
  return right / static_cast<double>(t.samples.size());
}

TEST(AugmentedDiscreteBayesFilter, FittedOnHeldOutTracksBeatsNaiveAndNormalized) {
  const SyntheticTracks held_out = synthetic_tracks(3000, 21), test = synthetic_tracks(3000, 22);
  auto params = learning::fit_adbf(held_out.samples, kHolisticPrior, kDefaultClassCount, {});
  ASSERT_TRUE(params.has_value()) << params.error().message;
  const double naive =
      track_accuracy(test, [](auto& s, auto& e) { return naive_dbf(e, s.holistic); });
  const double normalized =
      track_accuracy(test, [](auto& s, auto& e) { return normalized_dbf(e, s.holistic); });
  const double adbf = track_accuracy(test, [&](auto& s, auto& e) {
    return augmented_dbf(e, kHolisticPrior, s.holistic, *params);
  });
  EXPECT_GE(adbf, naive);
  EXPECT_GE(adbf, normalized);
  EXPECT_GT(adbf, 0.5);  // chance: 0.25
  RecordProperty("naive", std::to_string(naive));
  RecordProperty("normalized", std::to_string(normalized));
  RecordProperty("adbf", std::to_string(adbf));
}

TEST(TrackEvidence, UpdatesAndFiltersAllocateNothing) {
  TrackEvidence e;
  const LogOdds prior{-1.0f, -2.0f, -3.0f};
  const AdbfParams p;
  e.add_segment({0.0f, 0.0f, 0.0f}, prior);  // warm-up
  float sink = 0;
  rt::testing::AllocationCounter counter;
  for (int i = 0; i < 1000; ++i) {
    e.add_segment({0.1f * float(i % 7), -1.0f, 0.5f}, prior);
    sink +=
        naive_dbf(e, prior)[0] + normalized_dbf(e, prior)[1] + augmented_dbf(e, prior, prior, p)[2];
  }
  counter.stop();
  EXPECT_EQ(counter.allocations(), 0u);
  EXPECT_TRUE(std::isfinite(sink));
}

}  // namespace
}  // namespace stac::classification
