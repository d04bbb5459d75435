// `stac process` and `stac eval` run as a user would, on a short simulated drive.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>
#include <string>
#include <vector>

#include "evaluation/tracklet_truth.hpp"
#include "evaluation/tracks_jsonl.hpp"
#include "formats/dataset_file.hpp"
#include "formats/kitti_raw.hpp"
#include "settings/settings.hpp"
#include "shared_data.hpp"
#include "stac_cli.hpp"
#include "test_paths.hpp"

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
  auto out = evaluation::read_tracks_file(tracks);
  ASSERT_TRUE(out) << out.error().message;
  auto truth_scans = evaluation::read_truth_file(truth);
  ASSERT_TRUE(truth_scans) << truth_scans.error().message;
  ASSERT_GE(out->size(), 17u);  // 2 s at 10 Hz, complete scans only
  std::size_t segments = 0, with_truth = 0, confirmed = 0;
  for (const evaluation::TracksScan& s : *out) {
    for (const evaluation::SegmentRecord& seg : s.segments) {
      ++segments;
      with_truth += seg.has_truth ? 1 : 0;
      std::uint32_t n = 0;
      for (const auto& [id, count] : seg.truth) n += count;
      EXPECT_EQ(n, seg.points);  // every point of a segment is accounted for
    }
    for (const evaluation::TrackRecord& t : s.tracks) confirmed += t.state == "confirmed" ? 1 : 0;
  }
  EXPECT_GT(segments, 100u);
  EXPECT_EQ(with_truth, segments);
  EXPECT_GT(confirmed, 50u);
  // The ego of each scan is where the truth says (same world frame, rebuilt from the INS stream).
  const evaluation::TruthScanRecord* t0 = nullptr;
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
  auto parked_out = evaluation::read_tracks_file(dir / "parked.jsonl");
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
  auto truth = evaluation::read_truth_file(at("urban.jsonl"));
  ASSERT_TRUE(truth && !truth->empty() && truth->front().origin);

  // With --truth: the truth's origin. Without: the first pose's, metres away from it.
  CliResult p = stac("process " + at("urban.pcap") + " --truth " + at("urban.jsonl") +
                     " --tracks " + at("same.jsonl"));
  ASSERT_EQ(p.code, 0) << p.output;
  p = stac("process " + at("urban.pcap") + " --tracks " + at("own.jsonl"));
  ASSERT_EQ(p.code, 0) << p.output;
  auto same = evaluation::read_tracks_file(at("same.jsonl"));
  auto own = evaluation::read_tracks_file(at("own.jsonl"));
  ASSERT_TRUE(same && own && !same->empty() && own->size() == same->size());
  EXPECT_EQ(same->front().frame, evaluation::TracksFrame::kEnu);
  EXPECT_EQ(same->front().origin, *truth->front().origin);
  EXPECT_EQ(own->front().frame, evaluation::TracksFrame::kEnu);
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
  auto vehicle = evaluation::read_tracks_file(at("vehicle.jsonl"));
  ASSERT_TRUE(vehicle && !vehicle->empty());
  EXPECT_EQ(vehicle->front().frame, evaluation::TracksFrame::kVehicle);
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

// Issue 33: a KITTI raw drive folder as the input. The 40 real scans of kitti-raw-seq (no OXTS,
// no timestamps) run parked, said so, with a picture of each scan; a drive's timestamps.txt
// gives the scans their times; its oxts/ records are the INS (world frame, the mounting from
// calib_imu_to_velo.txt); sim-compare reads the same folder.
TEST(ProcessCli, KittiRawDriveRunsParkedWithAPictureOfEachScanOrPosedByItsOxts) {
  constexpr const char* kSeq = "kitti-raw-seq/velodyne_points/data/0000000000.bin";
  STAC_REQUIRE_SHARED_DATA(kSeq);
  const std::filesystem::path seq = stac::testing::shared_data("kitti-raw-seq");
  const auto dir = fresh_dir("kitti_raw");
  CliResult p = stac("process " + seq.string() + " --tracks " + (dir / "t.jsonl").string() +
                     " --pictures " + (dir / "pictures").string());
  ASSERT_EQ(p.code, 0) << p.output;
  for (const char* said :
       {"KITTI raw drive: 40 scans", "100 ms apart (no velodyne_points", "0 left out",
        "no oxts/ in the drive: parked sensor", "40 complete scans", "pictures    40 in"}) {
    EXPECT_NE(p.output.find(said), std::string::npos) << said << " missing from\n" << p.output;
  }
  auto tracks = evaluation::read_tracks_file(dir / "t.jsonl");
  ASSERT_TRUE(tracks) << tracks.error().message;
  ASSERT_EQ(tracks->size(), 40u);
  std::size_t confirmed = 0, segments = 0;
  for (std::size_t k = 0; k < tracks->size(); ++k) {
    const evaluation::TracksScan& t = (*tracks)[k];
    EXPECT_EQ(t.frame, evaluation::TracksFrame::kVehicle);
    EXPECT_EQ(t.stamp_ns, 1'000'000'000 + static_cast<std::int64_t>(k) * 100'000'000);
    segments += t.segments.size();
    for (const evaluation::TrackRecord& r : t.tracks) confirmed += r.state == "confirmed" ? 1 : 0;
  }
  EXPECT_GT(segments, 40u * 30u);  // a dense street: dozens of segments a scan
  EXPECT_GT(confirmed, 40u * 10u);
  for (int k = 0; k < 40; ++k) {
    char name[32];
    std::snprintf(name, sizeof(name), "scan_%06d.png", k);
    std::error_code ec;
    EXPECT_GT(std::filesystem::file_size(dir / "pictures" / name, ec), 10'000u) << name;
  }

  // A drive of three of the scans, with its times.
  const auto drive = dir / "2011_09_26_drive";
  std::filesystem::create_directories(drive / "velodyne_points" / "data");
  for (int k = 0; k < 3; ++k) {
    const std::string name = "000000000" + std::to_string(k) + ".bin";
    std::filesystem::create_symlink(seq / "velodyne_points" / "data" / name,
                                    drive / "velodyne_points" / "data" / name);
  }
  std::ofstream(drive / "velodyne_points" / "timestamps.txt")
      << "2011-09-26 13:02:25.964389445\n2011-09-26 13:02:26.066013922\n";
  p = stac("process " + drive.string() + " --tracks " + (dir / "d.jsonl").string());
  EXPECT_NE(p.code, 0);
  EXPECT_NE(p.output.find("timestamps.txt has 2 times for 3 scans"), std::string::npos) << p.output;
  std::ofstream(drive / "velodyne_points" / "timestamps.txt", std::ios::app)
      << "2011-09-26 13:02:26.167672432\n";
  p = stac("process " + drive.string() + " --tracks " + (dir / "d.jsonl").string());
  ASSERT_EQ(p.code, 0) << p.output;
  EXPECT_NE(p.output.find("times from velodyne_points/timestamps.txt"), std::string::npos)
      << p.output;
  auto timed = evaluation::read_tracks_file(dir / "d.jsonl");
  ASSERT_TRUE(timed && timed->size() == 3u);
  EXPECT_NEAR(static_cast<double>(timed->front().stamp_ns - 1'317'042'145'964'389'445), 0.0,
              1000.0);
  // Its GPS/IMU: oxts/ records are the INS. An empty oxts/data is refused; --no-deskew parks.
  std::filesystem::create_directories(drive / "oxts" / "data");
  p = stac("process " + drive.string() + " --tracks " + (dir / "d.jsonl").string());
  EXPECT_NE(p.code, 0);
  EXPECT_NE(p.output.find("no .txt record"), std::string::npos) << p.output;
  p = stac("process " + drive.string() + " --no-deskew --tracks " + (dir / "d.jsonl").string());
  EXPECT_EQ(p.code, 0) << p.output;
  EXPECT_NE(p.output.find("--no-deskew: parked sensor"), std::string::npos) << p.output;
  // Three records, facing north (yaw pi/2) and 1 m further north each; the mounting in the date
  // folder above the drive, as KITTI ships it: the IMU 0.81 m behind, 0.32 m left of and 0.80 m
  // below the velodyne.
  std::filesystem::copy_file(drive / "velodyne_points" / "timestamps.txt",
                             drive / "oxts" / "timestamps.txt");
  for (int k = 0; k < 3; ++k) {
    char line[256];
    std::snprintf(line, sizeof(line),
                  "%.12f 8.4 110 0 0 1.5707963267948966 10 0 10 0 0 0 0 9.81 0 0 9.81 0 0 0 0 0 "
                  "0 0.05 0.02 4 10 4 4 0\n",
                  49.0 + k / 111'200.0);
    std::ofstream(drive / "oxts" / "data" / ("000000000" + std::to_string(k) + ".txt")) << line;
  }
  std::ofstream(dir / "calib_imu_to_velo.txt")
      << "calib_time: 25-May-2012 16:47:16\nR: 1 0 0 0 1 0 0 0 1\nT: -0.81 0.32 -0.80\n";
  p = stac("process " + drive.string() + " --tracks " + (dir / "posed.jsonl").string());
  ASSERT_EQ(p.code, 0) << p.output;
  for (const std::string& said :
       {std::string("3 OXTS records, 3 poses"), std::string("0 scans without a pose"),
        "sensor mounting from " + (dir / "calib_imu_to_velo.txt").string()}) {
    EXPECT_NE(p.output.find(said), std::string::npos) << said << " missing from\n" << p.output;
  }
  auto posed = evaluation::read_tracks_file(dir / "posed.jsonl");
  auto parked = evaluation::read_tracks_file(dir / "d.jsonl");
  ASSERT_TRUE(posed && parked && posed->size() == 3u && parked->size() == 3u);
  for (std::size_t k = 0; k < 3; ++k) {
    const evaluation::TracksScan& t = (*posed)[k];
    EXPECT_EQ(t.frame, evaluation::TracksFrame::kEnu);
    EXPECT_NEAR(t.origin[0], 49.0, 1e-9);
    EXPECT_NEAR(t.ego.x, 0.0, 0.01);
    EXPECT_NEAR(t.ego.y, static_cast<double>(k), 0.01);  // 1 m north a scan
    EXPECT_NEAR(t.ego.yaw, std::numbers::pi / 2, 1e-6);
  }
  // The first scan's segments: the vehicle's (parked with the config's mounting, the sensor
  // 1.73 m up) turned to face north and moved by the drive's mounting.
  const evaluation::TracksScan& a = (*posed)[0];
  const evaluation::TracksScan& b = (*parked)[0];
  ASSERT_EQ(a.segments.size(), b.segments.size());
  ASSERT_FALSE(a.segments.empty());
  for (std::size_t i = 0; i < a.segments.size(); i += 7) {
    EXPECT_NEAR(a.segments[i].x, -b.segments[i].y + 0.32, 1e-3) << i;
    EXPECT_NEAR(a.segments[i].y, b.segments[i].x + 0.81, 1e-3) << i;
    EXPECT_NEAR(a.segments[i].z, b.segments[i].z - 1.73 + 0.80, 1e-3) << i;
  }

  // sim-compare reports the real scans of the same folder.
  const std::string pcap = (dir / "sim.pcap").string();
  ASSERT_EQ(stac("sim --scenario urban --seed 3 --duration 0.5 --out " + pcap + " --truth " +
                 (dir / "sim.jsonl").string())
                .code,
            0);
  p = stac("sim-compare --sim " + pcap + " --kitti " + seq.string() + " --report " +
           (dir / "realism").string());
  ASSERT_EQ(p.code, 0) << p.output;
  EXPECT_NE(p.output.find("vs 40 KITTI scans"), std::string::npos) << p.output;
}

// Issue 33: `stac sim --kitti-raw` writes a drive in KITTI raw's layout (scans not deskewed, an
// OXTS record at each scan's mid-sweep time, the mounting), so the KITTI path runs with known
// answers: the same simulated drive through its pcap and through its KITTI raw folder tracks the
// same within a stated tolerance (MOTA and HOTA within 0.03; the KITTI path places each scan at one
// instant, not deskewed, so its boxes may sit up to 0.1 m farther off on average).
TEST(ProcessCli, ASimulatedDriveThroughPcapAndThroughKittiRawTracksTheSame) {
  const auto dir = fresh_dir("kitti_sim");
  const auto at = [&](const char* name) { return (dir / name).string(); };
  CliResult r = stac("sim --scenario urban --seed 7 --duration 6 --out " + at("run.pcap") +
                     " --truth " + at("run.jsonl") + " --kitti-raw " + at("drive"));
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("KITTI raw: 59 complete scans"), std::string::npos) << r.output;
  for (const char* f :
       {"drive/calib_imu_to_velo.txt", "drive/oxts/timestamps.txt",
        "drive/velodyne_points/timestamps.txt", "drive/velodyne_points/data/0000000058.bin",
        "drive/velodyne_points/timestamps_start.txt", "drive/velodyne_points/timestamps_end.txt",
        "drive/oxts/data/0000000058.txt"})
    EXPECT_TRUE(std::filesystem::is_regular_file(dir / f)) << f;

  r = stac("process " + at("run.pcap") + " --tracks " + at("pcap.jsonl"));
  ASSERT_EQ(r.code, 0) << r.output;
  r = stac("process " + at("drive") + " --tracks " + at("kitti.jsonl"));
  ASSERT_EQ(r.code, 0) << r.output;
  for (const char* said :
       {"59 OXTS records, 59 poses", "0 scans without a pose", "59 complete scans",
        "each point's by its azimuth in its sweep", "drive/calib_imu_to_velo.txt"})
    EXPECT_NE(r.output.find(said), std::string::npos) << said << " missing from\n" << r.output;
  std::map<std::string, nlohmann::json> m;
  for (const char* path : {"pcap", "kitti"}) {
    const std::string report = at(path) + std::string("_eval");
    r = stac("eval --truth " + at("run.jsonl") + " --tracks " + at(path) + std::string(".jsonl") +
             " --report " + report);
    ASSERT_EQ(r.code, 0) << r.output;
    std::ifstream in(report + "/metrics.json");
    m[path] = nlohmann::json::parse(in);
  }
  const auto number = [&](const char* path, const char* key) {
    return m[path].at(key).get<double>();
  };
  EXPECT_GT(number("pcap", "mota"), 0.8) << m["pcap"].dump(2);
  EXPECT_NEAR(number("kitti", "mota"), number("pcap", "mota"), 0.03);
  EXPECT_NEAR(number("kitti", "hota"), number("pcap", "hota"), 0.03);
  EXPECT_NEAR(number("kitti", "motp_distance_m"), number("pcap", "motp_distance_m"), 0.1);
  // Every truth scan paired: the drive's sweeps start facing backward, half a turn before the
  // capture's scans, so it holds one more complete scan (59, the capture 58).
  EXPECT_GT(number("kitti", "gt"), number("pcap", "gt"));
  EXPECT_LT(number("kitti", "gt"), number("pcap", "gt") * 60 / 58);

  // The drive's tracklet_labels.xml, written from the truth, scores the same tracks as the truth
  // does (only cars, pedestrians and bicyclists are labelled, so a track on background counts
  // only when classified as one of them).
  EXPECT_TRUE(std::filesystem::is_regular_file(dir / "drive/tracklet_labels.xml"));
  r = stac("eval --tracklets " + at("drive") + "/tracklet_labels.xml --tracks " +
           at("kitti.jsonl") + " --report " + at("tracklets_eval"));
  ASSERT_EQ(r.code, 0) << r.output;
  {
    std::ifstream in(at("tracklets_eval") + "/metrics.json");
    m["tracklets"] = nlohmann::json::parse(in);
  }
  EXPECT_NEAR(number("tracklets", "mota"), number("kitti", "mota"), 0.03);
  EXPECT_NEAR(number("tracklets", "hota"), number("kitti", "hota"), 0.03);
  EXPECT_GT(number("tracklets", "gt"), 0.9 * number("kitti", "gt"));
  r = stac("eval --tracklets " + at("drive") + "/tracklet_labels.xml --truth " + at("run.jsonl") +
           " --tracks " + at("kitti.jsonl"));
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.output.find("not both"), std::string::npos) << r.output;
  {  // labels for frames the drive does not have
    std::ifstream in(dir / "drive/tracklet_labels.xml");
    std::string xml{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    const std::string first = "<first_frame>0</first_frame>";
    ASSERT_NE(xml.find(first), std::string::npos);
    xml.replace(xml.find(first), first.size(), "<first_frame>58</first_frame>");
    std::ofstream(dir / "late.xml") << xml;
  }
  r = stac("eval --tracklets " + at("late.xml") + " --drive " + at("drive") + " --tracks " +
           at("kitti.jsonl"));
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.output.find("has a pose for frame 59; the drive has 59 scans"), std::string::npos)
      << r.output;

  {  // Truth velocities are over the frames' times, at which KITTI's boxes are, not the sweeps'
     // starts the truth scans are stamped with: every other sweep moved by 30 ms changes none.
    auto ego = stac::settings::load_ego_settings(
        std::filesystem::path(::stac::testing::source_dir()) / "config/stac.yaml");
    ASSERT_TRUE(ego) << ego.error().message;
    const auto velocities = [&] {
      std::vector<double> v;
      auto truth = stac::evaluation::truth_from_tracklets(dir / "drive/tracklet_labels.xml",
                                                          dir / "drive", *ego);
      EXPECT_TRUE(truth) << truth.error().message;
      if (truth)
        for (const auto& scan : *truth)
          for (const auto& o : scan.objects) v.insert(v.end(), {o.vx, o.vy});
      return v;
    };
    const std::vector<double> before = velocities();
    ASSERT_FALSE(before.empty());
    EXPECT_GT(std::count_if(before.begin(), before.end(), [](double x) { return std::abs(x) > 1; }),
              0);  // something moves
    const auto sweeps = dir / "drive/velodyne_points";
    struct Restore {  // the drive's own sweep times back for the steps below, even on a failure
      std::filesystem::path from, to;
      ~Restore() {
        for (const char* name : {"timestamps_start.txt", "timestamps_end.txt"})
          if (std::filesystem::exists(from / name))
            std::filesystem::copy_file(from / name, to / name,
                                       std::filesystem::copy_options::overwrite_existing);
      }
    } restore{dir, sweeps};
    for (const char* name : {"timestamps_start.txt", "timestamps_end.txt"}) {
      std::filesystem::copy_file(sweeps / name, dir / name);
      std::ifstream in(sweeps / name);
      std::string shifted, line;
      for (int k = 0; std::getline(in, line); ++k) {
        std::int64_t ns = 0;
        ASSERT_TRUE(stac::formats::parse_kitti_time(line, ns)) << line;
        shifted += stac::formats::format_kitti_time(ns + (k % 2 == 1 ? 30'000'000 : 0)) + "\n";
      }
      in.close();
      std::ofstream(sweeps / name) << shifted;
    }
    const std::vector<double> after = velocities();
    ASSERT_EQ(after.size(), before.size());
    for (std::size_t i = 0; i < before.size(); ++i) EXPECT_NEAR(after[i], before[i], 1e-9) << i;
  }

  // `stac dataset` takes the folder as it takes the pcap: about as many tracks kept and labelled
  // (a dataset for stac train, or, without --truth, for stac induct).
  std::map<std::string, std::size_t> kept;
  for (const char* in : {"run.pcap", "drive"}) {
    const std::string out = at(in) + std::string("_data");
    r = stac("dataset --in " + at(in) + " --truth " + at("run.jsonl") + " --out " + out);
    ASSERT_EQ(r.code, 0) << r.output;
    auto d = stac::formats::read_dataset(out);
    ASSERT_TRUE(d.has_value()) << d.error().message;
    kept[in] = d->tracks.size();
    std::size_t cars = 0;
    for (const auto& t : d->tracks) cars += t.label == 0 ? 1 : 0;
    EXPECT_GT(cars, 10u) << in;
  }
  EXPECT_GT(kept["drive"], kept["run.pcap"] * 8 / 10);
  EXPECT_LT(kept["drive"], kept["run.pcap"] * 12 / 10);
  r = stac("dataset --in " + at("drive") + " --out " + at("unlabeled_data"));
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("unlabeled tracks"), std::string::npos) << r.output;

  // Only the KITTI folder; nothing to write at all is refused.
  r = stac("sim --scenario empty --seed 2 --duration 1 --truth " + at("only.jsonl") +
           " --kitti-raw " + at("only"));
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("(no pcap)"), std::string::npos) << r.output;
  EXPECT_TRUE(std::filesystem::is_regular_file(dir / "only/velodyne_points/data/0000000000.bin"));
  r = stac("sim --scenario empty --duration 1 --truth " + at("none.jsonl"));
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.output.find("nothing to write"), std::string::npos) << r.output;
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
      stac("process " + std::string(::stac::testing::source_dir()) +
           "/README.md --origin 95,0,0 --tracks " + (dir / "x.jsonl").string());
  EXPECT_NE(origin.code, 0);
}

}  // namespace
}  // namespace stac::tools
