// Every Velodyne model end to end, as a user would run it (issue 33): `stac sim --model` writes
// its packets and position packets, `stac status` and `stac decode` recognise it from its bytes,
// `stac process --sensor auto` tracks the drive and `stac eval` scores it against the truth.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "shared_data.hpp"
#include "stac_cli.hpp"

namespace stac::tools {
namespace {

using stac::testing::CliResult;
using stac::testing::stac;

struct Case {
  const char* model;   // as the user types it
  const char* name;    // as STAC writes it
  const char* shared;  // its calibration in ../shared/data (velodyne.model_calibrations), or
                       // nullptr for the repository's own
  double min_mota;     // the parking lot's cars and pedestrians, 3 s
};

class FamilyCli : public ::testing::TestWithParam<Case> {};

double metric(const std::filesystem::path& report, const char* key) {
  std::ifstream in(report / "metrics.json");
  return nlohmann::json::parse(in).at(key).get<double>();
}

TEST_P(FamilyCli, SimulatedDriveIsRecognisedDecodedTrackedAndScored) {
  const Case c = GetParam();
  if (c.shared != nullptr) STAC_REQUIRE_SHARED_DATA(c.shared);
  const auto dir = stac::testing::fresh_dir(std::string("stac_family_") + c.name);
  const std::string pcap = (dir / "run.pcap").string(), truth = (dir / "run.jsonl").string();
  const CliResult sim =
      stac(std::string("sim --model \"") + c.model +
           "\" --scenario parking-lot --seed 11 --duration 3 --out " + pcap + " --truth " + truth);
  ASSERT_EQ(sim.code, 0) << sim.output;

  // status: the factory bytes and the position packets' NMEA.
  const CliResult status = stac("status --model auto --in " + pcap);
  ASSERT_EQ(status.code, 0) << status.output;
  EXPECT_NE(status.output.find(std::string(c.name) + " data packets (0 whose"), std::string::npos)
      << status.output;
  EXPECT_NE(status.output.find("return mode strongest"), std::string::npos) << status.output;
  EXPECT_NE(status.output.find("0 unreadable"), std::string::npos) << status.output;
  EXPECT_NE(status.output.find("PPS locked, $GPRMC,"), std::string::npos) << status.output;
  EXPECT_NE(status.output.find("UTC, valid, 44.24"), std::string::npos) << status.output;

  // decode: with the configuration's HDL-64E it warns that the packets name another model; with
  // --model auto it follows them and every scan is whole.
  const CliResult forced = stac("decode --in " + pcap + " --out " + (dir / "forced.csv").string());
  EXPECT_NE(forced.output.find(std::string("its packets name a ") + c.name), std::string::npos)
      << forced.output;
  const CliResult decoded =
      stac("decode --model auto --in " + pcap + " --out " + (dir / "points.csv").string());
  ASSERT_EQ(decoded.code, 0) << decoded.output;
  EXPECT_NE(decoded.output.find(std::string("packets of a ") + c.name), std::string::npos)
      << decoded.output;
  EXPECT_NE(decoded.output.find("invalid block 0, duplicate 0"), std::string::npos)
      << decoded.output;
  EXPECT_NE(decoded.output.find("(28 complete"), std::string::npos) << decoded.output;

  // process + eval: tracks in the truth's world frame, scored.
  const std::string tracks = (dir / "tracks.jsonl").string();
  const CliResult p =
      stac("process " + pcap + " --sensor auto --truth " + truth + " --tracks " + tracks);
  ASSERT_EQ(p.code, 0) << p.output;
  const CliResult e = stac("eval --truth " + truth + " --tracks " + tracks + " --report " +
                           (dir / "eval").string());
  ASSERT_EQ(e.code, 0) << e.output;
  const double mota = metric(dir / "eval", "mota");
  std::printf("%s: MOTA %.3f\n", c.name, mota);
  EXPECT_GT(mota, c.min_mota) << e.output;
}

INSTANTIATE_TEST_SUITE_P(Models, FamilyCli,
                         ::testing::Values(Case{"HDL-32E", "HDL-32E", nullptr, 0.3},
                                           Case{"VLP-16", "VLP-16", nullptr, 0.3},
                                           Case{"vlp32c", "VLP-32C", nullptr, 0.25}),
                         [](const ::testing::TestParamInfo<Case>& p) {
                           std::string name = p.param.name;
                           std::erase_if(name, [](char ch) { return !std::isalnum(ch); });
                           return name;
                         });

// The records of two pcap files (same link type) merged in time order into `out`.
void merge_pcaps(const std::filesystem::path& a, const std::filesystem::path& b,
                 const std::filesystem::path& out) {
  struct Record {
    std::uint64_t stamp_us;
    std::string bytes;
  };
  std::string header;
  std::vector<Record> records;
  for (const auto& file : {a, b}) {
    std::ifstream in(file, std::ios::binary);
    std::string bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    ASSERT_GE(bytes.size(), 24u) << file;
    header = bytes.substr(0, 24);
    for (std::size_t at = 24; at + 16 <= bytes.size();) {
      std::uint32_t sec = 0, usec = 0, length = 0;
      std::memcpy(&sec, bytes.data() + at, 4);
      std::memcpy(&usec, bytes.data() + at + 4, 4);
      std::memcpy(&length, bytes.data() + at + 8, 4);
      ASSERT_LE(at + 16 + length, bytes.size()) << file;
      records.push_back({std::uint64_t{sec} * 1'000'000 + usec, bytes.substr(at, 16 + length)});
      at += 16 + length;
    }
  }
  std::stable_sort(records.begin(), records.end(),
                   [](const Record& x, const Record& y) { return x.stamp_us < y.stamp_us; });
  std::ofstream o(out, std::ios::binary);
  o << header;
  for (const Record& r : records) o << r.bytes;
}

// The number after `label` in `text` (0 when absent).
unsigned long long number_after(const std::string& text, const std::string& label) {
  const auto at = text.find(label);
  return at == std::string::npos ? 0 : std::stoull(text.substr(at + label.size()));
}

// Two sensors on one port (issue 47): with --model auto the capture's first packets name the model
// and the other sensor's packets are dropped and counted, not decoded as garbage points of the
// first (a VLP-16's 16 lasers with an HDL-32E's blocks).
TEST(FamilyCli, TwoModelsOnOnePortWithModelAutoKeepOnlyTheFirstModelsPoints) {
  const auto dir = stac::testing::fresh_dir("stac_family_two_models");
  for (const char* model : {"VLP-16", "HDL-32E"}) {
    const CliResult sim = stac(std::string("sim --model ") + model +
                               " --scenario parking-lot --seed 11 --duration 1 --out " +
                               (dir / (std::string(model) + ".pcap")).string() + " --truth " +
                               (dir / (std::string(model) + ".jsonl")).string());
    ASSERT_EQ(sim.code, 0) << sim.output;
  }
  merge_pcaps(dir / "VLP-16.pcap", dir / "HDL-32E.pcap", dir / "both.pcap");
  std::map<std::string, CliResult> alone;
  for (const char* model : {"VLP-16", "HDL-32E"}) {
    alone[model] =
        stac("decode --model auto --in " + (dir / (std::string(model) + ".pcap")).string() +
             " --out " + (dir / "alone.csv").string());
    ASSERT_EQ(alone[model].code, 0) << alone[model].output;
  }
  const CliResult both = stac("decode --model auto --in " + (dir / "both.pcap").string() +
                              " --out " + (dir / "both.csv").string());
  ASSERT_EQ(both.code, 0) << both.output;
  // The model of the earliest packet is taken; the other's packets (every one to the port) are
  // dropped, and the points are exactly those of the first model's capture alone.
  const bool vlp_first = both.output.find("packets of a VLP-16") != std::string::npos;
  const std::string first = vlp_first ? "VLP-16" : "HDL-32E",
                    other = vlp_first ? "HDL-32E" : "VLP-16";
  ASSERT_NE(both.output.find("packets of a " + first), std::string::npos) << both.output;
  const unsigned long long other_packets = number_after(alone[other].output, "frames: ");
  EXPECT_GT(other_packets, 700u) << alone[other].output;
  EXPECT_EQ(number_after(both.output, "another model's packets "), other_packets) << both.output;
  EXPECT_GT(number_after(alone[first].output, "  points    "), 10'000u) << alone[first].output;
  EXPECT_EQ(number_after(both.output, "  points    "),
            number_after(alone[first].output, "  points    "))
      << both.output;
}

// A sensor the calibration does not fit, and a model name STAC does not know, are refused with
// what to do.
TEST(FamilyCli, WrongModelOrCalibrationIsNamed) {
  STAC_REQUIRE_SHARED_DATA("velodyne/calib/rosdrivers_64e_s2.1-sztaki.yaml");
  const auto dir = stac::testing::fresh_dir("stac_family_wrong");
  const std::string pcap = (dir / "run.pcap").string();
  const CliResult sim = stac("sim --model VLP-16 --duration 0.3 --out " + pcap + " --truth " +
                             (dir / "t.jsonl").string());
  ASSERT_EQ(sim.code, 0) << sim.output;
  const CliResult unknown = stac("decode --model VLS-128 --in " + pcap + " --out x.csv");
  EXPECT_NE(unknown.code, 0);
  EXPECT_NE(unknown.output.find("not a sensor model: use S2, S2.1, S3"), std::string::npos)
      << unknown.output;
  const CliResult misfit =
      stac("decode --model VLP-16 --calib " +
           stac::testing::shared_data("velodyne/calib/rosdrivers_64e_s2.1-sztaki.yaml").string() +
           " --in " + pcap + " --out x.csv");
  EXPECT_NE(misfit.code, 0);
  EXPECT_NE(misfit.output.find("enables laser 63, a VLP-16 has lasers 0..15"), std::string::npos)
      << misfit.output;
  const CliResult dual =
      stac("sim --model VLP-16 --dual-return --duration 0.3 --out " + (dir / "dual.pcap").string() +
           " --truth " + (dir / "d.jsonl").string());
  ASSERT_EQ(dual.code, 0) << dual.output;
  const CliResult dual_status = stac("status --model VLP-16 --in " + (dir / "dual.pcap").string());
  EXPECT_NE(dual_status.output.find("return mode dual"), std::string::npos) << dual_status.output;
  const CliResult no_dual =
      stac("sim --model S2.1 --dual-return --duration 0.3 --out x.pcap --truth x.jsonl");
  EXPECT_NE(no_dual.code, 0);
  EXPECT_NE(no_dual.output.find("has no dual-return mode"), std::string::npos) << no_dual.output;
}

}  // namespace
}  // namespace stac::tools
