// Decode throughput of the HDL-64E driver on one core: packets -> corrected, timed points framed
// into scans. Reported as points/s and as a multiple of the sensor's 1,333,312 points/s.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <filesystem>
#include <random>

#include "drivers/velodyne/scan_assembler.hpp"
#include "velodyne/synthetic_stream.hpp"

namespace {

using namespace stac::velodyne;

constexpr double kSensorPointsPerSecond = 1'333'312.0;

Calibration benchmark_calibration() {
  const std::filesystem::path path = std::filesystem::path(STAC_SHARED_DATA_DIR) /
                                     "velodyne/calib/rosdrivers_64e_s2.1-sztaki.yaml";
  auto c = load_calibration(path);
  if (!c) {
    std::fprintf(stderr, "decode_bench: %s\n", c.error().message.c_str());
    std::abort();
  }
  return *c;
}

// One second of traffic at 600 rpm with ranges spread over 2-80 m (all two-point paths taken).
std::vector<stac::testing::StreamPacket> traffic() {
  stac::testing::StreamSpec spec;
  spec.seconds = 1.0;
  auto packets = stac::testing::make_stream(spec);
  std::mt19937 rng(42);
  std::uniform_int_distribution<int> range(1000, 40000);
  for (auto& p : packets) {
    for (int b = 0; b < kBlocksPerPacket; ++b) {
      for (int j = 0; j < kLasersPerBlock; ++j) {
        store_u16(p.bytes.data() + b * 100 + 4 + 3 * j, static_cast<std::uint16_t>(range(rng)));
      }
    }
  }
  return packets;
}

void BM_DecodeAndFrameScans(benchmark::State& state) {
  const auto packets = traffic();
  ScanAssemblerConfig cfg;
  cfg.decoder.gate_two_point_correction = state.range(0) != 0;
  ScanAssembler assembler(benchmark_calibration(), cfg);
  Scan a(scan_capacity(cfg)), b(scan_capacity(cfg));
  Scan* current = &a;
  assembler.begin(*current);
  std::size_t points = 0;
  std::int64_t shift = 0;
  for (auto _ : state) {
    for (const auto& p : packets) {
      if (assembler.add_packet(p.bytes, p.stamp_ns + shift)) {
        points += current->points.size();
        benchmark::DoNotOptimize(current->points.data());
        current = current == &a ? &b : &a;
        assembler.begin(*current);
      }
    }
    shift += 1'000'000'000;  // the next pass continues in time: no gap, no duplicate
  }
  const double seconds_per_iteration = 1.0;
  state.SetItemsProcessed(static_cast<std::int64_t>(points));
  state.counters["points_per_s"] =
      benchmark::Counter(static_cast<double>(points), benchmark::Counter::kIsRate);
  state.counters["x_realtime"] = benchmark::Counter(
      static_cast<double>(points) / kSensorPointsPerSecond, benchmark::Counter::kIsRate);
  state.counters["sensor_s_per_iter"] = seconds_per_iteration;
}
BENCHMARK(BM_DecodeAndFrameScans)->Arg(0)->Arg(1)->ArgName("gate")->Unit(benchmark::kMillisecond);

void BM_DecodeBlock(benchmark::State& state) {
  const auto packets = traffic();
  PacketDecoder decoder(benchmark_calibration(), DecoderConfig{});
  Point out[kLasersPerBlock];
  std::size_t i = 0;
  std::int64_t points = 0;
  for (auto _ : state) {
    const RawPacket* p = as_packet(packets[i].bytes);
    for (int b = 0; b < kBlocksPerPacket; ++b)
      points += decoder.decode_block(p->blocks[b], b, false, 0, out);
    benchmark::DoNotOptimize(out);
    i = (i + 1) % packets.size();
  }
  state.SetItemsProcessed(points);
  state.counters["x_realtime"] = benchmark::Counter(
      static_cast<double>(points) / kSensorPointsPerSecond, benchmark::Counter::kIsRate);
}
BENCHMARK(BM_DecodeBlock);

}  // namespace

BENCHMARK_MAIN();
