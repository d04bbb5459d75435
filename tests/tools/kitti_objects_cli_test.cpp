// `stac kitti-objects` on the real KITTI object frames: every labelled object within 40 m is
// reported with its segmentation status and class, the report agrees with the table, and broken
// folders and files are refused with a message naming them.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "formats/kitti_files.hpp"
#include "shared_data.hpp"
#include "stac_cli.hpp"

namespace stac::tools {
namespace {

using stac::testing::stac;

constexpr const char* kKitti = "kitti-object/velodyne/000000.bin";

TEST(KittiObjectsCli, EveryLabelledObjectWithinRangeIsReportedSegmentedAndClassified) {
  STAC_REQUIRE_SHARED_DATA(kKitti);
  const auto dir = stac::testing::fresh_dir("kitti_objects");
  const std::string kitti = stac::testing::shared_data("kitti-object").string();
  const auto r = stac("kitti-objects --dir " + kitti + " --report " + dir.string());
  ASSERT_EQ(r.code, 0) << r.output;
  // Frame 000000's pedestrian 8.4 m ahead: 460 points in its box, one segment, a pedestrian.
  EXPECT_NE(r.output.find("000000  Pedestrian"), std::string::npos) << r.output;
  const nlohmann::json m = nlohmann::json::parse(std::ifstream(dir / "metrics.json"));
  EXPECT_EQ(m["frames"].get<int>(), 6);
  const int objects = m["objects"].get<int>();
  EXPECT_GE(objects, 5);
  std::ifstream csv(dir / "objects.csv");
  std::string line;
  ASSERT_TRUE(std::getline(csv, line));
  int rows = 0, segmented = 0, pedestrians_right = 0;
  while (std::getline(csv, line)) {
    ++rows;
    segmented += line.find(",segmented,") != std::string::npos ? 1 : 0;
    if (line.rfind("000000,Pedestrian,pedestrian,", 0) == 0)
      pedestrians_right += line.find(",pedestrian,pedestrian,") != std::string::npos ? 1 : 0;
  }
  EXPECT_EQ(rows, objects);
  EXPECT_GE(segmented, objects - 1);
  EXPECT_EQ(pedestrians_right, 1) << r.output;
  for (int f = 0; f < 6; ++f) {
    const auto png = dir / ("frame_00000" + std::to_string(f) + ".png");
    EXPECT_GT(std::filesystem::file_size(png), 10000u) << png;
  }
}

TEST(KittiObjectsCli, BrokenFoldersAndFilesAreNamed) {
  STAC_REQUIRE_SHARED_DATA(kKitti);
  const auto dir = stac::testing::fresh_dir("kitti_objects_bad");
  const auto empty = stac("kitti-objects --dir " + dir.string());
  EXPECT_NE(empty.code, 0);
  EXPECT_NE(empty.output.find("no velodyne/*.bin"), std::string::npos) << empty.output;

  // A copy of frame 000000 with a broken label file, then with a broken calibration.
  const std::filesystem::path src = stac::testing::shared_data("kitti-object");
  for (const char* sub : {"velodyne", "calib", "label_2"})
    std::filesystem::create_directories(dir / sub);
  std::filesystem::copy_file(src / "velodyne/000000.bin", dir / "velodyne/000000.bin");
  std::filesystem::copy_file(src / "calib/000000.txt", dir / "calib/000000.txt");
  std::ofstream(dir / "label_2/000000.txt") << "Car 0.00 0 1.5 10 20\n";
  const auto labels = stac("kitti-objects --dir " + dir.string());
  EXPECT_NE(labels.code, 0);
  EXPECT_NE(labels.output.find("label_2/000000.txt:1: not a KITTI label line"), std::string::npos)
      << labels.output;
  const std::string box = " 0.00 0 1.5 10 20 30 40 1.5 1.6 3.9 1 1.7 12 0.1\n";  // 14 numbers
  const std::pair<std::string, std::string> label_cases[] = {
      {"Dragon" + box, "label_2/000000.txt:1: type 'Dragon' is not a KITTI class"},
      {"Car 0.00 0 1.5 10 20 30 40 -1.5 1.6 3.9 1 1.7 12 0.1\n",
       "label_2/000000.txt:1: negative dimensions"},
      {"Car" + box.substr(0, box.size() - 1) + " 7\n",
       "label_2/000000.txt:1: not a KITTI label line"},
  };
  for (const auto& [text, expected] : label_cases) {
    std::ofstream(dir / "label_2/000000.txt", std::ios::trunc) << text;
    const auto r = stac("kitti-objects --dir " + dir.string());
    EXPECT_NE(r.code, 0) << text;
    EXPECT_NE(r.output.find(expected), std::string::npos) << r.output;
  }
  std::ofstream(dir / "label_2/000000.txt", std::ios::trunc) << "Car" + box;
  std::ofstream(dir / "calib/000000.txt", std::ios::trunc) << "P0: 1 2 3\n";
  const auto calib = stac("kitti-objects --dir " + dir.string());
  EXPECT_NE(calib.code, 0);
  EXPECT_NE(calib.output.find("Tr_velo_to_cam"), std::string::npos) << calib.output;
  // All zeros: every point at the camera, every object at range 0, not a calibration.
  std::ofstream(dir / "calib/000000.txt", std::ios::trunc)
      << "R0_rect: 0 0 0 0 0 0 0 0 0\nTr_velo_to_cam: 0 -1 0 0 0 0 -1 -0.08 1 0 0 -0.27\n";
  const auto singular = stac("kitti-objects --dir " + dir.string());
  EXPECT_NE(singular.code, 0);
  EXPECT_NE(singular.output.find("'R0_rect:' is not a rotation"), std::string::npos)
      << singular.output;
}

TEST(KittiFiles, LabelBoxesHoldTheirCentreAndNotWhatIsBesideThem) {
  formats::KittiObject car;
  car.height = 1.5;
  car.width = 1.8;
  car.length = 4.0;
  car.bottom_centre = {2.0, 1.6, 20.0};
  car.rotation_y = M_PI / 2;  // length along the camera's -z... i.e. across the view
  EXPECT_TRUE(car.contains({2.0, 0.85, 20.0}, 0.0));
  EXPECT_TRUE(car.contains({2.0, 0.85, 21.9}, 0.0));   // 1.9 m along its length
  EXPECT_FALSE(car.contains({3.5, 0.85, 20.0}, 0.0));  // 1.5 m across: outside its width
  EXPECT_FALSE(car.contains({2.0, -0.2, 20.0}, 0.0));  // above its roof (y down)
  EXPECT_TRUE(car.contains({2.0, 1.65, 20.0}, 0.1));   // just under its bottom, with margin
}

}  // namespace
}  // namespace stac::tools
