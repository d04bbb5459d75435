// Segmentation of the six real KITTI scans (HDL-64E, about 124k points each) on one core:
// STAC's grid segmenter on the whole scan (ground + obstacle grid + flood fill + boxes) against
// PCL's EuclideanClusterExtraction (tolerance 0.5 m, the approach Autoware's euclidean_cluster
// wraps) on the SAME obstacle points STAC found, raw or after a 0.1 / 0.2 m voxel grid. Each
// iteration segments one scan (round robin); per-iteration times give the median, p99 and max.
// BM_StacSegmentAndTrack: segmentation + tracking per scan as the perception thread runs them.
// BM_StacSegmenterBesideMemoryProbe: how the segmenter's time follows the machine's memory speed.
#include <benchmark/benchmark.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>
#include <pcl/segmentation/extract_clusters.h>
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "benchmarks/kitti_scans.hpp"
#include "benchmarks/timing_stats.hpp"
#include "perception/segmentation/segmenter.hpp"
#include "pipeline/scan_pipeline.hpp"

namespace {

using namespace stac::segmentation;
using stac::benchmarks::quantile;

const std::vector<std::vector<float>>& scans() {
  return stac::benchmarks::kitti_scans();
}

PointView view(const std::vector<float>& xyzi) {
  return {xyzi.data(), xyzi.size() / 4, 16};
}

// The obstacle points of each scan as STAC classifies them (every obstacle cluster kept).
const std::vector<pcl::PointCloud<pcl::PointXYZ>::Ptr>& obstacle_clouds() {
  static const std::vector<pcl::PointCloud<pcl::PointXYZ>::Ptr> all = [] {
    SegmenterConfig c;
    c.min_segment_points = 1;
    c.max_segment_points = 100'000'000;
    c.max_segment_extent_m = 1e6;
    Segmenter segmenter(c);
    Segments out = segmenter.make_segments();
    std::vector<pcl::PointCloud<pcl::PointXYZ>::Ptr> clouds;
    for (const auto& scan : scans()) {
      segmenter.segment(view(scan), out);
      auto cloud = pcl::PointCloud<pcl::PointXYZ>::Ptr(new pcl::PointCloud<pcl::PointXYZ>);
      for (const std::uint32_t i : out.point_indices) {
        cloud->push_back(pcl::PointXYZ(scan[4 * i], scan[4 * i + 1], scan[4 * i + 2]));
      }
      clouds.push_back(cloud);
    }
    return clouds;
  }();
  return all;
}

// This thread's CPU time (ms): on a shared machine wall time also counts the other processes.
double cpu_ms() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

// Per-iteration times: wall (steady clock) and CPU, each as median, p99 and max.
struct Times {
  std::vector<double> wall, cpu;
  double wall0 = 0, cpu0 = 0;
  std::chrono::steady_clock::time_point t0;
  Times() {
    wall.reserve(100000);
    cpu.reserve(100000);
  }
  void start() {
    t0 = std::chrono::steady_clock::now();
    cpu0 = cpu_ms();
  }
  void stop() {
    wall.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    cpu.push_back(cpu_ms() - cpu0);
  }
};

void report(benchmark::State& state, Times& t, double points, double segments) {
  std::vector<double> wall_in_order = t.wall;
  for (auto* v : {&t.wall, &t.cpu}) std::sort(v->begin(), v->end());
  state.counters["median_ms"] = quantile(t.wall, 0.5);
  state.counters["p99_ms"] = quantile(t.wall, 0.99);
  state.counters["max_ms"] = t.wall.back();
  state.counters["cpu_median_ms"] = quantile(t.cpu, 0.5);
  state.counters["cpu_p99_ms"] = quantile(t.cpu, 0.99);
  state.counters["slow_blocks"] =
      stac::benchmarks::slow_blocks(std::move(wall_in_order), quantile(t.wall, 0.5));
  state.counters["points"] = points;
  state.counters["segments"] = segments;
}

// Arg 1: the default (L-shape fitted boxes); 0: principal-axis boxes (box_fit_points 0), for
// the fit's cost.
void BM_StacSegmenter(benchmark::State& state) {
  SegmenterConfig config;
  if (state.range(0) == 0) config.box_fit_points = 0;
  Segmenter segmenter{config};
  Segments out = segmenter.make_segments();
  segmenter.segment(view(scans()[0]), out);  // warm-up
  Times t;
  std::size_t k = 0;
  double points = 0, segments = 0;
  for (auto _ : state) {
    const auto& scan = scans()[k++ % scans().size()];
    t.start();
    segmenter.segment(view(scan), out);
    t.stop();
    benchmark::DoNotOptimize(out.segments.data());
    points += static_cast<double>(scan.size() / 4);
    segments += static_cast<double>(out.segments.size());
  }
  const auto n = static_cast<double>(t.wall.size());
  report(state, t, points / n, segments / n);
}
BENCHMARK(BM_StacSegmenter)->Arg(1)->Arg(0)->Iterations(1200)->Unit(benchmark::kMillisecond);

// How much of the segmenter's spread is the machine's: one scan (the first) segmented again and
// again, each time right after a fixed probe that reads 8 MB of memory (every 64-byte line once).
// The same work each iteration, so on a steady machine both times would barely vary. Reports the
// segmenter's median and p99, the probe's median and p99, their correlation over the iterations,
// and the segmenter's mean time after the probe's fastest half and after its slowest tenth
// (docs/benchmarks.md, "The host's steadiness").
void BM_StacSegmenterBesideMemoryProbe(benchmark::State& state) {
  Segmenter segmenter{SegmenterConfig{}};
  Segments out = segmenter.make_segments();
  const PointView scan = view(scans()[0]);
  segmenter.segment(scan, out);  // warm-up
  std::vector<std::uint64_t> probe(std::size_t{1} << 20);
  for (std::size_t i = 0; i < probe.size(); ++i) probe[i] = i;
  std::vector<double> seg_ms, probe_ms;
  std::uint64_t sum = 0;
  const auto ms_since = [](std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  };
  for (auto _ : state) {
    auto t0 = std::chrono::steady_clock::now();
    for (std::size_t i = 0; i < probe.size(); i += 8) sum += probe[i];
    probe_ms.push_back(ms_since(t0));
    t0 = std::chrono::steady_clock::now();
    segmenter.segment(scan, out);
    seg_ms.push_back(ms_since(t0));
  }
  benchmark::DoNotOptimize(sum);
  const auto n = static_cast<double>(seg_ms.size());
  double mean_s = 0, mean_p = 0;
  for (std::size_t i = 0; i < seg_ms.size(); ++i) {
    mean_s += seg_ms[i] / n;
    mean_p += probe_ms[i] / n;
  }
  double cov = 0, var_s = 0, var_p = 0;
  for (std::size_t i = 0; i < seg_ms.size(); ++i) {
    cov += (seg_ms[i] - mean_s) * (probe_ms[i] - mean_p);
    var_s += (seg_ms[i] - mean_s) * (seg_ms[i] - mean_s);
    var_p += (probe_ms[i] - mean_p) * (probe_ms[i] - mean_p);
  }
  std::vector<double> seg_sorted = seg_ms, probe_sorted = probe_ms;
  std::sort(seg_sorted.begin(), seg_sorted.end());
  std::sort(probe_sorted.begin(), probe_sorted.end());
  const double probe_median = quantile(probe_sorted, 0.5), probe_p90 = quantile(probe_sorted, 0.9);
  double fast = 0, slow = 0;
  std::size_t fast_n = 0, slow_n = 0;
  for (std::size_t i = 0; i < seg_ms.size(); ++i) {
    if (probe_ms[i] < probe_median) fast += seg_ms[i], ++fast_n;
    if (probe_ms[i] > probe_p90) slow += seg_ms[i], ++slow_n;
  }
  state.counters["median_ms"] = quantile(seg_sorted, 0.5);
  state.counters["p99_ms"] = quantile(seg_sorted, 0.99);
  state.counters["probe_median_ms"] = probe_median;
  state.counters["probe_p99_ms"] = quantile(probe_sorted, 0.99);
  state.counters["correlation"] = var_s > 0 && var_p > 0 ? cov / std::sqrt(var_s * var_p) : 0.0;
  state.counters["after_fast_probe_ms"] = fast_n > 0 ? fast / static_cast<double>(fast_n) : 0.0;
  state.counters["after_slow_probe_ms"] = slow_n > 0 ? slow / static_cast<double>(slow_n) : 0.0;
}
BENCHMARK(BM_StacSegmenterBesideMemoryProbe)->Iterations(2000)->Unit(benchmark::kMillisecond);

// Segmentation + tracking of one scan per iteration, as the perception thread runs them:
// ScanPipeline::process without poses (no deskew, the sensor parked: segment, detections with
// the end-on completion, track), default settings. The KITTI scans in sequence order and back
// (0..5, 4..1, 0..5, ...: the scene moves forwards then backwards and never jumps), 100 ms
// apart; times are of the whole process() call.
void BM_StacSegmentAndTrack(benchmark::State& state) {
  namespace velodyne = stac::velodyne;
  std::vector<velodyne::Scan> driver_scans;
  for (const auto& xyzi : scans()) {
    velodyne::Scan& scan = driver_scans.emplace_back(xyzi.size() / 4);
    for (std::size_t i = 0; i < xyzi.size() / 4; ++i) {
      velodyne::Point p{};
      p.x = xyzi[4 * i], p.y = xyzi[4 * i + 1], p.z = xyzi[4 * i + 2],
      p.intensity = xyzi[4 * i + 3];
      (void)scan.points.push_back(p);
    }
  }
  stac::pipeline::ScanPipeline pipeline{stac::pipeline::PipelineConfig{}};
  stac::pipeline::ScanResult result = pipeline.make_result();
  const std::size_t period = 2 * (driver_scans.size() - 1);  // 0..5, 4..1
  std::int64_t k = 0;
  const auto next = [&]() -> velodyne::Scan& {
    const std::size_t phase = static_cast<std::size_t>(k) % period;
    velodyne::Scan& scan = driver_scans[phase < driver_scans.size() ? phase : period - phase];
    scan.header.stamp_ns = scan.header.end_stamp_ns = 1'000'000'000 + k++ * 100'000'000;
    return scan;
  };
  for (int warm = 0; warm < 20; ++warm) pipeline.process(next(), nullptr, result);
  Times t;
  std::vector<double> segment_ms, track_ms;  // the pipeline's own stage times (thread CPU)
  double points = 0, segments = 0, tracks = 0;
  for (auto _ : state) {
    velodyne::Scan& scan = next();
    t.start();
    pipeline.process(scan, nullptr, result);
    t.stop();
    segment_ms.push_back(1e-6 * static_cast<double>(result.stage_ns[stac::pipeline::kSegment]));
    track_ms.push_back(1e-6 * static_cast<double>(result.stage_ns[stac::pipeline::kTrack]));
    benchmark::DoNotOptimize(result.tracked.tracks.data());
    points += static_cast<double>(scan.points.size());
    segments += static_cast<double>(result.segments.segments.size());
    tracks += static_cast<double>(result.tracked.tracks.size());
  }
  const auto n = static_cast<double>(t.wall.size());
  report(state, t, points / n, segments / n);
  state.counters["tracks"] = tracks / n;
  for (auto* v : {&segment_ms, &track_ms}) std::sort(v->begin(), v->end());
  state.counters["segment_median_ms"] = quantile(segment_ms, 0.5);
  state.counters["segment_p99_ms"] = quantile(segment_ms, 0.99);
  state.counters["track_median_ms"] = quantile(track_ms, 0.5);
  state.counters["track_p99_ms"] = quantile(track_ms, 0.99);
}
BENCHMARK(BM_StacSegmentAndTrack)->Iterations(1200)->Unit(benchmark::kMillisecond);

// voxel_cm = 0: the raw obstacle points; else a voxel grid of that leaf size first (timed).
void BM_PclEuclideanClusters(benchmark::State& state) {
  const float leaf = static_cast<float>(state.range(0)) / 100.0f;
  Times t;
  std::size_t k = 0;
  double points = 0, segments = 0;
  for (auto _ : state) {
    const auto& obstacle = obstacle_clouds()[k++ % obstacle_clouds().size()];
    t.start();
    pcl::PointCloud<pcl::PointXYZ>::Ptr cloud = obstacle;
    if (leaf > 0) {
      cloud.reset(new pcl::PointCloud<pcl::PointXYZ>);
      pcl::VoxelGrid<pcl::PointXYZ> grid;
      grid.setInputCloud(obstacle);
      grid.setLeafSize(leaf, leaf, leaf);
      grid.filter(*cloud);
    }
    pcl::search::KdTree<pcl::PointXYZ>::Ptr tree(new pcl::search::KdTree<pcl::PointXYZ>);
    tree->setInputCloud(cloud);
    std::vector<pcl::PointIndices> clusters;
    pcl::EuclideanClusterExtraction<pcl::PointXYZ> ec;
    ec.setClusterTolerance(0.5);
    ec.setMinClusterSize(8);  // as min_segment_points
    ec.setMaxClusterSize(30000);
    ec.setSearchMethod(tree);
    ec.setInputCloud(cloud);
    ec.extract(clusters);
    t.stop();
    points += static_cast<double>(obstacle->size());
    segments += static_cast<double>(clusters.size());
  }
  const auto n = static_cast<double>(t.wall.size());
  report(state, t, points / n, segments / n);
}
BENCHMARK(BM_PclEuclideanClusters)
    ->Arg(0)
    ->Iterations(12)
    ->ArgName("voxel_cm")
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PclEuclideanClusters)
    ->Arg(10)
    ->Iterations(30)
    ->ArgName("voxel_cm")
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PclEuclideanClusters)
    ->Arg(20)
    ->Iterations(60)
    ->ArgName("voxel_cm")
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
