// Group induction at the thesis's scale (issue 29; docs/learning.md "Scale"): the induction phase
// over a full buffer of 20,000 groups of 10 segments (this build's 931 segment and 940 holistic
// dimensions), one training round on the inducted groups, and memory over 50 chunks streamed
// through the bounded buffer. Run on one core (taskset -c 1); data synthetic, classifier trained
// on a few labelled examples of it so that some groups are inducted.
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <fstream>
#include <random>
#include <string>

#include "perception/classification/holistic.hpp"
#include "perception/descriptors/descriptors.hpp"
#include "perception/learning/induction.hpp"

namespace {

using namespace stac;
using classification::ClassIndex;
constexpr std::size_t kSeg = descriptors::kDimensions;
constexpr std::size_t kHol = classification::kHolisticDimensions;

// Element c (c < 3) of every segment says the class (near +2 for its own class), the rest noise.
std::vector<float> rows(std::mt19937& rng, std::size_t n, std::size_t dims, int cls) {
  std::normal_distribution<float> g(0.0f, 1.0f);
  std::vector<float> v(n * dims);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t e = 0; e < dims; ++e)
      v[i * dims + e] = (static_cast<int>(e) == cls ? 2.0f : 0.0f) + g(rng);
  return v;
}

// `inducted`: every group already carries its class (the worst case of a training round: the
// whole buffer in the training set).
std::vector<learning::Group> groups(std::mt19937& rng, std::size_t n, std::uint32_t source,
                                    bool inducted = false) {
  std::vector<learning::Group> out(n);
  std::uniform_int_distribution<int> cls(0, 3);
  for (std::size_t i = 0; i < n; ++i) {
    const int c = cls(rng);
    if (inducted) out[i].label = c == 3 ? classification::kBackground : static_cast<ClassIndex>(c);
    out[i].source = source;
    out[i].track = i;
    out[i].segments = rows(rng, 10, kSeg, c);
    out[i].holistic = rows(rng, 1, kHol, c);
  }
  return out;
}

// A model trained on 400 labelled tracks of the same data.
classification::TrackClassifierModel model(std::mt19937& rng) {
  std::vector<learning::TrackExample> labels;
  for (int i = 0; i < 400; ++i) {
    const int c = i % 4;
    labels.push_back({c == 3 ? classification::kBackground : static_cast<ClassIndex>(c),
                      rows(rng, 10, kSeg, c), rows(rng, 1, kHol, c)});
  }
  const auto data = learning::round_data(labels, {}, {}, 3, kSeg, kHol);
  learning::TrainingPhaseConfig config;
  config.reset_rounds = 200;
  auto start = learning::initial_model(classification::default_class_names(), data, data,
                                       classification::build_layouts(), config);
  auto trained = learning::training_phase(*start, data, true, config);
  return *trained;
}

double rss_mb() {
  std::ifstream statm("/proc/self/statm");
  std::size_t pages = 0, resident = 0;
  statm >> pages >> resident;
  return static_cast<double>(resident) * static_cast<double>(sysconf(_SC_PAGESIZE)) / 1e6;
}

void BM_InductionPhaseFullBuffer(benchmark::State& state) {
  std::mt19937 rng(1);
  const auto m = model(rng);
  auto buffer = groups(rng, static_cast<std::size_t>(state.range(0)), 0);
  learning::InductionConfig config;
  std::size_t inducted = 0;
  for (auto _ : state) {
    const auto s = learning::induction_phase(m.segment, buffer, config, learning::uniform_noise(0));
    inducted = buffer.size() - s.uninducted;
  }
  state.counters["groups"] = static_cast<double>(buffer.size());
  state.counters["inducted"] = static_cast<double>(inducted);
  state.counters["rss_MB"] = rss_mb();
}
BENCHMARK(BM_InductionPhaseFullBuffer)->Arg(20'000)->Unit(benchmark::kSecond)->Iterations(1);

void BM_TrainingRoundFullBuffer(benchmark::State& state) {
  std::mt19937 rng(2);
  const auto m = model(rng);
  const auto buffer = groups(rng, static_cast<std::size_t>(state.range(0)), 0, true);
  const auto data = learning::round_data({}, {}, buffer, 3, kSeg, kHol);
  learning::TrainingPhaseConfig phase;
  for (auto _ : state) {
    auto next = learning::training_phase(m, data, false, phase);
    benchmark::DoNotOptimize(next);
  }
  state.counters["segments_trained"] = static_cast<double>(data.segments.size());
  state.counters["boosting_rounds"] = static_cast<double>(phase.warm_rounds);
  state.counters["rss_MB"] = rss_mb();
}
BENCHMARK(BM_TrainingRoundFullBuffer)->Arg(20'000)->Unit(benchmark::kSecond)->Iterations(1);

// (Every group inducted: the training set is the whole buffer, 200,000 segments.)

// 50 chunks of 2,000 groups through a buffer of 20,000: the buffer's size and the process's RSS
// after the first buffer-filling chunk and after the last.
void BM_FiftyChunksThroughTheBuffer(benchmark::State& state) {
  std::mt19937 rng(3);
  const auto m = model(rng);
  learning::InductionConfig config;
  double rss_full = 0, rss_last = 0, rss_max = 0;
  std::size_t size = 0;
  for (auto _ : state) {
    std::vector<learning::Group> buffer;
    for (std::uint32_t chunk = 0; chunk < 50; ++chunk) {
      for (auto& g : groups(rng, 2'000, chunk)) buffer.push_back(std::move(g));
      (void)learning::induction_phase(m.segment, buffer, config, learning::uniform_noise(0));
      learning::keep_most_useful(buffer, config.buffer_groups);
      buffer.shrink_to_fit();
      const double rss = rss_mb();
      if (chunk == 10) rss_full = rss;  // the buffer full since chunk 9
      rss_max = std::max(rss_max, rss);
      rss_last = rss;
    }
    size = buffer.size();
  }
  state.counters["buffer_groups"] = static_cast<double>(size);
  state.counters["rss_MB_chunk10"] = rss_full;
  state.counters["rss_MB_chunk50"] = rss_last;
  state.counters["rss_MB_max"] = rss_max;
}
BENCHMARK(BM_FiftyChunksThroughTheBuffer)->Unit(benchmark::kSecond)->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
