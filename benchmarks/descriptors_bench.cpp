// Segment descriptors (29 spaces, 931 values) on every segment the Segmenter finds in the six
// real KITTI scans, one segment per iteration (round robin) on one core; per-segment wall times
// give the median, p99 and max (microseconds). BM_ClassifyStage: the whole per-segment work of
// the pipeline's classify stage (descriptors, accumulated cloud described every 5th update,
// segment + holistic classification, ADBF) with the shipped model when there is one.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>
#include <vector>

#include "benchmarks/kitti_scans.hpp"
#include "benchmarks/timing_stats.hpp"
#include "perception/classification/track_classifier.hpp"
#include "perception/descriptors/descriptors.hpp"
#include "perception/segmentation/segmenter.hpp"
#include "settings/build_tree.hpp"
#include "tests/classification/made_up_model.hpp"

namespace {

using namespace stac;

struct Corpus {
  std::vector<std::vector<float>> scans;
  std::vector<std::pair<std::size_t, std::vector<std::uint32_t>>> segments;  // scan, indices
};

const Corpus& corpus() {
  static const Corpus c = [] {
    Corpus out;
    segmentation::Segmenter segmenter{segmentation::SegmenterConfig{}};
    auto segs = segmenter.make_segments();
    for (const std::vector<float>& v : stac::benchmarks::kitti_scans()) {
      segmenter.segment({v.data(), v.size() / 4, 16}, segs);
      for (const auto& s : segs.segments) {
        const auto idx = segs.indices(s);
        out.segments.emplace_back(out.scans.size(),
                                  std::vector<std::uint32_t>(idx.begin(), idx.end()));
      }
      out.scans.push_back(std::move(v));
    }
    return out;
  }();
  return c;
}

// Median, p99 and max of per-call times (us) as counters.
void report_percentiles(benchmark::State& state, std::vector<double>& us) {
  std::sort(us.begin(), us.end());
  state.counters["median_us"] = stac::benchmarks::quantile(us, 0.5);
  state.counters["p99_us"] = stac::benchmarks::quantile(us, 0.99);
  state.counters["max_us"] = us.back();
}

void BM_SegmentDescriptors(benchmark::State& state) {
  const Corpus& c = corpus();
  descriptors::DescriptorConfig config;
  config.intensity_full_scale = 1.0;
  descriptors::DescriptorPipeline pipeline(config);
  descriptors::Descriptors out;
  std::vector<double> us;
  us.reserve(static_cast<std::size_t>(state.max_iterations));
  std::size_t k = 0;
  double points = 0;
  for (auto _ : state) {
    const auto& [scan, indices] = c.segments[k++ % c.segments.size()];
    descriptors::SegmentView view;
    view.xyzi = c.scans[scan].data();
    view.stride_bytes = 16;
    view.indices = indices;
    const auto t0 = std::chrono::steady_clock::now();
    pipeline.compute(view, out);
    us.push_back(
        std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
    benchmark::DoNotOptimize(out.values.data());
    points += static_cast<double>(indices.size());
  }
  report_percentiles(state, us);
  state.counters["mean_points"] = points / static_cast<double>(us.size());
  state.counters["segments"] = static_cast<double>(c.segments.size());
}
BENCHMARK(BM_SegmentDescriptors)->Iterations(20000)->Unit(benchmark::kMicrosecond);

// The shipped model (config/models/stac_default.stacmodel), else one with made-up responses over
// the same layouts (tests/classification/made_up_model.hpp). The amount of work is the same; the
// real model's bins are spread over its tables, so it costs more cache misses.
std::shared_ptr<const classification::TrackClassifierModel> bench_model(bool& shipped) {
  const std::filesystem::path file =
      std::filesystem::path(stac::settings::kSourceDir) / "config/models/stac_default.stacmodel";
  std::ifstream in(file, std::ios::binary);
  const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                                        std::istreambuf_iterator<char>());
  if (auto m = classification::deserialize(bytes); m.has_value()) {
    shipped = true;
    return std::make_shared<const classification::TrackClassifierModel>(std::move(*m));
  }
  shipped = false;
  return classification::testing::made_up_model().value();
}

void BM_ClassifyStage(benchmark::State& state) {
  const Corpus& c = corpus();
  bool shipped = false;
  classification::TrackClassifierConfig config;
  config.descriptors.intensity_full_scale = 1.0;  // KITTI reflectance
  config.max_tracks = 64;
  classification::TrackClassifier stage(config, bench_model(shipped));
  // One track update per iteration: 64 tracks in 64 pool slots, each fed the corpus's segments
  // in turn, so accumulated clouds grow and are described every 5th update as in the pipeline.
  segmentation::Segments segments(1, 40000);
  tracking::TrackerOutput tracked(1);
  (void)tracked.tracks.resize(1);
  rt::FixedVector<classification::TrackClass> out(1);
  std::vector<double> us;
  us.reserve(static_cast<std::size_t>(state.max_iterations));
  std::size_t k = 0;
  for (auto _ : state) {
    const auto& [scan, indices] = c.segments[k % c.segments.size()];
    segments.segments.clear();
    segmentation::Segment* seg = segments.segments.append();
    seg->first = 0;
    seg->count = static_cast<std::uint32_t>(indices.size());
    (void)segments.point_indices.resize(indices.size());
    std::copy(indices.begin(), indices.end(), segments.point_indices.data());
    tracking::Track& t = tracked.tracks[0];
    t.id = 1 + k % 64;
    t.slot = static_cast<std::uint32_t>(k % 64);
    t.segment = 0;
    ++k;
    const auto t0 = std::chrono::steady_clock::now();
    stage.classify(c.scans[scan].data(), 16, segments, tracked, out);
    us.push_back(
        std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
    benchmark::DoNotOptimize(out[0].log_odds.data());
  }
  report_percentiles(state, us);
  state.counters["shipped_model"] = shipped ? 1 : 0;
  state.counters["holistic_share"] = static_cast<double>(stage.counters().holistic_described) /
                                     static_cast<double>(stage.counters().segments_described);
}
BENCHMARK(BM_ClassifyStage)->Iterations(20000)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
