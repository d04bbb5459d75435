#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <iterator>
#include <random>
#include <set>
#include <type_traits>
#include <vector>

#include "applanix/applanix_stream.hpp"
#include "drivers/applanix/stream_parser.hpp"
#include "drivers/io/pcap_reader.hpp"
#include "rt/testing/alloc_counter.hpp"
#include "shared_data.hpp"
#include "test_paths.hpp"

namespace stac::applanix {
namespace {

using testing::EncodedMessage;

constexpr const char* kCapture = "applanix/clearpath_basic_data_smoke.pcap";

static_assert(std::is_nothrow_invocable_v<decltype(&StreamParser::next), StreamParser&, Parsed&>);
static_assert(std::is_nothrow_invocable_v<decltype(&StreamParser::feed), StreamParser&,
                                          std::span<const std::uint8_t>>);

// What the parser reports for one message, comparable across runs.
struct Seen {
  bool is_group = true;
  std::uint16_t id = 0;
  std::vector<std::uint8_t> bytes;
  bool operator==(const Seen&) const = default;
};

Seen seen_of(const Parsed& p) {
  Seen s;
  s.is_group = !std::holds_alternative<Message>(p.content);
  s.id = static_cast<std::uint16_t>(p.bytes[4] | (p.bytes[5] << 8));
  s.bytes.assign(p.bytes.begin(), p.bytes.end());
  return s;
}

std::vector<Seen> drain(StreamParser& parser) {
  std::vector<Seen> out;
  Parsed p;
  while (parser.next(p)) out.push_back(seen_of(p));
  return out;
}

std::vector<Seen> parse_in_chunks(const std::vector<std::uint8_t>& stream, std::mt19937& rng,
                                  std::size_t max_chunk, StreamParser& parser) {
  std::vector<Seen> out;
  std::size_t at = 0;
  while (at < stream.size()) {
    const std::size_t n = std::min<std::size_t>(1 + rng() % max_chunk, stream.size() - at);
    parser.feed({stream.data() + at, n});
    for (auto& s : drain(parser)) out.push_back(std::move(s));
    at += n;
  }
  return out;
}

std::vector<Seen> expected_of(const std::vector<EncodedMessage>& messages) {
  std::vector<Seen> out;
  for (const auto& m : messages) out.push_back({m.is_group, m.id, m.bytes});
  return out;
}

std::vector<EncodedMessage> random_messages(std::mt19937& rng, int count) {
  std::vector<EncodedMessage> out;
  for (int i = 0; i < count; ++i) out.push_back(testing::random_message(rng));
  return out;
}

std::vector<std::uint8_t> concat(const std::vector<EncodedMessage>& messages) {
  std::vector<std::uint8_t> out;
  for (const auto& m : messages) out.insert(out.end(), m.bytes.begin(), m.bytes.end());
  return out;
}

TEST(ApplanixGroups, WireSizesMatchTheIcd) {
  std::vector<std::uint8_t> buf(kMaxMessageBytes);
  EXPECT_EQ(encode_group1(Group1{}, TimeDistance{}, buf), 140u);
  EXPECT_EQ(encode_group2(Group2{}, TimeDistance{}, buf), 88u);
  Group3 g3;
  g3.channel_count = 19;
  EXPECT_EQ(encode_group3(g3, TimeDistance{}, buf), 464u);  // 76 + 20 * 19 + 8, as in the capture
  EXPECT_EQ(encode_message(0, 1, {}, buf), 16u);
  EXPECT_EQ(encode_group1(Group1{}, TimeDistance{}, std::span<std::uint8_t>(buf).first(139)), 0u);
}

TEST(ApplanixGroups, EncodedGroup1HasIcdOffsetsPaddingAndChecksum) {
  Group1 g;
  g.latitude_deg = 44.5;
  g.heading_deg = 270.25;
  g.alignment_status = 4;
  TimeDistance t;
  t.time1_s = 1234.5;
  t.time_types = 0x21;
  std::uint8_t b[140];
  ASSERT_EQ(encode_group1(g, t, b), 140u);
  EXPECT_EQ(std::memcmp(b, "$GRP\x01\x00\x84\x00", 8), 0);  // byte count 132
  double v = 0;
  std::memcpy(&v, b + 8, 8);
  EXPECT_EQ(v, 1234.5);
  EXPECT_EQ(b[32], 0x21);
  std::memcpy(&v, b + 34, 8);
  EXPECT_EQ(v, 44.5);
  std::memcpy(&v, b + 86, 8);
  EXPECT_EQ(v, 270.25);
  EXPECT_EQ(b[134], 4);
  EXPECT_EQ(b[135], 0);
  EXPECT_EQ(b[138], '$');
  EXPECT_EQ(b[139], '#');
  EXPECT_EQ(word_sum(b), 0);
  EXPECT_TRUE(is_valid_message(b));
}

TEST(ApplanixGroups, RandomRoundTripsAreExact) {
  std::mt19937 rng(11);
  std::vector<std::uint8_t> buf(kMaxMessageBytes);
  for (int i = 0; i < 200; ++i) {
    const TimeDistance t = testing::random_time(rng);
    const Group1 g1 = testing::random_group1(rng);
    const Group2 g2 = testing::random_group2(rng);
    const Group3 g3 = testing::random_group3(rng, rng() % 40);
    std::vector<std::uint8_t> body(rng() % 64);
    for (auto& b : body) b = static_cast<std::uint8_t>(rng());
    std::vector<std::uint8_t> stream;
    auto add = [&](std::size_t n) {
      ASSERT_GT(n, 0u);
      ASSERT_TRUE(is_valid_message({buf.data(), n}));
      stream.insert(stream.end(), buf.begin(), buf.begin() + static_cast<std::ptrdiff_t>(n));
    };
    add(encode_group1(g1, t, buf));
    add(encode_group2(g2, t, buf));
    add(encode_group3(g3, t, buf));
    add(encode_message(42, 7, body, buf));
    StreamParser parser;
    parser.feed(stream);
    Parsed p;
    ASSERT_TRUE(parser.next(p));
    const auto* d1 = std::get_if<Group1>(&p.content);
    ASSERT_NE(d1, nullptr);
    EXPECT_TRUE(*d1 == g1);  // every field, exactly
    EXPECT_EQ(p.time.time1_s, t.time1_s);
    EXPECT_EQ(p.time.time2_s, t.time2_s);
    EXPECT_EQ(p.time.distance_tag_m, t.distance_tag_m);
    EXPECT_EQ(p.time.time_types, t.time_types);
    EXPECT_EQ(p.time.distance_type, t.distance_type);
    ASSERT_TRUE(parser.next(p));
    const auto* d2 = std::get_if<Group2>(&p.content);
    ASSERT_NE(d2, nullptr);
    EXPECT_TRUE(*d2 == g2);
    ASSERT_TRUE(parser.next(p));
    const auto* d3 = std::get_if<Group3>(&p.content);
    ASSERT_NE(d3, nullptr);
    ASSERT_EQ(d3->channel_count, g3.channel_count);
    for (std::size_t c = 0; c < g3.channel_count; ++c) {
      EXPECT_TRUE(d3->channels[c] == g3.channels[c]) << "channel " << c;
    }
    EXPECT_EQ(d3->solution_status, g3.solution_status);
    EXPECT_EQ(d3->sv_count, g3.sv_count);
    EXPECT_EQ(d3->hdop, g3.hdop);
    EXPECT_EQ(d3->vdop, g3.vdop);
    EXPECT_EQ(d3->dgps_latency_s, g3.dgps_latency_s);
    EXPECT_EQ(d3->dgps_reference_id, g3.dgps_reference_id);
    EXPECT_EQ(d3->gps_week, g3.gps_week);
    EXPECT_EQ(d3->gps_utc_offset_s, g3.gps_utc_offset_s);
    EXPECT_EQ(d3->message_latency_s, g3.message_latency_s);
    EXPECT_EQ(d3->geoid_separation_m, g3.geoid_separation_m);
    EXPECT_EQ(d3->receiver_type, g3.receiver_type);
    EXPECT_EQ(d3->status, g3.status);
    ASSERT_TRUE(parser.next(p));
    const auto* m = std::get_if<Message>(&p.content);
    ASSERT_NE(m, nullptr);
    EXPECT_EQ(m->id, 42);
    EXPECT_EQ(m->transaction, 7);
    ASSERT_GE(m->body.size(), body.size());
    ASSERT_LE(m->body.size(), body.size() + 3);  // pad
    EXPECT_TRUE(std::equal(body.begin(), body.end(), m->body.begin()));
    EXPECT_FALSE(parser.next(p));
    EXPECT_EQ(parser.counters().groups, 3u);
    EXPECT_EQ(parser.counters().control_messages, 1u);
    EXPECT_EQ(parser.counters().garbage_bytes, 0u);
  }
}

TEST(ApplanixStreamParser, AnyChunkingGivesTheSameMessages) {
  std::mt19937 rng(3);
  const auto messages = random_messages(rng, 300);
  const auto stream = concat(messages);
  const auto expected = expected_of(messages);
  for (const std::size_t max_chunk : {std::size_t{1}, std::size_t{2}, std::size_t{7},
                                      std::size_t{64}, std::size_t{1500}, stream.size()}) {
    StreamParser parser;
    EXPECT_EQ(parse_in_chunks(stream, rng, max_chunk, parser), expected)
        << "chunks up to " << max_chunk;
    EXPECT_EQ(parser.counters().garbage_bytes, 0u);
    EXPECT_EQ(parser.counters().groups + parser.counters().control_messages, messages.size());
  }
}

TEST(ApplanixStreamParser, ResynchronisesAfterGarbageAndCountsIt) {
  std::mt19937 rng(5);
  const auto messages = random_messages(rng, 200);
  std::vector<std::uint8_t> stream;
  std::uint64_t garbage = 0;
  for (const auto& m : messages) {
    // Garbage that looks like the start of a message as well as random bytes.
    std::vector<std::uint8_t> junk(rng() % 40);
    for (auto& b : junk) b = static_cast<std::uint8_t>(rng());
    if (rng() % 2 == 0) junk.insert(junk.end(), {'$', 'G', 'R', 'P', 0x01, 0x00, 0x84, 0x00});
    if (rng() % 3 == 0) junk.insert(junk.end(), {'$', 'M', 'S'});
    if (rng() % 3 == 0) junk.insert(junk.end(), {'$', '$'});
    garbage += junk.size();
    stream.insert(stream.end(), junk.begin(), junk.end());
    stream.insert(stream.end(), m.bytes.begin(), m.bytes.end());
  }
  StreamParser parser;
  EXPECT_EQ(parse_in_chunks(stream, rng, 100, parser), expected_of(messages));
  EXPECT_EQ(parser.counters().garbage_bytes, garbage);
  EXPECT_GT(parser.counters().bad_checksum + parser.counters().bad_terminator, 0u);
}

TEST(ApplanixStreamParser, CorruptedMessageIsRejectedAndItsNeighboursKept) {
  std::mt19937 rng(8);
  auto messages = random_messages(rng, 50);
  messages[20].bytes[messages[20].bytes.size() / 2] ^= 0x10;  // inside a message
  auto expected = expected_of(messages);
  expected.erase(expected.begin() + 20);
  StreamParser parser;
  EXPECT_EQ(parse_in_chunks(concat(messages), rng, 33, parser), expected);
  EXPECT_EQ(parser.counters().bad_checksum, 1u);
  EXPECT_EQ(parser.counters().garbage_bytes, messages[20].bytes.size());
}

TEST(ApplanixStreamParser, BadChecksumLengthAndOversizeAreCounted) {
  std::vector<std::uint8_t> buf(kMaxMessageBytes);
  const std::size_t n = encode_group1(Group1{}, TimeDistance{}, buf);
  std::vector<std::uint8_t> good(buf.begin(), buf.begin() + static_cast<std::ptrdiff_t>(n));
  auto bad_sum = good;
  bad_sum[136] ^= 0x01;
  auto bad_len = good;
  bad_len[6] = 130;  // byte count 130: total 138 is not a multiple of 4
  auto no_end = good;
  no_end[139] = '!';
  std::vector<std::uint8_t> big(good.begin(), good.begin() + 8);
  big[6] = 0xF8;  // byte count 8184 + 8 > the 4096-byte buffer below
  big[7] = 0x1F;
  std::vector<std::uint8_t> stream;
  for (const auto* part : {&bad_sum, &good, &bad_len, &good, &no_end, &big, &good}) {
    stream.insert(stream.end(), part->begin(), part->end());
  }
  StreamParser parser(4096);
  parser.feed(stream);
  const auto seen = drain(parser);
  EXPECT_EQ(seen.size(), 3u);
  EXPECT_EQ(parser.counters().bad_checksum, 1u);
  EXPECT_EQ(parser.counters().bad_length, 1u);
  EXPECT_EQ(parser.counters().bad_terminator, 1u);
  EXPECT_EQ(parser.counters().oversize, 1u);
  EXPECT_EQ(parser.counters().garbage_bytes, 3 * 140u + 8u);
}

TEST(ApplanixStreamParser, TruncatedEndIsCountedNotEmitted) {
  std::mt19937 rng(13);
  const auto messages = random_messages(rng, 10);
  auto stream = concat(messages);
  stream.resize(stream.size() - 10);
  StreamParser parser;
  EXPECT_EQ(parse_in_chunks(stream, rng, 50, parser).size(), messages.size() - 1);
  parser.end_of_stream();
  EXPECT_EQ(parser.counters().truncated, 1u);
  EXPECT_EQ(parser.counters().garbage_bytes, messages.back().bytes.size() - 10);
  // The next stream starts clean.
  parser.feed(messages.front().bytes);
  EXPECT_EQ(drain(parser).size(), 1u);
}

TEST(ApplanixStreamParser, MalformedGroupLayoutIsCounted) {
  // A valid frame with id 1 but the length of Group 2: framing passes, the layout does not.
  std::vector<std::uint8_t> buf(kMaxMessageBytes);
  std::vector<std::uint8_t> data(48);
  const std::size_t n = encode_group(1, TimeDistance{}, data, buf);
  StreamParser parser;
  parser.feed({buf.data(), n});
  Parsed p;
  EXPECT_FALSE(parser.next(p));
  EXPECT_EQ(parser.counters().malformed, 1u);
  EXPECT_EQ(parser.counters().groups, 0u);
}

TEST(ApplanixStreamParser, GpsWeekFromGroup3GivesAbsoluteTimeAcrossTheWeekRollover) {
  std::vector<std::uint8_t> stream(kMaxMessageBytes * 3);
  std::span<std::uint8_t> out(stream);
  Group3 g3;
  g3.gps_week = 2000;
  g3.gps_utc_offset_s = 18.0;
  TimeDistance t;
  t.time_types = 0x01;  // time1 GPS
  t.time1_s = 604799.5;
  std::size_t at = encode_group3(g3, t, out);
  t.time1_s = 604799.75;
  at += encode_group1(Group1{}, t, out.subspan(at));
  t.time1_s = 0.25;  // Sunday midnight passed, no new Group 3 yet
  at += encode_group1(Group1{}, t, out.subspan(at));
  t.time_types = 0x02;  // time1 UTC
  t.time1_s = 1.0;
  at += encode_group1(Group1{}, t, out.subspan(at));
  t.time_types = 0x00;  // POS time: no absolute time
  at += encode_group1(Group1{}, t, out.subspan(at));

  StreamParser parser;
  EXPECT_FALSE(parser.gps_week());
  parser.feed(out.first(at));
  Parsed p;
  ASSERT_TRUE(parser.next(p));
  EXPECT_EQ(parser.gps_week(), 2000u);
  constexpr std::int64_t kWeekNs = 604'800'000'000'000;
  ASSERT_TRUE(parser.next(p));
  EXPECT_EQ(p.time1_gps_ns, 2000 * kWeekNs + 604'799'750'000'000);
  ASSERT_TRUE(parser.next(p));
  EXPECT_EQ(p.time1_gps_ns, 2001 * kWeekNs + 250'000'000);
  ASSERT_TRUE(parser.next(p));
  EXPECT_EQ(p.time1_gps_ns, 2001 * kWeekNs + 19'000'000'000);  // UTC + 18 s
  ASSERT_TRUE(parser.next(p));
  EXPECT_FALSE(p.time1_gps_ns);
}

TEST(ApplanixStreamParser, SteadyStateAllocatesNothing) {
  std::mt19937 rng(21);
  const auto stream = concat(random_messages(rng, 200));
  StreamParser parser;
  Parsed p;
  std::size_t count = 0;
  rt::testing::AllocationCounter counter;
  for (std::size_t at = 0; at < stream.size(); at += 37) {
    parser.feed({stream.data() + at, std::min<std::size_t>(37, stream.size() - at)});
    while (parser.next(p)) ++count;
  }
  counter.stop();
  EXPECT_EQ(counter.allocations(), 0u);
  EXPECT_EQ(count, 200u);
}

// The real POS LV capture: every UDP payload is one or more whole messages.
TEST(ApplanixRealCapture, LastGroup1AndGroupIdsMatchTheReadme) {
  STAC_REQUIRE_SHARED_DATA(kCapture);
  auto reader =
      io::PcapReader::open(testing::shared_data(kCapture),
                           io::PcapFilter{.udp_dst_port = kPortDisplay, .udp_src_port = {}});
  ASSERT_TRUE(reader) << reader.error().message;
  StreamParser parser;
  io::Datagram d;
  Parsed p;
  Group1 last;
  TimeDistance last_time;
  std::optional<std::int64_t> last_gps_ns;
  std::set<std::uint16_t> message_ids;
  Group3 g3;
  std::size_t datagrams = 0, g1 = 0;
  while (reader->next(d)) {
    ++datagrams;
    parser.feed(d.payload);
    while (parser.next(p)) {
      if (const auto* g = std::get_if<Group1>(&p.content)) {
        last = *g;
        last_time = p.time;
        last_gps_ns = p.time1_gps_ns;
        ++g1;
      }
      if (const auto* g = std::get_if<Group3>(&p.content)) g3 = *g;
      if (const auto* m = std::get_if<Message>(&p.content)) message_ids.insert(m->id);
    }
    parser.end_of_stream();
  }
  EXPECT_EQ(datagrams, 241u);
  EXPECT_EQ(g1, 82u);
  EXPECT_NEAR(last.latitude_deg, 44.2449408681, 0.5e-10);
  EXPECT_NEAR(last.longitude_deg, -76.5096210157, 0.5e-10);
  EXPECT_NEAR(last.roll_deg, 2.04550977266, 0.5e-11);
  EXPECT_NEAR(last.pitch_deg, 1.3181307736, 0.5e-10);
  EXPECT_NEAR(last.heading_deg, 20.812475085, 0.5e-9);
  EXPECT_EQ(last.alignment_status, 4);
  EXPECT_EQ(last_time.time_types, 0x01);
  EXPECT_EQ(last_time.time1_type(), TimeType::gps);

  std::set<std::uint16_t> ids;
  for (const auto& c : parser.group_counts()) ids.insert(c.id);
  EXPECT_EQ(ids, (std::set<std::uint16_t>{1, 2, 3, 4, 7, 8, 10, 12, 13, 21, 99, 20000}));
  EXPECT_EQ(parser.groups_seen(1), 82u);
  EXPECT_EQ(parser.groups_seen(3), 80u);
  EXPECT_EQ(message_ids.size(), 25u);  // $MSG echoes of the control messages
  EXPECT_EQ(parser.counters().control_messages, 25u * 81u);
  const auto& c = parser.counters();
  EXPECT_EQ(
      c.bad_checksum + c.bad_length + c.bad_terminator + c.oversize + c.malformed + c.truncated,
      0u);
  EXPECT_EQ(c.garbage_bytes, 0u);

  // Group 3: 19 channel records, GPS week 1694, GPS-UTC 15 s.
  EXPECT_EQ(g3.channel_count, 19u);
  EXPECT_EQ(g3.gps_week, 1694u);
  EXPECT_EQ(g3.gps_utc_offset_s, 15.0);
  ASSERT_TRUE(last_gps_ns);
  EXPECT_EQ(*last_gps_ns, 1694 * 604'800'000'000'000 + std::llround(last_time.time1_s * 1e9));
}

}  // namespace
}  // namespace stac::applanix

namespace stac::applanix {
namespace {

// Found by fuzz/applanix_stream_fuzz: a week number no receiver sends (a 32-bit field of
// garbage) overflowed the nanoseconds (undefined behaviour); such a time is now no time.
TEST(ApplanixGroups, GpsTimeOfAWeekOrSecondsNoReceiverSendsIsNoTime) {
  const auto ok = gps_time_ns(TimeType::gps, 100.5, 2300, 18.0);
  ASSERT_TRUE(ok.has_value());
  EXPECT_EQ(*ok, (2300 * kSecondsPerWeek + 100) * 1'000'000'000 + 500'000'000);
  EXPECT_FALSE(gps_time_ns(TimeType::gps, 100.5, 0xFFFF'FFFFu, 18.0).has_value());
  EXPECT_FALSE(gps_time_ns(TimeType::gps, 100.5, kMaxGpsWeek + 1, 18.0).has_value());
  EXPECT_FALSE(gps_time_ns(TimeType::gps, 1e300, 2300, 18.0).has_value());
  EXPECT_FALSE(gps_time_ns(TimeType::utc, 100.0, 2300, -1e300).has_value());
  EXPECT_TRUE(gps_time_ns(TimeType::gps, 0.0, kMaxGpsWeek, 0.0).has_value());
}

// The fuzzer's input itself, through the stream parser, chunk by chunk.
TEST(ApplanixStreamParser, TheFuzzersWeekOverflowInputIsParsedWithoutATime) {
  std::ifstream f(std::string(::stac::testing::source_dir()) +
                      "/fuzz/corpus/applanix_stream_fuzz/crash_gps_week_overflow",
                  std::ios::binary);
  const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(f)),
                                        std::istreambuf_iterator<char>());
  ASSERT_FALSE(bytes.empty());
  StreamParser parser;
  parser.feed(bytes);
  Parsed m;
  int messages = 0;
  while (parser.next(m)) {
    ++messages;
    if (m.time1_gps_ns) {
      EXPECT_GE(*m.time1_gps_ns, 0);
      EXPECT_LE(*m.time1_gps_ns, std::int64_t{kMaxGpsWeek + 1} * kSecondsPerWeek * 1'000'000'000);
    }
  }
  parser.end_of_stream();
  EXPECT_GT(messages + parser.counters().garbage_bytes, 0u);
}

}  // namespace
}  // namespace stac::applanix
