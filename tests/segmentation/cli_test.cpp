// `stac segment` as a user runs it: KITTI scans, simulated captures, bad input, bad config.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "shared_data.hpp"
#include "stac_cli.hpp"
#include "test_paths.hpp"

namespace stac::segmentation {
namespace {

using stac::testing::CliResult;
using stac::testing::stac;

std::filesystem::path fresh_dir(const std::string& name) {
  return stac::testing::fresh_dir("stac_segment_" + name);
}

// The text of the shipped config/stac.yaml.
std::string shipped_config() {
  std::ifstream in(std::string(::stac::testing::source_dir()) + "/config/stac.yaml");
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// The number after `label` in the summary, e.g. "segments   217 of ...".
long summary_number(const std::string& output, const std::string& label) {
  const auto at = output.find(label);
  if (at == std::string::npos) return -1;
  return std::stol(output.substr(at + label.size()));
}

TEST(SegmentCli, KittiScanGivesCsvPictureAndSummary) {
  STAC_REQUIRE_SHARED_DATA("kitti/000000.bin");
  const auto dir = fresh_dir("kitti");
  const CliResult r =
      stac("segment --in " + stac::testing::shared_data("kitti/000000.bin").string() + " --out " +
           (dir / "s.csv").string() + " --png " + (dir / "s.png").string());
  ASSERT_EQ(r.code, 0) << r.output;
  const long segments = summary_number(r.output, "segments   ");
  EXPECT_GT(segments, 30) << r.output;
  EXPECT_NE(r.output.find("overflow   points 0, cells 0, segments 0"), std::string::npos)
      << r.output;
  std::ifstream csv(dir / "s.csv");
  std::string header, line;
  std::getline(csv, header);
  EXPECT_EQ(
      header,
      "id,points,centroid_x,centroid_y,centroid_z,box_x,box_y,length,width,height,yaw,z_min,z_max");
  long rows = 0;
  while (std::getline(csv, line)) {
    ++rows;
    std::istringstream in(line);
    std::string field;
    int fields = 0;
    while (std::getline(in, field, ',')) ++fields;
    EXPECT_EQ(fields, 13) << line;
  }
  EXPECT_EQ(rows, segments);
  EXPECT_GT(std::filesystem::file_size(dir / "s.png"), 20'000u);
}

TEST(SegmentCli, SimulatedCaptureIsDecodedAndSegmented) {
  STAC_REQUIRE_SHARED_DATA("velodyne/calib/rosdrivers_64e_s2.1-sztaki.yaml");
  const auto dir = fresh_dir("capture");
  const auto pcap = (dir / "run.pcap").string();
  const CliResult sim = stac("sim --scenario parking-lot --seed 11 --duration 0.5 --out " + pcap +
                             " --truth " + (dir / "run.jsonl").string());
  ASSERT_EQ(sim.code, 0) << sim.output;
  const CliResult r = stac("segment --in " + pcap + " --scan 1");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("run.pcap scan 1"), std::string::npos) << r.output;
  EXPECT_GT(summary_number(r.output, "points     "), 50'000) << r.output;
  EXPECT_GT(summary_number(r.output, "segments   "), 10) << r.output;  // parked cars, poles

  const CliResult missing = stac("segment --in " + pcap + " --scan 40");
  EXPECT_EQ(missing.code, 1);
  EXPECT_NE(missing.output.find("--scan 40 is not among them"), std::string::npos)
      << missing.output;

  // The format comes from the file's first bytes, not its name.
  std::filesystem::copy_file(pcap, dir / "capture.bin");
  const CliResult named_bin = stac("segment --in " + (dir / "capture.bin").string() + " --scan 1");
  ASSERT_EQ(named_bin.code, 0) << named_bin.output;
  EXPECT_NE(named_bin.output.find("capture.bin scan 1"), std::string::npos) << named_bin.output;
  EXPECT_EQ(summary_number(named_bin.output, "segments   "),
            summary_number(r.output, "segments   "));
  if (std::filesystem::exists(stac::testing::shared_data("kitti/000000.bin"))) {
    std::filesystem::copy_file(stac::testing::shared_data("kitti/000000.bin"), dir / "scan.dat");
    const CliResult kitti = stac("segment --in " + (dir / "scan.dat").string());
    ASSERT_EQ(kitti.code, 0) << kitti.output;
    EXPECT_EQ(summary_number(kitti.output, "points     "), 124668) << kitti.output;
  }
}

// A KITTI raw drive folder is read as `stac process` reads it (formats::RecordedDrive): its scan N
// is the folder's Nth .bin file, segmented alike; a folder that is no drive is named as such.
TEST(SegmentCli, ScanNOfAKittiRawDriveFolderIsItsNthScanFile) {
  STAC_REQUIRE_SHARED_DATA("kitti-raw-seq/velodyne_points/data/0000000003.bin");
  const std::string drive = stac::testing::shared_data("kitti-raw-seq").string();
  const CliResult folder = stac("segment --in " + drive + " --scan 3");
  ASSERT_EQ(folder.code, 0) << folder.output;
  EXPECT_NE(folder.output.find("kitti-raw-seq scan 3"), std::string::npos) << folder.output;
  const CliResult file = stac("segment --in " + drive + "/velodyne_points/data/0000000003.bin");
  ASSERT_EQ(file.code, 0) << file.output;
  EXPECT_EQ(summary_number(folder.output, "segments   "),
            summary_number(file.output, "segments   "))
      << folder.output << file.output;
  EXPECT_GT(summary_number(folder.output, "segments   "), 10) << folder.output;

  const CliResult past = stac("segment --in " + drive + " --scan 40");
  EXPECT_EQ(past.code, 1);
  EXPECT_NE(past.output.find("holds 40 complete scans; --scan 40 is not among them"),
            std::string::npos)
      << past.output;
  const auto empty = fresh_dir("no_drive");
  const CliResult not_drive = stac("segment --in " + empty.string());
  EXPECT_EQ(not_drive.code, 1);
  EXPECT_NE(not_drive.output.find("a folder but not a KITTI raw drive"), std::string::npos)
      << not_drive.output;
}

TEST(SegmentCli, RejectsAFileThatIsNotAKittiScan) {
  const auto dir = fresh_dir("notscan");
  std::ofstream(dir / "odd.bin") << "seventeen bytes!!";
  const CliResult r = stac("segment --in " + (dir / "odd.bin").string());
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("17 bytes is not a KITTI scan"), std::string::npos) << r.output;
}

TEST(SegmentCli, ConfigErrorsNameTheKey) {
  STAC_REQUIRE_SHARED_DATA("kitti/000000.bin");
  const auto dir = fresh_dir("config");
  const std::string shipped = shipped_config();
  const std::string scan = stac::testing::shared_data("kitti/000000.bin").string();
  {
    std::string yaml = shipped;
    const auto at = yaml.find("  ground_radius_m:");
    yaml.erase(at, yaml.find('\n', at) - at + 1);
    std::ofstream(dir / "missing.yaml") << yaml;
    const CliResult r =
        stac("segment --config " + (dir / "missing.yaml").string() + " --in " + scan);
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(r.output.find("missing required key 'segmentation.ground_radius_m'"),
              std::string::npos)
        << r.output;
  }
  {
    std::string yaml = shipped;
    const auto at = yaml.find("  cell_m: 0.15");
    yaml.replace(at, 14, "  cell_m: 0.0");
    std::ofstream(dir / "zero.yaml") << yaml;
    const CliResult r = stac("segment --config " + (dir / "zero.yaml").string() + " --in " + scan);
    EXPECT_EQ(r.code, 1);
    // Named as every configuration error is: the file, 'section.key', what, the line.
    EXPECT_NE(r.output.find((dir / "zero.yaml").string() +
                            ": 'segmentation.cell_m' must be in [0.02, 5] m (line "),
              std::string::npos)
        << r.output;
  }
}

// Capacities beyond their bounds are errors before anything is allocated; within them, a machine
// without the memory (here: 400 MB of address space) gets a message and exit code 1, not an abort.
TEST(SegmentCli, CapacitiesAreBoundedAndMemoryLeftShortIsAnError) {
  STAC_REQUIRE_SHARED_DATA("kitti/000000.bin");
  const auto dir = fresh_dir("capacities");
  const std::string shipped = shipped_config();
  const std::string scan = stac::testing::shared_data("kitti/000000.bin").string();
  const auto with = [&](const std::string& name,
                        std::initializer_list<std::pair<std::string, std::string>> edits) {
    std::string yaml = shipped;
    for (const auto& [from, to] : edits) {
      const auto at = yaml.find(from);
      EXPECT_NE(at, std::string::npos) << from;
      yaml.replace(at, from.size(), to);
    }
    const auto path = dir / name;
    std::ofstream(path) << yaml;
    return path.string();
  };
  const CliResult over = stac(
      "segment --config " +
      with("over.yaml", {{"  max_occupied_cells: 200000 ", "  max_occupied_cells: 100000000 "}}) +
      " --in " + scan);
  EXPECT_EQ(over.code, 1);
  EXPECT_NE(over.output.find("'segmentation.max_occupied_cells' must be in 1..4194304"),
            std::string::npos)
      << over.output;
  const std::string most =
      with("most.yaml", {{"  max_points: 300000 ", "  max_points: 10000000 "},
                         {"  max_occupied_cells: 200000 ", "  max_occupied_cells: 4194304 "},
                         {"  max_segments: 2000 ", "  max_segments: 1000000 "}});
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "the memory limit part: AddressSanitizer reserves terabytes of address space for "
                  "its shadow memory, which a 400 MB `ulimit -v` refuses at start-up";
#endif
  const std::string cmd = "bash -c 'ulimit -v 400000; " + std::string(::stac::testing::stac_cli()) +
                          " segment --config " + most + " --in " + scan + " --out " +
                          (dir / "x.csv").string() + "' 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  ASSERT_NE(p, nullptr);
  std::string out;
  char buf[4096];
  while (const std::size_t n = std::fread(buf, 1, sizeof(buf), p)) out.append(buf, n);
  const int status = pclose(p);
  ASSERT_TRUE(WIFEXITED(status)) << out;
  EXPECT_EQ(WEXITSTATUS(status), 1) << out;
  EXPECT_NE(out.find("stac: out of memory while allocating what the configuration asks for"),
            std::string::npos)
      << out;
}

}  // namespace
}  // namespace stac::segmentation
