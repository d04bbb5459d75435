// `stac process` and `stac eval` run as a user would, on a short simulated drive.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "shared_data.hpp"
#include "stac_cli.hpp"
#include "tools/evaluation/tracks_jsonl.hpp"

namespace stac::tools {
namespace {

using stac::testing::CliResult;
using stac::testing::stac;

constexpr const char* kYaml = "velodyne/calib/rosdrivers_64e_s2.1-sztaki.yaml";

std::filesystem::path fresh_dir(const std::string& name) {
  return stac::testing::fresh_dir("stac_process_" + name);
}

TEST(ProcessCli, SimulatedDriveGivesOneLinePerScanWithSegmentsTracksAndTruthThatEvalReads) {
  STAC_REQUIRE_SHARED_DATA(kYaml);
  const auto dir = fresh_dir("drive");
  const std::string pcap = (dir / "run.pcap").string(), truth = (dir / "run.jsonl").string();
  const CliResult sim =
      stac("sim --scenario parking-lot --seed 11 --duration 2 --calib " +
           stac::testing::shared_data(kYaml).string() + " --out " + pcap + " --truth " + truth);
  ASSERT_EQ(sim.code, 0) << sim.output;
  const std::string tracks = (dir / "run.tracks.jsonl").string();
  const CliResult p = stac("process " + pcap + " --truth " + truth + " --tracks " + tracks);
  ASSERT_EQ(p.code, 0) << p.output;
  for (const char* word : {"complete scans", "INS fixes", "hour from the INS",
                           "0 scans without a pose", "segment", "track", "median", "p99"}) {
    EXPECT_NE(p.output.find(word), std::string::npos) << word << " missing from:\n" << p.output;
  }
  auto out = read_tracks_file(tracks);
  ASSERT_TRUE(out) << out.error().message;
  auto truth_scans = read_truth_file(truth);
  ASSERT_TRUE(truth_scans) << truth_scans.error().message;
  ASSERT_GE(out->size(), 17u);  // 2 s at 10 Hz, complete scans only
  std::size_t segments = 0, with_truth = 0, confirmed = 0;
  for (const TracksScan& s : *out) {
    for (const SegmentRecord& seg : s.segments) {
      ++segments;
      with_truth += seg.has_truth ? 1 : 0;
      std::uint32_t n = 0;
      for (const auto& [id, count] : seg.truth) n += count;
      EXPECT_EQ(n, seg.points);  // every point of a segment is accounted for
    }
    for (const TrackRecord& t : s.tracks) confirmed += t.state == "confirmed" ? 1 : 0;
  }
  EXPECT_GT(segments, 100u);
  EXPECT_EQ(with_truth, segments);
  EXPECT_GT(confirmed, 50u);
  // The ego of each scan is where the truth says (same world frame, rebuilt from the INS stream).
  const TruthScanRecord* t0 = nullptr;
  for (const auto& t : *truth_scans) {
    if (std::llabs(t.stamp_ns - out->front().stamp_ns) < 1'000'000) t0 = &t;
  }
  ASSERT_NE(t0, nullptr);
  EXPECT_NEAR(out->front().ego.x, t0->ego.x, 0.05);
  EXPECT_NEAR(out->front().ego.y, t0->ego.y, 0.05);

  const CliResult e = stac("eval --truth " + truth + " --tracks " + tracks + " --report " +
                           (dir / "eval").string());
  ASSERT_EQ(e.code, 0) << e.output;
  EXPECT_TRUE(std::filesystem::exists(dir / "eval" / "metrics.json"));

  // Without the INS the sensor frame is the world: still one line per scan, and it says so.
  const CliResult parked =
      stac("process " + pcap + " --no-deskew --tracks " + (dir / "parked.jsonl").string());
  ASSERT_EQ(parked.code, 0) << parked.output;
  EXPECT_NE(parked.output.find("parked sensor"), std::string::npos) << parked.output;
  auto parked_out = read_tracks_file(dir / "parked.jsonl");
  ASSERT_TRUE(parked_out);
  EXPECT_EQ(parked_out->size(), out->size());
}

double mota_of(const std::filesystem::path& report) {
  std::ifstream in(report / "metrics.json");
  return nlohmann::json::parse(in).at("mota").get<double>();
}

// Issue 33: a tracks file records its frame, and eval brings the truth into it or refuses. Before,
// tracks anchored at the first pose were scored in the simulator's frame without a word.
TEST(ProcessCli, TracksRecordTheirFrameAndEvalBringsTheTruthIntoItOrRefuses) {
  STAC_REQUIRE_SHARED_DATA(kYaml);
  const auto dir = fresh_dir("frames");
  const auto at = [&](const char* name) { return (dir / name).string(); };
  const std::string calib = stac::testing::shared_data(kYaml).string();
  ASSERT_EQ(stac("sim --scenario urban --seed 7 --duration 4 --calib " + calib + " --out " +
                 at("urban.pcap") + " --truth " + at("urban.jsonl"))
                .code,
            0);
  auto truth = read_truth_file(at("urban.jsonl"));
  ASSERT_TRUE(truth && !truth->empty() && truth->front().origin);

  // With --truth: the truth's origin. Without: the first pose's, metres away from it.
  CliResult p = stac("process " + at("urban.pcap") + " --truth " + at("urban.jsonl") +
                     " --tracks " + at("same.jsonl"));
  ASSERT_EQ(p.code, 0) << p.output;
  p = stac("process " + at("urban.pcap") + " --tracks " + at("own.jsonl"));
  ASSERT_EQ(p.code, 0) << p.output;
  auto same = read_tracks_file(at("same.jsonl"));
  auto own = read_tracks_file(at("own.jsonl"));
  ASSERT_TRUE(same && own && !same->empty() && own->size() == same->size());
  EXPECT_EQ(same->front().frame, TracksFrame::kEnu);
  EXPECT_EQ(same->front().origin, *truth->front().origin);
  EXPECT_EQ(own->front().frame, TracksFrame::kEnu);
  EXPECT_NE(own->front().origin, *truth->front().origin);

  CliResult e = stac("eval --truth " + at("urban.jsonl") + " --tracks " + at("same.jsonl") +
                     " --report " + at("eval_same"));
  ASSERT_EQ(e.code, 0) << e.output;
  EXPECT_NE(e.output.find("frames: the same"), std::string::npos) << e.output;
  e = stac("eval --truth " + at("urban.jsonl") + " --tracks " + at("own.jsonl") + " --report " +
           at("eval_own"));
  ASSERT_EQ(e.code, 0) << e.output;
  EXPECT_NE(e.output.find("frames: the truth moved from ENU at"), std::string::npos) << e.output;
  const double right = mota_of(at("eval_same")), moved = mota_of(at("eval_own"));
  EXPECT_GT(right, 0.5);
  EXPECT_NEAR(moved, right, 0.02);
  std::ifstream report(dir / "eval_own" / "report.md");
  const std::string md((std::istreambuf_iterator<char>(report)), {});
  EXPECT_NE(md.find("frames: the truth moved"), std::string::npos) << md;

  // No pose on a moving vehicle: refused, saying what to do.
  p = stac("process " + at("urban.pcap") + " --no-deskew --tracks " + at("vehicle.jsonl"));
  ASSERT_EQ(p.code, 0) << p.output;
  auto vehicle = read_tracks_file(at("vehicle.jsonl"));
  ASSERT_TRUE(vehicle && !vehicle->empty());
  EXPECT_EQ(vehicle->front().frame, TracksFrame::kVehicle);
  e = stac("eval --truth " + at("urban.jsonl") + " --tracks " + at("vehicle.jsonl"));
  EXPECT_NE(e.code, 0);
  EXPECT_NE(e.output.find("the ego moves in the truth"), std::string::npos) << e.output;
  EXPECT_NE(e.output.find("INS stream"), std::string::npos) << e.output;

  // A parked ego without a pose: the truth in its vehicle frame, scored as with the INS.
  ASSERT_EQ(stac("sim --scenario intersection --seed 3 --duration 4 --calib " + calib + " --out " +
                 at("parked.pcap") + " --truth " + at("parked.jsonl"))
                .code,
            0);
  p = stac("process " + at("parked.pcap") + " --tracks " + at("ins.jsonl"));
  ASSERT_EQ(p.code, 0) << p.output;
  p = stac("process " + at("parked.pcap") + " --no-deskew --tracks " + at("none.jsonl"));
  ASSERT_EQ(p.code, 0) << p.output;
  e = stac("eval --truth " + at("parked.jsonl") + " --tracks " + at("ins.jsonl") + " --report " +
           at("eval_ins"));
  ASSERT_EQ(e.code, 0) << e.output;
  e = stac("eval --truth " + at("parked.jsonl") + " --tracks " + at("none.jsonl") + " --report " +
           at("eval_none"));
  ASSERT_EQ(e.code, 0) << e.output;
  EXPECT_NE(e.output.find("vehicle frame of its first scan"), std::string::npos) << e.output;
  EXPECT_GT(mota_of(at("eval_ins")), 0.5);
  EXPECT_NEAR(mota_of(at("eval_none")), mota_of(at("eval_ins")), 0.03);
}

// Issue 31: Applanix messages dropped for a bad checksum are reported, not silently lost.
TEST(ProcessCli, InsMessagesWithBadChecksumsAreCountedInTheSummary) {
  STAC_REQUIRE_SHARED_DATA(kYaml);
  const auto dir = fresh_dir("checksums");
  const std::string pcap = (dir / "run.pcap").string();
  const CliResult sim = stac("sim --scenario urban --seed 12 --duration 1 --calib " +
                             stac::testing::shared_data(kYaml).string() + " --out " + pcap +
                             " --truth " + (dir / "run.jsonl").string());
  ASSERT_EQ(sim.code, 0) << sim.output;
  // One byte of the body of every 10th Group 1 flipped (the TCP payload carries it as it is).
  std::string bytes;
  {
    std::ifstream in(pcap, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  int flipped = 0, seen = 0;
  for (std::size_t at = bytes.find("$GRP\x01"); at != std::string::npos;
       at = bytes.find("$GRP\x01", at + 1)) {
    if (seen++ % 10 != 0 || at + 40 >= bytes.size()) continue;
    bytes[at + 30] = static_cast<char>(bytes[at + 30] ^ 0x5a);
    ++flipped;
  }
  ASSERT_GT(flipped, 5);
  std::ofstream(pcap, std::ios::binary | std::ios::trunc) << bytes;
  const CliResult p = stac("process " + pcap + " --tracks " + (dir / "t.jsonl").string());
  ASSERT_EQ(p.code, 0) << p.output;
  const auto at = p.output.find("bad checksum ");
  ASSERT_NE(at, std::string::npos) << p.output;
  EXPECT_EQ(std::stoi(p.output.substr(at + 13)), flipped) << p.output;
}

TEST(ProcessCli, BadInputsAreNamed) {
  const auto dir = fresh_dir("errors");
  const CliResult missing =
      stac("process /nonexistent.pcap --tracks " + (dir / "x.jsonl").string());
  EXPECT_NE(missing.code, 0);
  EXPECT_NE(missing.output.find("nonexistent.pcap"), std::string::npos) << missing.output;
  const CliResult origin =
      stac("process " + std::string(STAC_SOURCE_DIR) + "/README.md --origin 95,0,0 --tracks " +
           (dir / "x.jsonl").string());
  EXPECT_NE(origin.code, 0);
}

}  // namespace
}  // namespace stac::tools
