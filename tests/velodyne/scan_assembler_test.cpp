#include "drivers/velodyne/scan_assembler.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "rt/testing/alloc_counter.hpp"
#include "shared_data.hpp"
#include "synthetic_stream.hpp"

namespace stac::velodyne {
namespace {

using stac::testing::make_stream;
using stac::testing::StreamPacket;
using stac::testing::StreamSpec;

using stac::testing::flat_calibration;

struct Assembled {
  std::vector<ScanHeader> headers;
  std::vector<std::size_t> sizes;
  std::vector<std::pair<int, int>> azimuth_span;  // min, max forward from first
  AssemblerCounters counters;
};

Assembled assemble(const std::vector<StreamPacket>& packets, ScanAssemblerConfig cfg = {}) {
  ScanAssembler a(flat_calibration(), cfg);
  Scan scan(scan_capacity(cfg));
  a.begin(scan);
  Assembled run;
  auto take = [&] {
    run.headers.push_back(scan.header);
    run.sizes.push_back(scan.points.size());
    int lo = 36000, hi = 0;
    for (const Point& p : scan.points) {
      const int d = (p.azimuth - scan.header.first_azimuth + 36000) % 36000;
      lo = std::min(lo, d);
      hi = std::max(hi, d);
    }
    run.azimuth_span.emplace_back(lo, hi);
    a.begin(scan);
  };
  for (const StreamPacket& p : packets) {
    if (a.add_packet(p.bytes, p.stamp_ns)) take();
  }
  if (a.flush()) take();
  run.counters = a.counters();
  return run;
}

// 600 rpm: 2083.3 firings of 64 returns per turn.
TEST(ScanAssembler, FramesOnCutAngle) {
  StreamSpec spec;
  spec.seconds = 1.05;
  const Assembled run = assemble(make_stream(spec));
  ASSERT_GE(run.headers.size(), 11u);
  EXPECT_FALSE(run.headers.front().starts_at_cut);  // started mid-turn
  EXPECT_FALSE(run.headers.back().ends_at_cut);     // flushed at the end
  for (std::size_t i = 1; i + 1 < run.headers.size(); ++i) {
    const ScanHeader& h = run.headers[i];
    SCOPED_TRACE("scan " + std::to_string(i));
    EXPECT_TRUE(h.complete());
    EXPECT_EQ(h.sequence, i);
    // Firings are 17.28 units (48 us) apart at 600 rpm, rounded to whole units.
    EXPECT_LT(h.first_azimuth, 18);  // the first firing at or after 0 deg
    EXPECT_GE(h.last_azimuth, 36000 - 18);
    EXPECT_NEAR(static_cast<double>(run.sizes[i]), 2083.3 * 64, 64 * 1.5);
    EXPECT_LT(run.azimuth_span[i].second, 36000);
    EXPECT_NEAR(static_cast<double>(h.end_stamp_ns - h.stamp_ns) * 1e-9, 0.1, 0.0002);
  }
  EXPECT_EQ(run.counters.packets_lost, 0u);
  EXPECT_EQ(run.counters.late_firings, 0u);
}

TEST(ScanAssembler, FramesOnCutAngleUnderRpmDrift) {
  StreamSpec spec;
  spec.seconds = 3.0;
  spec.rpm = [](double t) { return 300.0 + 300.0 * t; };  // 300 -> 1200 rpm
  const Assembled run = assemble(make_stream(spec));
  // Turns: integral of rpm/60 over 3 s = (300*3 + 150*9)/60 = 37.5.
  EXPECT_NEAR(static_cast<double>(run.headers.size()), 38.5, 1.0);
  double previous_size = 1e12;
  for (std::size_t i = 1; i + 1 < run.headers.size(); ++i) {
    SCOPED_TRACE("scan " + std::to_string(i));
    EXPECT_TRUE(run.headers[i].complete());
    // Never more than one turn (ros-drivers/velodyne #128), never much less.
    EXPECT_LT(run.azimuth_span[i].second, 36000);
    EXPECT_GT(run.azimuth_span[i].second, 36000 - 130);
    EXPECT_LT(static_cast<double>(run.sizes[i]), previous_size);  // faster = fewer points
    previous_size = static_cast<double>(run.sizes[i]);
  }
  EXPECT_EQ(run.counters.packets_lost, 0u);
}

TEST(ScanAssembler, CountsLostPacketsAsGaps) {
  StreamSpec spec;
  spec.seconds = 1.0;
  auto packets = make_stream(spec);
  std::mt19937 rng(7);
  std::vector<StreamPacket> lossy;
  std::size_t dropped = 0;
  for (std::size_t i = 0; i < packets.size(); ++i) {
    if (i > 10 && rng() % 20 == 0) {
      ++dropped;
      continue;
    }
    lossy.push_back(packets[i]);
  }
  const Assembled clean = assemble(packets);
  const Assembled run = assemble(lossy);
  EXPECT_EQ(run.headers.size(), clean.headers.size());
  EXPECT_NEAR(static_cast<double>(run.counters.packets_lost), static_cast<double>(dropped), 2.0);
  std::uint64_t per_scan = 0;
  for (const auto& h : run.headers) per_scan += h.packets_lost;
  EXPECT_EQ(per_scan, run.counters.packets_lost);
  for (std::size_t i = 1; i + 1 < run.headers.size(); ++i) {
    // Framed by angle despite the holes: a lost packet at the cut delays the first firing by
    // at most its 6 firings of 17.28 units.
    EXPECT_LT(run.headers[i].first_azimuth, 18 * 7);
  }
}

// Issue 31: a scan missing 20% of its packets was called complete and published as if whole.
TEST(ScanAssembler, AScanMissingMoreThanTheFloorAllowsIsNotComplete) {
  StreamSpec spec;
  spec.seconds = 1.0;
  auto packets = make_stream(spec);
  std::vector<StreamPacket> lossy;
  for (std::size_t i = 0; i < packets.size(); ++i)
    if (i < 10 || i % 5 != 0) lossy.push_back(packets[i]);  // every 5th packet lost: 20%
  const Assembled run = assemble(lossy);
  ASSERT_GE(run.headers.size(), 5u);
  for (std::size_t i = 1; i + 1 < run.headers.size(); ++i) {
    EXPECT_NEAR(run.headers[i].completeness(), 0.8, 0.03);
    EXPECT_FALSE(run.headers[i].complete()) << i;  // the default floor: 0.9
    EXPECT_TRUE(run.headers[i].below_completeness);
  }
  EXPECT_GE(run.counters.below_completeness, run.headers.size() - 2);
  // With a floor of 0.75 they are complete again.
  ScanAssemblerConfig lenient;
  lenient.min_completeness = 0.75;
  const Assembled taken = assemble(lossy, lenient);
  for (std::size_t i = 1; i + 1 < taken.headers.size(); ++i)
    EXPECT_TRUE(taken.headers[i].complete()) << i;
}

TEST(ScanAssembler, DropsDuplicatePackets) {
  StreamSpec spec;
  spec.seconds = 0.5;
  auto packets = make_stream(spec);
  std::vector<StreamPacket> doubled;
  for (std::size_t i = 0; i < packets.size(); ++i) {
    doubled.push_back(packets[i]);
    if (i % 10 == 3) doubled.push_back(packets[i]);
  }
  const Assembled clean = assemble(packets);
  const Assembled run = assemble(doubled);
  EXPECT_EQ(run.counters.duplicates, (packets.size() + 6) / 10);
  EXPECT_EQ(run.sizes, clean.sizes);
}

TEST(ScanAssembler, ToleratesReorderingAndCountsLateFirings) {
  StreamSpec spec;
  spec.seconds = 1.0;
  auto packets = make_stream(spec);
  const Assembled clean = assemble(packets);
  auto swapped = packets;
  for (std::size_t i = 5; i + 1 < swapped.size(); i += 7) std::swap(swapped[i], swapped[i + 1]);
  const Assembled run = assemble(swapped);
  ASSERT_EQ(run.headers.size(), clean.headers.size());
  std::size_t total = 0, total_clean = 0;
  for (auto s : run.sizes) total += s;
  for (auto s : clean.sizes) total_clean += s;
  // Every point is kept except firings that arrived after their scan was closed.
  EXPECT_EQ(total + run.counters.late_firings * 64, total_clean);
  EXPECT_EQ(run.counters.packets_lost, 0u);
  for (std::size_t i = 1; i + 1 < run.headers.size(); ++i) {
    EXPECT_LT(run.azimuth_span[i].second, 36000);
  }
}

TEST(ScanAssembler, HonoursANonZeroCutAngle) {
  StreamSpec spec;
  spec.seconds = 0.5;
  ScanAssemblerConfig cfg;
  cfg.cut_angle = 27000;
  const Assembled run = assemble(make_stream(spec), cfg);
  for (std::size_t i = 1; i + 1 < run.headers.size(); ++i) {
    EXPECT_GE(run.headers[i].first_azimuth, 27000);
    EXPECT_LT(run.headers[i].first_azimuth, 27018);
  }
}

TEST(ScanAssembler, SilenceClosesTheScanInProgress) {
  StreamSpec spec;
  spec.seconds = 0.25;
  auto a = make_stream(spec);
  auto b = make_stream(spec);
  for (auto& p : b) p.stamp_ns += 2'000'000'000;  // 1.75 s later the sensor resumes
  a.insert(a.end(), b.begin(), b.end());
  const Assembled run = assemble(a);
  EXPECT_EQ(run.counters.time_gaps, 1u);
  const auto closed_by_gap = std::count_if(run.headers.begin(), run.headers.end(),
                                           [](const ScanHeader& h) { return !h.ends_at_cut; });
  EXPECT_EQ(closed_by_gap, 2);  // the one before the silence and the flushed last one
}

TEST(ScanAssembler, StoppedSensorTimesOut) {
  StreamSpec spec;
  spec.seconds = 1.0;
  spec.rpm = [](double) { return 0.0; };
  const Assembled run = assemble(make_stream(spec));
  EXPECT_GE(run.counters.timeouts, 3u);
  for (const auto& h : run.headers) EXPECT_FALSE(h.complete());
}

TEST(ScanAssembler, CountsMalformedPacketsWithoutCrashing) {
  ScanAssemblerConfig cfg;
  ScanAssembler a(flat_calibration(), cfg);
  Scan scan(scan_capacity(cfg));
  a.begin(scan);
  std::mt19937 rng(3);
  std::vector<std::uint8_t> garbage(2000);
  for (int i = 0; i < 2000; ++i) {
    const std::size_t n = rng() % garbage.size();
    for (auto& b : garbage) b = static_cast<std::uint8_t>(rng());
    (void)a.add_packet(std::span(garbage.data(), i % 3 == 0 ? kPacketSize : n), i * 1000);
  }
  auto good = make_stream(StreamSpec{});
  auto bad_bank = good[0];
  bad_bank.bytes[0] = 0x12;
  auto bad_rotation = good[1];
  store_u16(bad_rotation.bytes.data() + 102, 36000);
  EXPECT_FALSE(a.add_packet(bad_bank.bytes, 0));
  EXPECT_FALSE(a.add_packet(bad_rotation.bytes, 0));
  EXPECT_FALSE(a.add_packet(std::span(good[2].bytes.data(), 1205), 0));
  const auto& c = a.counters();
  EXPECT_EQ(c.packets, 2003u);
  EXPECT_GE(c.invalid_block, 600u);
  EXPECT_GE(c.wrong_size, 1300u);
  EXPECT_EQ(c.invalid_block + c.wrong_size, c.packets);
  EXPECT_TRUE(scan.points.empty());
}

// Packets whose bank ids hold but whose blocks' rotations jump (corrupted) are dropped: the
// scans are framed as without them, none is split, nothing counts as lost or late.
TEST(ScanAssembler, PacketsWithJumpingRotationsAreDroppedAndSplitNoScan) {
  StreamSpec spec;
  spec.seconds = 1.05;
  const auto clean = make_stream(spec);
  std::vector<StreamPacket> mixed;
  std::mt19937 rng(7);
  std::uint64_t wild = 0;
  for (std::size_t i = 0; i < clean.size(); ++i) {
    mixed.push_back(clean[i]);
    if (i % 97 == 13) {  // after it, a copy with random rotations (each < 36000)
      StreamPacket w = clean[i];
      for (int b = 0; b < kBlocksPerPacket; ++b)
        store_u16(w.bytes.data() + 100 * b + 2, static_cast<std::uint16_t>(rng() % 36000));
      w.bytes[1010] ^= 0x5A;  // a distance byte: not a duplicate of the packet before it
      mixed.push_back(w);
      ++wild;
    }
  }
  const Assembled a = assemble(clean), b = assemble(mixed);
  EXPECT_EQ(b.counters.invalid_block, wild);
  ASSERT_EQ(a.headers.size(), b.headers.size());
  for (std::size_t i = 0; i < a.headers.size(); ++i) {
    EXPECT_EQ(a.headers[i].complete(), b.headers[i].complete()) << i;
    EXPECT_EQ(a.sizes[i], b.sizes[i]) << i;
  }
  EXPECT_EQ(b.counters.packets_lost, 0u);
  EXPECT_EQ(b.counters.late_firings, 0u);
}

TEST(ScanAssembler, CountsPointsBeyondCapacity) {
  StreamSpec spec;
  spec.seconds = 0.3;
  ScanAssemblerConfig cfg;
  ScanAssembler a(flat_calibration(), cfg);
  Scan small(10000);
  a.begin(small);
  std::uint64_t dropped = 0;
  for (const auto& p : make_stream(spec)) {
    if (a.add_packet(p.bytes, p.stamp_ns)) {
      EXPECT_EQ(small.points.size(), 10000u);
      EXPECT_FALSE(small.header.complete());
      dropped += small.header.points_dropped;
      a.begin(small);
    }
  }
  EXPECT_GT(dropped, 100000u);
  EXPECT_EQ(a.counters().points_dropped, dropped);
}

TEST(ScanAssembler, MakesNoHeapAllocationAfterStartUp) {
  StreamSpec spec;
  spec.seconds = 0.5;
  spec.rpm = [](double t) { return 600.0 + 600.0 * t; };
  auto packets = make_stream(spec);
  ScanAssemblerConfig cfg;
  ScanAssembler a(flat_calibration(), cfg);
  Scan s1(scan_capacity(cfg)), s2(scan_capacity(cfg));
  Scan* current = &s1;
  a.begin(*current);
  int scans = 0;
  stac::rt::testing::AllocationCounter counter;
  for (const auto& p : packets) {
    if (a.add_packet(p.bytes, p.stamp_ns)) {
      current = current == &s1 ? &s2 : &s1;
      a.begin(*current);
      ++scans;
    }
  }
  counter.stop();
  EXPECT_GE(scans, 5);
  EXPECT_EQ(counter.allocations(), 0u);
}

}  // namespace
}  // namespace stac::velodyne
