#include "drivers/can/candump.hpp"

#include <gtest/gtest.h>

#include <fstream>

namespace stac::can {
namespace {

std::filesystem::path temp_file(const std::string& name, const std::string& text) {
  const auto p = std::filesystem::temp_directory_path() / ("stac_candump_" + name);
  std::ofstream(p) << text;
  return p;
}

TEST(CandumpLine, StandardExtendedRemoteAndErrorFrames) {
  Frame f;
  auto l = parse_candump_line("(1700000000.123456) can0 123#11223344", f);
  ASSERT_EQ(l.kind, CandumpLineKind::kFrame);
  EXPECT_EQ(l.interface, "can0");
  EXPECT_EQ(f.stamp_ns, 1'700'000'000'123'456'000);
  EXPECT_EQ(f.id, 0x123u);
  EXPECT_FALSE(f.extended);
  ASSERT_EQ(f.dlc, 4);
  EXPECT_EQ(f.data[0], 0x11);
  EXPECT_EQ(f.data[3], 0x44);

  ASSERT_EQ(parse_candump_line("(1.5) vcan1 18FEF1FE#00a1.b2c3", f).kind, CandumpLineKind::kFrame);
  EXPECT_EQ(f.stamp_ns, 1'500'000'000);
  EXPECT_TRUE(f.extended);
  EXPECT_EQ(f.id, 0x18FEF1FEu);
  ASSERT_EQ(f.dlc, 4);
  EXPECT_EQ(f.data[1], 0xA1);
  EXPECT_EQ(f.data[3], 0xC3);

  ASSERT_EQ(parse_candump_line("(2.000000) can0 7FF#R", f).kind, CandumpLineKind::kFrame);
  EXPECT_TRUE(f.remote);
  EXPECT_EQ(f.dlc, 0);
  ASSERT_EQ(parse_candump_line("(2.000000) can0 7FF#R4", f).kind, CandumpLineKind::kFrame);
  EXPECT_EQ(f.dlc, 4);
  ASSERT_EQ(parse_candump_line("(2.000000) can0 123# T", f).kind, CandumpLineKind::kFrame);
  EXPECT_EQ(f.dlc, 0);
  ASSERT_EQ(parse_candump_line("(2.000000) can0 20000004#0004000000000000", f).kind,
            CandumpLineKind::kFrame);
  EXPECT_TRUE(f.error);
  EXPECT_EQ(f.id, 4u);
}

TEST(CandumpLine, CanFdAndBlankLinesAreTheirOwnKinds) {
  Frame f;
  EXPECT_EQ(parse_candump_line("(1.000000) can0 123##1112233", f).kind, CandumpLineKind::kCanFd);
  EXPECT_EQ(parse_candump_line("   \r", f).kind, CandumpLineKind::kBlank);
}

TEST(CandumpLine, MalformedLinesSayWhatIsWrong) {
  const std::pair<const char*, const char*> cases[] = {
      {"1700000000.1 can0 123#11", "timestamp"},
      {"(17000x0000.1) can0 123#11", "timestamp"},
      // Issue 31: these wrapped around (written back as "-9223372036.-854775" and 3875820019.68).
      {"(9223372036.854775808) can0 123#11", "timestamp"},
      {"(999999999999.999999) can0 123#11", "timestamp"},
      {"(1.1) can0 123", "expected <id>#<data>"},
      {"(1.1) can0 1234#11", "3 (standard) or 8 (extended)"},
      {"(1.1) can0 800#11", "at most 7FF"},
      {"(1.1) can0 12G#11", "not hexadecimal"},
      {"(1.1) can0 123#112", "whole bytes"},
      {"(1.1) can0 123#1122334455667788AA", "more than 8 data bytes"},
      {"(1.1) can0 123#11 extra", "unexpected text"},
      {"(1.1) can0 123#R9", "remote frame"},
      {"(1.1)", "interface"},
  };
  for (const auto& [line, reason] : cases) {
    Frame f;
    const auto l = parse_candump_line(line, f);
    EXPECT_EQ(l.kind, CandumpLineKind::kMalformed) << line;
    EXPECT_NE(std::string(l.reason).find(reason), std::string::npos) << line << " -> " << l.reason;
  }
}

TEST(CandumpLine, TheLatestTimeThatFitsIsRead) {
  Frame f;
  const auto l = parse_candump_line("(9223372035.999999) can0 123#11", f);
  ASSERT_EQ(l.kind, CandumpLineKind::kFrame) << l.reason;
  EXPECT_EQ(f.stamp_ns, 9'223'372'035'999'999'000);
}

// A log's text in memory reads as its file (the fuzz harness reads logs so).
TEST(CandumpReader, TextInMemoryReadsAsAFile) {
  auto r = CandumpReader::from_text(
      "(1.000000) can0 123#11\n\n(1.500000) can0 1A0#0E10\n(2.0) can0 XYZ#11\n", "memory.log");
  Frame f;
  auto first = r.next(f);
  ASSERT_TRUE(first && *first);
  EXPECT_EQ(f.id, 0x123u);
  auto second = r.next(f);
  ASSERT_TRUE(second && *second);
  EXPECT_EQ(f.stamp_ns, 1'500'000'000);
  EXPECT_EQ(f.dlc, 2);
  const auto third = r.next(f);
  ASSERT_FALSE(third);
  EXPECT_NE(third.error().message.find("memory.log:4: the id is not hexadecimal"),
            std::string::npos)
      << third.error().message;
  EXPECT_EQ(r.counters().blank, 1u);
  auto empty = CandumpReader::from_text("", "empty.log");
  const auto end = empty.next(f);
  ASSERT_TRUE(end);
  EXPECT_FALSE(*end);
}

TEST(CandumpReader, MalformedLineStopsWithFileAndLine) {
  const auto p = temp_file(
      "bad.log", "(1.000000) can0 123#11\n\n(1.000000) can0 123##0AA\n(1.1) can0 XYZ#11\n");
  auto r = CandumpReader::open(p);
  ASSERT_TRUE(r);
  Frame f;
  auto first = r->next(f);
  ASSERT_TRUE(first);
  EXPECT_TRUE(*first);
  const auto second = r->next(f);
  ASSERT_FALSE(second);
  EXPECT_NE(second.error().message.find(p.string() + ":4: the id is not hexadecimal"),
            std::string::npos)
      << second.error().message;
  EXPECT_EQ(r->counters().can_fd, 1u);
  EXPECT_EQ(r->counters().blank, 1u);
  const auto missing = CandumpReader::open("/nonexistent/run.log");
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().message.find("/nonexistent/run.log"), std::string::npos);
}

TEST(CandumpWriter, RoundTripsThroughTheReaderInCandumpsFormat) {
  const auto p = std::filesystem::temp_directory_path() / "stac_candump_roundtrip.log";
  std::vector<Frame> frames;
  Frame a;
  a.stamp_ns = 1'700'000'000'123'456'000;
  a.id = 0x1A0;
  a.dlc = 8;
  a.data = {0x0E, 0x10, 0, 0, 0, 0xAB, 0, 0xFF};
  frames.push_back(a);
  Frame b;
  b.stamp_ns = 1'700'000'000'200'000'000;
  b.id = 0x18FEF1FE;
  b.extended = true;
  b.dlc = 3;
  b.data = {1, 2, 3};
  frames.push_back(b);
  Frame c;
  c.stamp_ns = 1'700'000'001'000'001'000;
  c.id = 0x7FF;
  c.remote = true;
  c.dlc = 2;
  frames.push_back(c);
  {
    auto w = CandumpWriter::open(p, "can0");
    ASSERT_TRUE(w);
    for (const Frame& f : frames) ASSERT_TRUE(w->write(f));
    ASSERT_TRUE(w->close());
  }
  std::ifstream in(p);
  std::string first;
  std::getline(in, first);
  EXPECT_EQ(first, "(1700000000.123456) can0 1A0#0E10000000AB00FF");
  auto r = CandumpReader::open(p);
  ASSERT_TRUE(r);
  for (const Frame& want : frames) {
    Frame got;
    auto ok = r->next(got);
    ASSERT_TRUE(ok && *ok);
    EXPECT_EQ(got.stamp_ns, want.stamp_ns);
    EXPECT_EQ(got.id, want.id);
    EXPECT_EQ(got.extended, want.extended);
    EXPECT_EQ(got.remote, want.remote);
    EXPECT_EQ(got.dlc, want.dlc);
    if (!want.remote) {
      EXPECT_EQ(got.data, want.data);
    }
  }
  Frame end;
  auto eof = r->next(end);
  ASSERT_TRUE(eof);
  EXPECT_FALSE(*eof);
  EXPECT_FALSE(CandumpWriter::open(p, "can 0"));
}

}  // namespace
}  // namespace stac::can
