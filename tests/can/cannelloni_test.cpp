// The cannelloni transport (CAN over UDP, drivers/can/cannelloni.hpp): the datagram format, and
// the reader on a real loopback UDP socket through the same OdometryInput as the other
// transports.
#include "drivers/can/cannelloni.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "can/shipped_decoder.hpp"
#include "drivers/can/odometry_input.hpp"
#include "rt/testing/alloc_counter.hpp"

namespace stac::can {
namespace {

Frame frame(std::uint32_t id, std::vector<std::uint8_t> data, bool extended = false) {
  Frame f;
  f.id = id;
  f.extended = extended;
  f.dlc = static_cast<std::uint8_t>(data.size());
  for (std::size_t i = 0; i < data.size(); ++i) f.data[i] = data[i];
  return f;
}

// A datagram written byte by byte from the format's description (doc/udp_format.md of
// mguentner/cannelloni): version 2, DATA, sequence 7, 3 frames: a standard id with 2 bytes, an
// extended id with 0 bytes, a CAN FD frame (len 0x80 | 3, a flags byte, 3 bytes).
const std::vector<std::uint8_t> kSample = {
    2,    0,    7,    0,    3,                       // header
    0x00, 0x00, 0x01, 0xA0, 2,    0x0E, 0x10,        // 0x1A0 [0E 10]
    0x98, 0xFE, 0xF1, 0xFE, 0,                       // 0x18FEF1FE, extended (0x80000000), no data
    0x00, 0x00, 0x01, 0x23, 0x83, 0x00, 1,    2, 3,  // CAN FD 0x123 [01 02 03]
};

TEST(Cannelloni, ADatagramOfTheFormatIsReadFrameByFrame) {
  CannelloniHeader h;
  ASSERT_TRUE(parse_cannelloni_header(kSample, h));
  EXPECT_EQ(h.version, 2);
  EXPECT_EQ(h.op_code, 0);
  EXPECT_EQ(h.sequence, 7);
  EXPECT_EQ(h.count, 3);
  Frame f;
  std::size_t at = kCannelloniHeaderBytes, next = 0;
  ASSERT_EQ(parse_cannelloni_frame(kSample, at, f, next), CannelloniFrameKind::kClassic);
  EXPECT_EQ(f.id, 0x1A0u);
  EXPECT_FALSE(f.extended);
  EXPECT_EQ(f.dlc, 2);
  EXPECT_EQ(f.data[0], 0x0E);
  EXPECT_EQ(f.data[1], 0x10);
  at = next;
  ASSERT_EQ(parse_cannelloni_frame(kSample, at, f, next), CannelloniFrameKind::kClassic);
  EXPECT_EQ(f.id, 0x18FEF1FEu);
  EXPECT_TRUE(f.extended);
  EXPECT_EQ(f.dlc, 0);
  at = next;
  ASSERT_EQ(parse_cannelloni_frame(kSample, at, f, next), CannelloniFrameKind::kFd);
  EXPECT_EQ(next, kSample.size());
  EXPECT_EQ(parse_cannelloni_frame(kSample, next, f, next), CannelloniFrameKind::kTruncated);
}

TEST(Cannelloni, EncodingGivesTheSameBytesAndRoundTrips) {
  const std::vector<Frame> frames = {frame(0x1A0, {0x0E, 0x10}), frame(0x18FEF1FE, {}, true)};
  std::vector<std::uint8_t> out(64);
  const std::size_t n = encode_cannelloni(frames, 7, out);
  std::vector<std::uint8_t> expected(kSample.begin(), kSample.begin() + 17);
  expected[4] = 2;  // two frames
  ASSERT_EQ(n, expected.size());
  EXPECT_EQ(std::vector<std::uint8_t>(out.begin(), out.begin() + static_cast<long>(n)), expected);
  EXPECT_EQ(encode_cannelloni(frames, 7, std::span<std::uint8_t>(out).first(16)), 0u)
      << "does not fit";
}

// Found by cannelloni_fuzz (fuzz/corpus/cannelloni_fuzz/crash_error_frame_id_round_trip): an
// error frame's id is its error class bits, 29 of them even without the EFF flag, and a remote
// frame keeps its DLC and bytes; both used to come back changed after encoding.
TEST(Cannelloni, ErrorAndRemoteFramesRoundTrip) {
  Frame error;
  from_socketcan_id(0x66F7F100u, error);  // RTR and ERR flags, no EFF
  ASSERT_TRUE(error.error && error.remote && !error.extended);
  EXPECT_EQ(to_socketcan_id(error), 0x66F7F100u);
  Frame remote = frame(0x1A0, {7, 8});
  remote.remote = true;
  std::vector<std::uint8_t> out(64);
  const std::size_t n = encode_cannelloni(std::vector<Frame>{error, remote}, 0, out);
  ASSERT_GT(n, 0u);
  Frame back;
  std::size_t next = 0;
  ASSERT_EQ(parse_cannelloni_frame(std::span(out).first(n), kCannelloniHeaderBytes, back, next),
            CannelloniFrameKind::kClassic);
  EXPECT_EQ(back.id, error.id);
  EXPECT_TRUE(back.error && back.remote);
  ASSERT_EQ(parse_cannelloni_frame(std::span(out).first(n), next, back, next),
            CannelloniFrameKind::kClassic);
  EXPECT_TRUE(back.remote);
  EXPECT_EQ(back.dlc, 2);
  EXPECT_EQ(back.data[1], 8);
  EXPECT_EQ(next, n);
}

TEST(Cannelloni, CutFramesAndImpossibleLengthsAreTruncatedNotRead) {
  Frame f;
  std::size_t next = 0;
  for (std::size_t size = kCannelloniHeaderBytes; size < 12; ++size) {
    const std::vector<std::uint8_t> cut(kSample.begin(), kSample.begin() + static_cast<long>(size));
    EXPECT_EQ(parse_cannelloni_frame(cut, kCannelloniHeaderBytes, f, next),
              CannelloniFrameKind::kTruncated)
        << size;
  }
  std::vector<std::uint8_t> nine = {2, 0, 0, 0, 1, 0, 0, 1, 0xA0, 9, 1, 2, 3, 4, 5, 6, 7, 8, 9};
  EXPECT_EQ(parse_cannelloni_frame(nine, kCannelloniHeaderBytes, f, next),
            CannelloniFrameKind::kTruncated)
      << "a classic frame of 9 bytes";
  std::vector<std::uint8_t> fd65(5 + 6 + 65, 0);
  fd65[9] = 0x80 | 65;
  EXPECT_EQ(parse_cannelloni_frame(fd65, kCannelloniHeaderBytes, f, next),
            CannelloniFrameKind::kTruncated)
      << "a CAN FD frame of 65 bytes";
  CannelloniHeader h;
  EXPECT_FALSE(parse_cannelloni_header(std::span(kSample).first(4), h));
}

struct Loopback {
  CannelloniReader reader = [] {
    auto r = CannelloniReader::open({"127.0.0.1", 0});
    EXPECT_TRUE(r) << r.error().message;
    return std::move(r).value();
  }();
  io::UdpSender sender = [this] {
    auto s = io::UdpSender::open("127.0.0.1", reader.port());
    EXPECT_TRUE(s);
    return std::move(s).value();
  }();
  void send(std::span<const std::uint8_t> bytes) { ASSERT_TRUE(sender.send(bytes)); }
  void send(const std::vector<Frame>& frames, std::uint8_t sequence) {
    std::vector<std::uint8_t> d(kCannelloniMaxDatagram);
    const std::size_t n = encode_cannelloni(frames, sequence, d);
    ASSERT_GT(n, 0u);
    send(std::span(d).first(n));
  }
};

TEST(CannelloniReader, FramesOfEveryDatagramAreReturnedAndWhatIsWrongIsCounted) {
  Loopback l;
  std::vector<Frame> many;
  for (std::uint32_t i = 0; i < 40; ++i) many.push_back(frame(0x100 + i, {1, 2}));
  l.send(many, 0);                          // more frames than one read takes
  l.send({frame(0x1A0, {0x0E, 0x10})}, 3);  // datagrams 1 and 2 lost
  l.send(kSample);                          // sequence 7 (3 more lost); a CAN FD frame
  const std::vector<std::uint8_t> v1 = {1, 0, 8, 0, 1, 0, 0, 1, 0xA0, 0};
  l.send(v1);  // version 1: malformed, its frame not read
  std::vector<std::uint8_t> cut(kSample.begin(), kSample.begin() + 14);
  cut[2] = 8;
  l.send(cut);  // cut inside its second frame: the first is read, the datagram is malformed
  std::vector<Frame> got;
  std::vector<Frame> out(16);
  for (int tries = 0; tries < 50 && got.size() < 44; ++tries) {
    const int n = l.reader.read(out, 200);
    ASSERT_GE(n, 0);
    got.insert(got.end(), out.begin(), out.begin() + n);
  }
  ASSERT_EQ(got.size(), 44u);  // 40 + 1 + 2 + 1
  EXPECT_EQ(got[39].id, 0x127u);
  EXPECT_EQ(got[40].id, 0x1A0u);
  EXPECT_EQ(got[42].id, 0x18FEF1FEu);
  EXPECT_EQ(got[43].id, 0x1A0u);
  EXPECT_GT(got[0].stamp_ns, 1'600'000'000'000'000'000);  // the receive time, UTC
  const CannelloniCounters c = l.reader.counters();
  EXPECT_EQ(c.datagrams, 5u);
  EXPECT_EQ(c.frames, 44u);
  EXPECT_EQ(c.can_fd, 1u);
  EXPECT_EQ(c.malformed, 2u);
  EXPECT_EQ(c.lost, 5u);
  EXPECT_EQ(l.reader.read(out, 10), 0) << "nothing more: a timeout";
}

// A gateway that restarts sends from a new socket and counts from 0 again: not a loss; the
// new sender's own gaps are.
TEST(CannelloniReader, SequenceNumbersCountPerSender) {
  Loopback l;
  l.send({frame(0x1A0, {1})}, 100);
  auto restarted = io::UdpSender::open("127.0.0.1", l.reader.port());
  ASSERT_TRUE(restarted);
  std::vector<std::uint8_t> d(32);
  for (const int sequence : {0, 1, 3}) {  // 2 is lost
    const std::size_t n = encode_cannelloni(std::vector<Frame>{frame(0x1A0, {2})},
                                            static_cast<std::uint8_t>(sequence), d);
    ASSERT_TRUE(restarted->send(std::span(d).first(n)));
  }
  std::vector<Frame> out(4);
  std::size_t got = 0;
  for (int tries = 0; tries < 50 && got < 4; ++tries)
    got += static_cast<std::size_t>(std::max(0, l.reader.read(out, 200)));
  ASSERT_EQ(got, 4u);
  EXPECT_EQ(l.reader.counters().lost, 1u);
}

TEST(CannelloniReader, StopEndsARead) {
  Loopback l;
  std::vector<Frame> out(4);
  l.reader.stop();
  EXPECT_EQ(l.reader.read(out, -1), CannelloniReader::kStopped);
}

TEST(CannelloniReader, APortInUseIsNamed) {
  Loopback l;
  auto second = CannelloniReader::open({"127.0.0.1", l.reader.port()});
  ASSERT_FALSE(second);
  EXPECT_NE(second.error().message.find("cannelloni"), std::string::npos) << second.error().message;
  EXPECT_NE(second.error().message.find(std::to_string(l.reader.port())), std::string::npos)
      << second.error().message;
}

// Through the input every transport shares: the signal map decodes, the other ids are dropped,
// and a read allocates nothing.
TEST(CannelloniReader, OdometryComesThroughTheSharedInputWithoutAllocation) {
  Loopback l;
  OdometryInput<CannelloniReader> in(std::move(l.reader), testing::shipped_decoder(), 16);
  for (std::uint8_t i = 0; i < 20; ++i) {
    l.send({frame(testing::kSpeedId, testing::kTenMetresPerSecond), frame(0x321, {1})}, i);
  }
  double sum = 0;
  rt::testing::AllocationCounter counter;
  for (int tries = 0; tries < 100 && in.counters().frames < 40; ++tries) {
    ASSERT_EQ(in.read(200, [&](const OdometryUpdate& u) { sum += u.speed_mps; }),
              InputEvent::kRead);
  }
  counter.stop();
  EXPECT_EQ(counter.allocations(), 0u);
  EXPECT_NEAR(sum, 200.0, 1e-9);
  const CanInputCounters c = in.counters();
  EXPECT_EQ(c.frames, 40u);
  EXPECT_EQ(c.not_mapped, 20u);
  EXPECT_EQ(c.lost, 0u);
  static_assert(TransportTraits<CannelloniReader>::kGone < CannelloniReader::kError);
}

}  // namespace
}  // namespace stac::can
