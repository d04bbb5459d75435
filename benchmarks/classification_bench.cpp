// Segment classification cost on one core: the binned boosting classifier on 931-element
// descriptors (the full layout, 2 grids of 10 and 100 bins per element), after 10 and after
// 2000 training rounds (the cost must not depend on it) with the default 3 classes and with the
// maximum of 8 (the table stride is the model's class count), and one track filter update.
#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include "perception/classification/track_filter.hpp"
#include "perception/descriptors/descriptors.hpp"
#include "perception/learning/boosting.hpp"

namespace {

using namespace stac;

// n examples of `classes` classes and background, in turn.
learning::TrainingSet random_segments(std::size_t n, std::size_t classes, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> g(0.0f, 1.0f);
  learning::TrainingSet set{descriptors::kDimensions, classes, {}, {}};
  std::vector<float> x(descriptors::kDimensions);
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t k = i % (classes + 1);
    for (auto& v : x) v = g(rng);
    for (std::size_t e = 0; e < 40; ++e) x[e] += static_cast<float>(k);  // some signal
    set.add(
        x, k == classes ? classification::kBackground : static_cast<classification::ClassIndex>(k));
  }
  return set;
}

void BM_ClassifySegment(benchmark::State& state) {
  const auto classes = static_cast<std::size_t>(state.range(1));
  const auto train = random_segments(400, classes, 1);
  learning::BoostingConfig config;
  config.rounds = static_cast<std::size_t>(state.range(0));
  const auto c = learning::train_boosting(train, classification::segment_layout(), config);
  if (!c) {
    state.SkipWithError(c.error().message.c_str());
    return;
  }
  const auto inputs =
      random_segments(256, classes, 2);  // different values: realistic cache behaviour
  classification::LogOdds out{};
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(c->classify(inputs.row(i++ % inputs.size()), out));
    benchmark::DoNotOptimize(out);
  }
  state.counters["table_MB"] = static_cast<double>(c->model().table.size() * 4) / 1e6;
}
BENCHMARK(BM_ClassifySegment)
    ->ArgNames({"rounds", "classes"})
    ->Args({10, 3})
    ->Args({2000, 3})
    ->Args({2000, 8})
    ->Unit(benchmark::kMicrosecond);

void BM_TrackFilterUpdate(benchmark::State& state) {
  classification::TrackEvidence e;
  const classification::LogOdds prior{-1.0f, -2.0f, -3.0f}, seg{0.5f, -1.0f, -2.0f};
  const classification::AdbfParams p;
  for (auto _ : state) {
    e.add_segment(seg, prior);
    benchmark::DoNotOptimize(classification::augmented_dbf(e, prior, prior, p));
  }
}
BENCHMARK(BM_TrackFilterUpdate);

}  // namespace

BENCHMARK_MAIN();
