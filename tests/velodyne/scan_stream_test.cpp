#include "drivers/velodyne/scan_stream.hpp"

#include <gtest/gtest.h>

#include <thread>

#include "rt/testing/alloc_counter.hpp"
#include "synthetic_stream.hpp"

namespace stac::velodyne {
namespace {

using stac::testing::flat_calibration;

TEST(ScanStream, StampsPointsAtTheirFiringTimeNotTheReceiveTime) {
  testing::StreamSpec spec;
  spec.seconds = 0.25;
  const auto packets = testing::make_stream(spec);
  ScanStream stream(flat_calibration(), ScanAssemblerConfig{}, 4);
  const std::int64_t span = stream.assembler().decoder().packet_span_ns(false);
  // Receive time = first firing + span: the stream must undo that.
  for (const auto& p : packets) (void)stream.add_packet(p.bytes, p.stamp_ns + span);
  const Scan* first = stream.take();
  ASSERT_NE(first, nullptr);
  EXPECT_EQ(first->header.stamp_ns, spec.start_ns);
  stream.release();
}

TEST(ScanStream, DropsTheNewestScanWhenTheConsumerFallsBehind) {
  testing::StreamSpec spec;
  spec.seconds = 1.05;  // 11 cut crossings
  ScanStream stream(flat_calibration(), ScanAssemblerConfig{}, 3);
  int completed = 0;
  for (const auto& p : testing::make_stream(spec))
    completed += stream.add_packet(p.bytes, p.stamp_ns) ? 1 : 0;
  EXPECT_EQ(completed, 10);  // cut crossings at 0.066 s + k * 0.1 s
  EXPECT_EQ(stream.assembler().counters().scans, 10u);
  // Nobody consumed: two slots were published, the rest dropped.
  EXPECT_EQ(stream.scans_published(), 2u);
  EXPECT_EQ(stream.scans_dropped(), 8u);
  const Scan* s = stream.take();
  ASSERT_NE(s, nullptr);
  EXPECT_EQ(s->header.sequence, 0u);  // the oldest ones survive, untouched
  stream.release();
  s = stream.take();
  ASSERT_NE(s, nullptr);
  EXPECT_EQ(s->header.sequence, 1u);
}

TEST(ScanStream, HandsScansToAnotherThreadWithoutLossOrAllocation) {
  testing::StreamSpec spec;
  spec.seconds = 2.0;
  spec.rpm = [](double t) { return 600.0 + 300.0 * t; };
  const auto packets = testing::make_stream(spec);
  ScanStream stream(flat_calibration(), ScanAssemblerConfig{}, 4);
  std::atomic<bool> done{false};
  std::atomic<std::uint64_t> consumed{0};
  std::vector<std::uint64_t> sequences;
  sequences.reserve(100);
  std::thread consumer([&] {
    while (true) {
      if (const Scan* s = stream.take()) {
        sequences.push_back(s->header.sequence);
        stream.release();
        consumed.fetch_add(1);
      } else if (done.load()) {
        if (stream.take() == nullptr) break;
      } else {
        std::this_thread::yield();
      }
    }
  });
  rt::testing::AllocationCounter counter;
  std::uint64_t completed = 0;
  for (const auto& p : packets) {
    completed += stream.add_packet(p.bytes, p.stamp_ns) ? 1 : 0;
    // Pace like the sensor would, roughly, so the consumer keeps up.
    if (stream.scans_published() - consumed.load() > 2) std::this_thread::yield();
  }
  completed += stream.finish() ? 1 : 0;
  counter.stop();
  done = true;
  consumer.join();
  EXPECT_EQ(counter.allocations(), 0u);
  EXPECT_EQ(stream.scans_published() + stream.scans_dropped(), completed);
  ASSERT_EQ(sequences.size(), stream.scans_published());
  for (std::size_t i = 1; i < sequences.size(); ++i) EXPECT_GT(sequences[i], sequences[i - 1]);
}

}  // namespace
}  // namespace stac::velodyne
