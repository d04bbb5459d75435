// Runs the real `stac eval` on files written the way `stac sim` and `stac process` write them.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "evaluation/tracks_jsonl.hpp"
#include "sim/run.hpp"
#include "stac_cli.hpp"

namespace stac::tools {
namespace {

using stac::testing::stac;

constexpr std::int64_t kStart = 1'767'268'800'000'000'000;

std::filesystem::path fresh_dir(const std::string& name) {
  return stac::testing::fresh_dir("stac_eval_cli_" + name);
}

// 20 scans: a car driving along y = 4 and a pedestrian, truth as `stac sim` writes it; tracks
// follow both perfectly, except that the car's track changes id once (scan 10) when
// `id_switch` is set. Segments carry truth: the pedestrian's segment also holds 40 car points.
void write_run(const std::filesystem::path& dir, bool id_switch) {
  std::ofstream truth(dir / "run.truth.jsonl");
  std::ofstream tracks(dir / "run.tracks.jsonl");
  for (int k = 0; k < 20; ++k) {
    sim::TruthScan t;
    t.scan = static_cast<std::uint64_t>(k);
    t.start_ns = kStart + k * 100'000'000LL;
    t.end_ns = t.start_ns + 99'000'000;
    const double cx = 5.0 + 1.0 * k;
    t.objects.push_back({1, sim::ObjectClass::kCar, cx, 4, 0.8, 4.5, 1.8, 1.5, 0, 10, 0, 500, 0});
    t.objects.push_back(
        {2, sim::ObjectClass::kPedestrian, -6, -2, 0.9, 0.6, 0.6, 1.8, 0, 0, 0, 60, 0});
    truth << sim::to_json(t) << "\n";

    evaluation::TracksScan o;
    o.scan = static_cast<std::uint64_t>(k);
    o.stamp_ns = t.start_ns;
    evaluation::SegmentRecord car;
    car.id = 0;
    car.points = 460;
    car.has_truth = true;
    car.truth = {{1, 460}};
    evaluation::SegmentRecord ped;
    ped.id = 1;
    ped.points = 100;
    ped.has_truth = true;
    ped.truth = {{1, 40}, {2, 60}};
    o.segments = {car, ped};
    evaluation::TrackRecord a;
    a.id = id_switch && k >= 10 ? 8 : 3;
    a.state = "confirmed";
    a.x = cx;
    a.y = 4;
    a.segment = 0;
    evaluation::TrackRecord b;
    b.id = 4;
    b.state = "confirmed";
    b.x = -6;
    b.y = -2;
    b.segment = 1;
    o.tracks = {a, b};
    std::string line;
    evaluation::append_json_line(o, line);
    tracks << line;
  }
}

TEST(EvalCli, WritesMetricsReportAndPlots) {
  const auto dir = fresh_dir("report");
  write_run(dir, true);
  const auto r = stac("eval --truth " + (dir / "run.truth.jsonl").string() + " --tracks " +
                      (dir / "run.tracks.jsonl").string() + " --report " + (dir / "out").string());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("| all |"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("20 scans paired"), std::string::npos) << r.output;
  std::ifstream m(dir / "out" / "metrics.json");
  ASSERT_TRUE(m.good());
  const auto j = nlohmann::json::parse(m);
  for (const char* key :
       {"mota", "motp", "id_switches", "hota", "under_segmentation", "over_segmentation"}) {
    ASSERT_TRUE(j.contains(key)) << key;
  }
  EXPECT_DOUBLE_EQ(j["mota"].get<double>(), 1.0 - 1.0 / 40.0);
  EXPECT_EQ(j["id_switches"].get<int>(), 1);
  EXPECT_DOUBLE_EQ(j["motp"].get<double>(), 1.0);
  EXPECT_DOUBLE_EQ(j["under_segmentation"].get<double>(), 0.5);  // the pedestrian, every scan
  EXPECT_DOUBLE_EQ(j["over_segmentation"].get<double>(), 0.0);
  EXPECT_GT(j["hota"].get<double>(), 0.5);
  EXPECT_LT(j["hota"].get<double>(), 1.0);
  EXPECT_TRUE(j["by_class"].contains("car"));
  EXPECT_TRUE(j["by_range"].contains("0-10"));
  for (const char* f : {"report.md", "range.png", "classes.png"}) {
    EXPECT_GT(std::filesystem::file_size(dir / "out" / f), 100u) << f;
  }
}

TEST(EvalCli, PerfectRunScoresOne) {
  const auto dir = fresh_dir("perfect");
  write_run(dir, false);
  const auto r = stac("eval --truth " + (dir / "run.truth.jsonl").string() + " --tracks " +
                      (dir / "run.tracks.jsonl").string() + " --report " + (dir / "out").string());
  ASSERT_EQ(r.code, 0) << r.output;
  std::ifstream m(dir / "out" / "metrics.json");
  const auto j = nlohmann::json::parse(m);
  EXPECT_DOUBLE_EQ(j["mota"].get<double>(), 1.0);
  EXPECT_NEAR(j["hota"].get<double>(), 1.0, 1e-12);
}

TEST(EvalCli, BadInputsGiveErrorsNamingTheFile) {
  const auto dir = fresh_dir("bad");
  write_run(dir, false);
  {
    std::ofstream f(dir / "broken.jsonl");
    f << "{\"scan\":0}\n";
  }
  auto r = stac("eval --truth " + (dir / "run.truth.jsonl").string() + " --tracks " +
                (dir / "broken.jsonl").string());
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.output.find("broken.jsonl:1: missing key 'time'"), std::string::npos) << r.output;
  r = stac("eval --truth " + (dir / "run.tracks.jsonl").string() + " --tracks " +
           (dir / "run.tracks.jsonl").string());
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.output.find("run.tracks.jsonl:1: missing key 'objects'"), std::string::npos)
      << r.output;
  r = stac("eval --truth " + (dir / "absent.jsonl").string() + " --tracks " +
           (dir / "run.tracks.jsonl").string());
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.output.find("absent.jsonl"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace stac::tools
