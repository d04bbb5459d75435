#include "drivers/io/tcp_stream.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <numeric>
#include <string>
#include <vector>

#include "drivers/io/pcap_reader.hpp"
#include "drivers/io/pcap_writer.hpp"
#include "rt/testing/alloc_counter.hpp"

namespace stac::io {
namespace {

std::vector<std::uint8_t> bytes(std::size_t n, std::uint8_t first = 0) {
  std::vector<std::uint8_t> v(n);
  std::iota(v.begin(), v.end(), first);
  return v;
}

TcpSegment segment(const std::vector<std::uint8_t>& stream, std::uint32_t isn, std::size_t from,
                   std::size_t n, std::uint8_t flags = kTcpAck) {
  TcpSegment s;
  s.payload = {stream.data() + from, n};
  s.seq = isn + 1 + static_cast<std::uint32_t>(from);
  s.flags = flags;
  return s;
}

// Adds each segment and collects everything delivered.
std::vector<std::uint8_t> run(TcpReassembler& r, const std::vector<TcpSegment>& segments,
                              bool finish) {
  std::vector<std::uint8_t> out;
  std::span<const std::uint8_t> chunk;
  for (const auto& s : segments) {
    r.add(s);
    while (r.next(chunk)) out.insert(out.end(), chunk.begin(), chunk.end());
  }
  if (finish) {
    r.finish();
    while (r.next(chunk)) out.insert(out.end(), chunk.begin(), chunk.end());
  }
  return out;
}

TEST(TcpReassembler, DeliversInOrderAndDropsRetransmissions) {
  const auto stream = bytes(300);
  const std::uint32_t isn = 0xFFFFFF00u;  // sequence numbers wrap inside the stream
  TcpSegment syn;
  syn.seq = isn;
  syn.flags = kTcpSyn;
  TcpReassembler r;
  const auto out = run(r,
                       {syn, segment(stream, isn, 0, 100), segment(stream, isn, 0, 100),
                        segment(stream, isn, 100, 100), segment(stream, isn, 50, 100),
                        segment(stream, isn, 150, 100), segment(stream, isn, 200, 100)},
                       false);
  EXPECT_EQ(out, stream);
  EXPECT_EQ(r.counters().retransmitted, 2u);    // 0-100 again, 50-150 after 200
  EXPECT_EQ(r.counters().overlap_bytes, 100u);  // 150-200 and 200-250 came twice
  EXPECT_EQ(r.counters().streams, 1u);
  EXPECT_EQ(r.counters().gaps, 0u);
}

TEST(TcpReassembler, OutOfOrderSegmentsWaitForTheHole) {
  const auto stream = bytes(400);
  TcpReassembler r;
  const auto out = run(r,
                       {segment(stream, 0, 0, 100), segment(stream, 0, 200, 100),
                        segment(stream, 0, 300, 100), segment(stream, 0, 50, 150)},
                       false);
  EXPECT_EQ(out, stream);
  EXPECT_EQ(r.counters().out_of_order, 2u);
  EXPECT_EQ(r.counters().overlap_bytes, 50u);
}

TEST(TcpReassembler, HoleThatNeverFillsIsSkippedAtFinishAndCounted) {
  const auto stream = bytes(400);
  TcpReassembler r;
  const auto out = run(
      r, {segment(stream, 0, 0, 100), segment(stream, 0, 300, 100), segment(stream, 0, 150, 50)},
      true);
  std::vector<std::uint8_t> expected(stream.begin(), stream.begin() + 100);
  expected.insert(expected.end(), stream.begin() + 150, stream.begin() + 200);
  expected.insert(expected.end(), stream.begin() + 300, stream.end());
  EXPECT_EQ(out, expected);
  EXPECT_EQ(r.counters().gaps, 2u);
  EXPECT_EQ(r.counters().gap_bytes, 150u);
}

TEST(TcpReassembler, FullStoreSkipsTheHoleInsteadOfGrowing) {
  const auto stream = bytes(1000);
  TcpReassembler r(2, 100);
  std::vector<TcpSegment> s = {segment(stream, 0, 0, 100), segment(stream, 0, 200, 100),
                               segment(stream, 0, 300, 100), segment(stream, 0, 400, 100)};
  const auto out = run(r, s, false);
  std::vector<std::uint8_t> expected(stream.begin(), stream.begin() + 100);
  expected.insert(expected.end(), stream.begin() + 200, stream.begin() + 500);
  EXPECT_EQ(out.size(), expected.size());
  EXPECT_EQ(out, expected);
  EXPECT_EQ(r.counters().gaps, 1u);
  EXPECT_EQ(r.counters().gap_bytes, 100u);
}

TEST(TcpReassembler, AddAndNextAllocateNothing) {
  const auto stream = bytes(1000);
  TcpReassembler r(4, 200);
  std::vector<TcpSegment> s;
  for (std::size_t at = 0; at < 1000; at += 100) s.push_back(segment(stream, 0, at, 100));
  std::swap(s[3], s[4]);
  s.push_back(segment(stream, 0, 500, 100));  // retransmitted
  std::size_t delivered = 0;
  std::span<const std::uint8_t> chunk;
  rt::testing::AllocationCounter counter;
  for (const auto& seg : s) {
    r.add(seg);
    while (r.next(chunk)) delivered += chunk.size();
  }
  counter.stop();
  EXPECT_EQ(counter.allocations(), 0u);
  EXPECT_EQ(delivered, 1000u);
}

TEST(TcpReassembler, SynStartsANewStream) {
  const auto stream = bytes(200);
  TcpReassembler r;
  TcpSegment syn;
  syn.seq = 5000;
  syn.flags = kTcpSyn;
  EXPECT_TRUE(r.add(segment(stream, 0, 0, 100)));
  EXPECT_FALSE(r.add(segment(stream, 0, 100, 50)));
  EXPECT_TRUE(r.add(syn));
  EXPECT_FALSE(r.add(segment(stream, 5000, 0, 10)));
  std::span<const std::uint8_t> chunk;
  ASSERT_TRUE(r.next(chunk));
  EXPECT_EQ(chunk.size(), 10u);
  EXPECT_EQ(r.counters().streams, 2u);
}

TEST(PcapReader, ReadsTcpSegmentsWrittenByPcapWriter) {
  const auto path = std::filesystem::temp_directory_path() / "stac_io_tcp.pcap";
  const auto stream = bytes(100);
  {
    auto w = PcapWriter::open(path);
    ASSERT_TRUE(w);
    TcpSegment s = segment(stream, 77, 0, 60);
    s.src_ip = 0xC0A80203;
    s.dst_ip = 0xC0A80201;
    s.src_port = 5602;
    s.dst_port = 40000;
    s.stamp_ns = 1'500'000'000'123;
    ASSERT_TRUE(w->write_tcp(s));
    Datagram d;
    d.payload = stream;
    d.dst_port = 5600;
    ASSERT_TRUE(w->write_udp(d));
    TcpSegment other = s;
    other.src_port = 5601;
    ASSERT_TRUE(w->write_tcp(other));
    ASSERT_TRUE(w->close());
  }
  auto r = PcapReader::open(path, {}, TcpFilter{.src_port = 5602, .dst_port = {}});
  ASSERT_TRUE(r) << r.error().message;
  TcpSegment s;
  ASSERT_TRUE(r->next_tcp(s));
  EXPECT_EQ(s.seq, 78u);
  EXPECT_EQ(s.flags, kTcpAck);
  EXPECT_EQ(s.src_ip, 0xC0A80203u);
  EXPECT_EQ(s.dst_port, 40000);
  EXPECT_EQ(s.stamp_ns, 1'500'000'000'123);
  EXPECT_EQ(std::vector<std::uint8_t>(s.payload.begin(), s.payload.end()),
            std::vector<std::uint8_t>(stream.begin(), stream.begin() + 60));
  EXPECT_FALSE(r->next_tcp(s));
  EXPECT_EQ(r->counters().segments, 1u);
  EXPECT_EQ(r->counters().non_tcp, 1u);
  EXPECT_EQ(r->counters().filtered_out, 1u);
  // The UDP reader of the same file still sees only its datagram.
  auto u = PcapReader::open(path);
  ASSERT_TRUE(u);
  Datagram d;
  ASSERT_TRUE(u->next(d));
  EXPECT_EQ(d.payload.size(), 100u);
  EXPECT_FALSE(u->next(d));
  EXPECT_EQ(u->counters().non_udp, 2u);
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace stac::io
