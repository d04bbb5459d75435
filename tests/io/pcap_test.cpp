#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <vector>

#include "drivers/io/pcap_reader.hpp"
#include "drivers/io/pcap_writer.hpp"
#include "rt/testing/alloc_counter.hpp"
#include "shared_data.hpp"

namespace stac::io {
namespace {

constexpr const char* kApplanix = "applanix/clearpath_basic_data_smoke.pcap";

std::filesystem::path temp(const std::string& name) {
  return std::filesystem::temp_directory_path() / ("stac_io_" + name);
}

// A classic pcap file with nanosecond magic, written byte by byte, so link types the writer
// does not produce can be tested.
void write_raw_pcap(const std::filesystem::path& path, std::uint32_t link,
                    const std::vector<std::vector<std::uint8_t>>& frames) {
  std::ofstream f(path, std::ios::binary);
  auto u32 = [&](std::uint32_t v) { f.write(reinterpret_cast<const char*>(&v), 4); };
  auto u16 = [&](std::uint16_t v) { f.write(reinterpret_cast<const char*>(&v), 2); };
  u32(0xA1B23C4D);
  u16(2);
  u16(4);
  u32(0);
  u32(0);
  u32(65535);
  u32(link);
  std::uint32_t t = 1000;
  for (const auto& fr : frames) {
    u32(t++);
    u32(5);
    u32(static_cast<std::uint32_t>(fr.size()));
    u32(static_cast<std::uint32_t>(fr.size()));
    f.write(reinterpret_cast<const char*>(fr.data()), static_cast<std::streamsize>(fr.size()));
  }
}

// Appends element by element (vector::insert trips GCC 12's -Warray-bounds false positive).
void append(std::vector<std::uint8_t>& to, const std::vector<std::uint8_t>& from) {
  for (std::uint8_t b : from) to.push_back(b);
}

// IPv4 + UDP with the given payload; `flags_frag` goes into bytes 6-7 of the IPv4 header.
std::vector<std::uint8_t> ipv4_udp(std::uint16_t dst_port, const std::vector<std::uint8_t>& payload,
                                   std::uint16_t flags_frag = 0x4000) {
  const auto udp_len = static_cast<std::uint16_t>(8 + payload.size());
  const auto total = static_cast<std::uint16_t>(20 + udp_len);
  std::vector<std::uint8_t> p = {0x45,
                                 0,
                                 static_cast<std::uint8_t>(total >> 8),
                                 static_cast<std::uint8_t>(total),
                                 0,
                                 1,
                                 static_cast<std::uint8_t>(flags_frag >> 8),
                                 static_cast<std::uint8_t>(flags_frag),
                                 64,
                                 17,
                                 0,
                                 0,
                                 10,
                                 0,
                                 0,
                                 1,
                                 10,
                                 0,
                                 0,
                                 2,
                                 0x12,
                                 0x34,
                                 static_cast<std::uint8_t>(dst_port >> 8),
                                 static_cast<std::uint8_t>(dst_port),
                                 static_cast<std::uint8_t>(udp_len >> 8),
                                 static_cast<std::uint8_t>(udp_len),
                                 0,
                                 0};
  append(p, payload);
  return p;
}

TEST(PcapReader, ReadsTheRealApplanixCapture) {
  STAC_REQUIRE_SHARED_DATA(kApplanix);
  auto r = PcapReader::open(stac::testing::shared_data(kApplanix));
  ASSERT_TRUE(r) << r.error().message;
  Datagram d;
  int n = 0;
  std::int64_t first = 0, last = 0;
  while (r->next(d)) {
    if (n == 0) first = d.stamp_ns;
    last = d.stamp_ns;
    ++n;
    EXPECT_EQ(d.src_ip, 0xC0A80203u);  // 192.168.2.3
    EXPECT_EQ(d.dst_ip, 0xC0A802FFu);  // 192.168.2.255
    EXPECT_EQ(d.src_port, 65534);
    EXPECT_EQ(d.dst_port, 5600);
    ASSERT_GE(d.payload.size(), 4u);
    EXPECT_EQ(std::string(reinterpret_cast<const char*>(d.payload.data()), 4).substr(0, 1), "$");
  }
  EXPECT_TRUE(r->error().empty()) << r->error();
  EXPECT_EQ(n, 241);
  EXPECT_NEAR(static_cast<double>(last - first) * 1e-9, 80.0, 2.0);  // an 80 s capture
}

// The same capture from memory (fuzzing reads captures so): the same datagrams, byte for byte;
// bytes that are not a capture, and no bytes, are named errors.
TEST(PcapReader, ACaptureInMemoryReadsAsItsFile) {
  STAC_REQUIRE_SHARED_DATA(kApplanix);
  const auto path = stac::testing::shared_data(kApplanix);
  std::ifstream in(path, std::ios::binary);
  const std::vector<std::uint8_t> bytes{std::istreambuf_iterator<char>(in),
                                        std::istreambuf_iterator<char>()};
  auto file = PcapReader::open(path);
  auto memory = PcapReader::open_memory(bytes, "memory.pcap");
  ASSERT_TRUE(file && memory) << (memory ? "" : memory.error().message);
  Datagram a, b;
  int n = 0;
  while (file->next(a)) {
    ASSERT_TRUE(memory->next(b)) << n;
    EXPECT_EQ(a.stamp_ns, b.stamp_ns);
    EXPECT_TRUE(std::equal(a.payload.begin(), a.payload.end(), b.payload.begin(), b.payload.end()));
    ++n;
  }
  EXPECT_FALSE(memory->next(b));
  EXPECT_EQ(n, 241);
  const std::string text = "this is not a capture, just some text that goes on for a while";
  auto garbage = PcapReader::open_memory(
      {reinterpret_cast<const std::uint8_t*>(text.data()), text.size()}, "memory.pcap");
  ASSERT_FALSE(garbage);
  EXPECT_EQ(garbage.error().message.rfind("memory.pcap: cannot read as a pcap capture", 0), 0u)
      << garbage.error().message;
  auto empty = PcapReader::open_memory({}, "empty.pcap");
  ASSERT_FALSE(empty);
  EXPECT_EQ(empty.error().message.rfind("empty.pcap: ", 0), 0u);
}

TEST(PcapReader, FiltersByPort) {
  STAC_REQUIRE_SHARED_DATA(kApplanix);
  auto r = PcapReader::open(stac::testing::shared_data(kApplanix),
                            PcapFilter{.udp_dst_port = 2368, .udp_src_port = {}});
  ASSERT_TRUE(r);
  Datagram d;
  EXPECT_FALSE(r->next(d));
  EXPECT_EQ(r->counters().filtered_out, 241u);
}

TEST(PcapWriter, RoundTripsPayloadsStampsAndAddresses) {
  const auto path = temp("roundtrip.pcap");
  {
    auto w = PcapWriter::open(path);
    ASSERT_TRUE(w) << w.error().message;
    for (int i = 0; i < 100; ++i) {
      std::vector<std::uint8_t> payload(static_cast<std::size_t>(1 + i * 13),
                                        static_cast<std::uint8_t>(i));
      Datagram d;
      d.payload = payload;
      d.stamp_ns = 1'700'000'000'123'456'789 + i * 1'000'001;
      d.src_ip = 0xC0A8032B;
      d.dst_ip = 0xFFFFFFFF;
      d.src_port = static_cast<std::uint16_t>(1000 + i);
      d.dst_port = 2368;
      ASSERT_TRUE(w->write_udp(d));
    }
    ASSERT_TRUE(w->close());
  }
  auto r = PcapReader::open(path);
  ASSERT_TRUE(r) << r.error().message;
  Datagram d;
  int i = 0;
  while (r->next(d)) {
    EXPECT_EQ(d.payload.size(), static_cast<std::size_t>(1 + i * 13));
    EXPECT_EQ(d.payload[0], static_cast<std::uint8_t>(i));
    EXPECT_EQ(d.stamp_ns, 1'700'000'000'123'456'789 + i * 1'000'001);  // nanoseconds kept
    EXPECT_EQ(d.src_ip, 0xC0A8032Bu);
    EXPECT_EQ(d.src_port, 1000 + i);
    EXPECT_EQ(d.dst_port, 2368);
    ++i;
  }
  EXPECT_EQ(i, 100);
  EXPECT_TRUE(r->error().empty());
}

TEST(PcapReader, ReadsLinuxCookedVlanAndRawIpFrames) {
  const std::vector<std::uint8_t> payload = {1, 2, 3, 4, 5};
  const auto ip = ipv4_udp(2368, payload);
  std::vector<std::uint8_t> sll(16, 0);
  sll[14] = 0x08;  // protocol 0x0800
  append(sll, ip);
  std::vector<std::uint8_t> sll2(20, 0);
  sll2[0] = 0x08;
  append(sll2, ip);
  std::vector<std::uint8_t> vlan(12, 0xAA);
  append(vlan, {0x81, 0x00, 0x00, 0x05, 0x08, 0x00});  // 802.1Q tag, then IPv4
  append(vlan, ip);
  const std::pair<std::uint32_t, std::vector<std::uint8_t>> cases[] = {
      {113, sll}, {276, sll2}, {1, vlan}, {101, ip}};
  for (const auto& [link, frame] : cases) {
    SCOPED_TRACE("link type " + std::to_string(link));
    const auto path = temp("link" + std::to_string(link) + ".pcap");
    write_raw_pcap(path, link, {frame, frame});
    auto r = PcapReader::open(path);
    ASSERT_TRUE(r) << r.error().message;
    Datagram d;
    ASSERT_TRUE(r->next(d));
    EXPECT_EQ(d.dst_port, 2368);
    ASSERT_EQ(d.payload.size(), payload.size());
    EXPECT_EQ(d.payload[4], 5);
    EXPECT_EQ(d.stamp_ns, 1000LL * 1'000'000'000 + 5);
    EXPECT_TRUE(r->next(d));
    EXPECT_FALSE(r->next(d));
  }
}

TEST(PcapReader, CountsFragmentsTruncatedFramesAndOtherProtocols) {
  const std::vector<std::uint8_t> payload(100, 7);
  auto fragment = ipv4_udp(2368, payload, 0x2000);  // more fragments
  auto truncated = ipv4_udp(2368, payload);
  truncated.resize(60);  // captured shorter than the UDP length
  auto tcp = ipv4_udp(2368, payload);
  tcp[9] = 6;
  std::vector<std::uint8_t> ipv6 = {0x60, 0, 0, 0};
  const auto path = temp("counted.pcap");
  write_raw_pcap(path, 101, {fragment, truncated, tcp, ipv6, ipv4_udp(2368, payload)});
  auto r = PcapReader::open(path);
  ASSERT_TRUE(r);
  Datagram d;
  ASSERT_TRUE(r->next(d));
  EXPECT_EQ(d.payload.size(), 100u);
  EXPECT_FALSE(r->next(d));
  const PcapCounters& c = r->counters();
  EXPECT_EQ(c.frames, 5u);
  EXPECT_EQ(c.fragments, 1u);
  EXPECT_EQ(c.truncated_frame, 1u);
  EXPECT_EQ(c.non_udp, 1u);
  EXPECT_EQ(c.non_ipv4, 1u);
  EXPECT_EQ(c.datagrams, 1u);
}

TEST(PcapReader, ATruncatedFileEndsWithAClearError) {
  STAC_REQUIRE_SHARED_DATA(kApplanix);
  const auto path = temp("cut.pcap");
  std::filesystem::copy_file(stac::testing::shared_data(kApplanix), path,
                             std::filesystem::copy_options::overwrite_existing);
  std::filesystem::resize_file(path, 50'000);  // in the middle of a record
  auto r = PcapReader::open(path);
  ASSERT_TRUE(r);
  Datagram d;
  int n = 0;
  while (r->next(d)) ++n;
  EXPECT_GT(n, 10);
  EXPECT_LT(n, 241);
  EXPECT_NE(r->error().find(path.string()), std::string::npos) << r->error();
  EXPECT_NE(r->error().find("truncated"), std::string::npos) << r->error();
  EXPECT_FALSE(r->next(d));  // stays stopped
}

TEST(PcapReader, GarbageAndMissingFilesGiveClearErrors) {
  const auto path = temp("garbage.pcap");
  std::ofstream(path) << "this is not a capture, just some text that goes on for a while";
  auto r = PcapReader::open(path);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find(path.string()), std::string::npos);
  auto missing = PcapReader::open(temp("no_such_file.pcap"));
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().message.find("no_such_file.pcap"), std::string::npos);
}

TEST(PcapReader, NextAllocatesNothing) {
  STAC_REQUIRE_SHARED_DATA(kApplanix);
  auto r = PcapReader::open(stac::testing::shared_data(kApplanix));
  ASSERT_TRUE(r);
  Datagram d;
  ASSERT_TRUE(r->next(d));  // libpcap sizes its buffer at open; the first read is steady state
  rt::testing::AllocationCounter counter;
  int n = 1;
  while (r->next(d)) ++n;
  counter.stop();
  EXPECT_EQ(n, 241);
  EXPECT_EQ(counter.allocations(), 0u);
}

}  // namespace
}  // namespace stac::io
