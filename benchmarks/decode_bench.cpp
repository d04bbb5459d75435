// Decode throughput of the Velodyne driver on one core: packets -> corrected, timed points framed
// into scans. Reported as points/s and as a multiple of the sensor's own rate (HDL-64E 1,333,312
// points/s; the HDL-32E, VLP-16 and VLP-32C: lasers x firing sequences a second).
#include <benchmark/benchmark.h>

#include <cstdio>
#include <filesystem>
#include <random>

#include "drivers/velodyne/scan_assembler.hpp"
#include "settings/build_tree.hpp"
#include "velodyne/synthetic_stream.hpp"

namespace {

using namespace stac::velodyne;

constexpr double kSensorPointsPerSecond = 1'333'312.0;

Calibration benchmark_calibration() {
  const std::filesystem::path path = std::filesystem::path(stac::settings::kSharedDataDir) /
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

// Frames `packets` (one pass = `pass_ns` of the sensor's time) into scans as long as the state
// runs, each pass continuing in time (no gap, no duplicate); points/s and the multiple of
// `sensor_points_per_s`.
void frame_scans(benchmark::State& state, const Calibration& calibration,
                 const ScanAssemblerConfig& cfg,
                 const std::vector<stac::testing::StreamPacket>& packets, std::int64_t pass_ns,
                 double sensor_points_per_s) {
  ScanAssembler assembler(calibration, cfg);
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
    shift += pass_ns;
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(points));
  state.counters["points_per_s"] =
      benchmark::Counter(static_cast<double>(points), benchmark::Counter::kIsRate);
  state.counters["x_realtime"] = benchmark::Counter(
      static_cast<double>(points) / sensor_points_per_s, benchmark::Counter::kIsRate);
  state.counters["sensor_s_per_iter"] = static_cast<double>(pass_ns) * 1e-9;
  if (assembler.counters().model_mismatch + assembler.counters().invalid_block != 0)
    state.SkipWithError("the packets were refused or named another model");
}

void BM_DecodeAndFrameScans(benchmark::State& state) {
  ScanAssemblerConfig cfg;
  cfg.decoder.gate_two_point_correction = state.range(0) != 0;
  frame_scans(state, benchmark_calibration(), cfg, traffic(), 1'000'000'000,
              kSensorPointsPerSecond);
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

// The HDL-32E, VLP-16 and VLP-32C: one second of each model's packets at 600 rpm (its firing
// timing, 0xEEFF blocks, factory bytes), ranges spread over 2-80 m, its calibration.
Model family_model(std::int64_t arg) {
  return arg == 0 ? Model::kHdl32e : arg == 1 ? Model::kVlp16 : Model::kVlp32c;
}

void BM_DecodeFamily(benchmark::State& state) {
  const Model model = family_model(state.range(0));
  const ModelTraits& t = traits(model);
  const std::filesystem::path shared(stac::settings::kSharedDataDir),
      source(stac::settings::kSourceDir);
  const std::filesystem::path file =
      model == Model::kHdl32e  ? shared / "velodyne/calib/veloview_HDL-32.xml"
      : model == Model::kVlp16 ? shared / "velodyne/calib/veloview_VLP-16.xml"
                               : source / "config/calib/vlp32c.yaml";
  auto loaded = load_calibration(file);
  if (!loaded) {
    state.SkipWithError(loaded.error().message.c_str());
    return;
  }
  const Calibration calibration = lasers_of(*loaded, model);
  std::vector<stac::testing::StreamPacket> packets;
  std::mt19937 rng(42);
  std::uniform_int_distribution<int> range(1000, 40000);
  const double period = 1.0 / t.packets_per_second_single;
  for (int k = 0; k < static_cast<int>(t.packets_per_second_single); ++k) {
    std::array<std::uint8_t, kPacketSize> p{};
    for (int b = 0; b < kBlocksPerPacket; ++b) {
      const double time = k * period + firing_time_us(t, b, 0, false) * 1e-6;
      const auto rot = static_cast<std::uint16_t>(std::lround(time * 3600.0 * 100.0) % 36000);
      store_u16(p.data() + b * 100, kUpperBank);
      store_u16(p.data() + b * 100 + 2, rot);
      for (int j = 0; j < kLasersPerBlock; ++j) {
        store_u16(p.data() + b * 100 + 4 + 3 * j, static_cast<std::uint16_t>(range(rng)));
        p[static_cast<std::size_t>(b * 100 + 6 + 3 * j)] = 100;
      }
    }
    p[1204] = kReturnStrongest;
    p[1205] = t.product_id;
    packets.push_back({p, std::llround(k * period * 1e9)});
  }
  ScanAssemblerConfig cfg;
  cfg.decoder.model = model;
  state.SetLabel(std::string(t.name));
  frame_scans(state, calibration, cfg, packets,
              std::llround(static_cast<double>(packets.size()) * period * 1e9),
              t.lasers * 1e6 / t.sequence_us);  // every laser once a firing sequence
}
BENCHMARK(BM_DecodeFamily)->DenseRange(0, 2)->ArgName("model")->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
