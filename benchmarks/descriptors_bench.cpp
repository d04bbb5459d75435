// Segment descriptors (29 spaces, 931 values) on every segment the Segmenter finds in the six
// real KITTI scans, one segment per iteration (round robin) on one core; per-segment wall times
// give the median, p99 and max (microseconds).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "benchmarks/kitti_scans.hpp"
#include "perception/descriptors/descriptors.hpp"
#include "perception/segmentation/segmenter.hpp"

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
  std::sort(us.begin(), us.end());
  const auto at = [&](double q) {
    return us[std::min(us.size() - 1, static_cast<std::size_t>(q * static_cast<double>(us.size())))];
  };
  state.counters["median_us"] = at(0.5);
  state.counters["p99_us"] = at(0.99);
  state.counters["max_us"] = us.back();
  state.counters["mean_points"] = points / static_cast<double>(us.size());
  state.counters["segments"] = static_cast<double>(c.segments.size());
}
BENCHMARK(BM_SegmentDescriptors)->Iterations(20000)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
