// The configuration readers of the edge: the shipped config/stac.yaml loads, and every broken
// key is named.
#include "settings/settings.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <fstream>
#include <regex>
#include <sstream>
#include <vector>

#include "settings/config_section.hpp"
#include "settings/dds_settings.hpp"
#include "settings/run_settings.hpp"
#include "test_paths.hpp"

namespace stac::settings {
namespace {

const std::filesystem::path kShipped =
    std::filesystem::path(::stac::testing::source_dir()) / "config/stac.yaml";

// The shipped file with one line of the ego section replaced.
std::filesystem::path with_line(const std::string& pattern, const std::string& replacement) {
  std::ifstream in(kShipped);
  std::stringstream text;
  text << in.rdbuf();
  const std::string edited = std::regex_replace(text.str(), std::regex(pattern), replacement);
  EXPECT_NE(edited, text.str()) << pattern;
  // One file per test and process: ctest runs the tests of this file in parallel.
  const auto path = std::filesystem::temp_directory_path() /
                    ("stac_settings_test_" +
                     std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) +
                     "_" + std::to_string(::getpid()) + ".yaml");
  std::ofstream(path) << edited;
  return path;
}

TEST(EgoSettings, TheShippedConfigLoads) {
  auto s = load_ego_settings(kShipped);
  ASSERT_TRUE(s) << s.error().message;
  EXPECT_FALSE(s->origin);  // auto
  EXPECT_NEAR(s->deskew.vehicle_T_sensor.translation().z(), 1.73, 1e-12);
  EXPECT_EQ(s->history.capacity, 2500u);  // 10 s at 200 Hz + 25 %
  EXPECT_EQ(s->deskew.bucket_ns, 100'000);
  EXPECT_EQ(s->ins_port, 5602);
}

TEST(EgoSettings, OriginAndExtrinsicsAreRead) {
  auto s = load_ego_settings(with_line("origin: auto", "origin: [44.2, -76.5, 80.0]"));
  ASSERT_TRUE(s) << s.error().message;
  ASSERT_TRUE(s->origin);
  EXPECT_EQ(s->origin->lat_deg, 44.2);
  auto yawed = load_ego_settings(
      with_line(R"(sensor_rpy_deg: \[0.0, 0.0, 0.0\])", "sensor_rpy_deg: [0, 0, 90]"));
  ASSERT_TRUE(yawed) << yawed.error().message;
  const Eigen::Vector3d x = yawed->deskew.vehicle_T_sensor.linear() * Eigen::Vector3d::UnitX();
  EXPECT_NEAR(x.y(), 1.0, 1e-12);  // the sensor's forward points to the vehicle's left
}

TEST(EgoSettings, EveryBrokenKeyIsNamed) {
  const std::pair<std::string, std::string> cases[] = {
      {"origin: auto", "origin: somewhere"},
      {"origin: auto", "origin: [95.0, 0.0, 0.0]"},
      {R"(sensor_xyz_m: \[0.0, 0.0, 1.73\])", "sensor_xyz_m: [0.0, 1.73]"},
      {"pose_history_s: 10.0", "pose_history_s: 0"},
      {"ins_port: 5602", "ins_port: 70000"},
      {"max_alignment_status: 2", "max_alignment_status: nine"},
      {"deskew_bucket_us: 100", "deskew_buckets_us: 100"},
  };
  for (const auto& [pattern, replacement] : cases) {
    auto s = load_ego_settings(with_line(pattern, replacement));
    ASSERT_FALSE(s) << replacement;
    const std::string key = replacement.substr(0, replacement.find(':'));
    EXPECT_NE(s.error().message.find("ego." + key), std::string::npos) << s.error().message;
  }
}

// A file that is not a configuration, or a key or section the shipped file does not know.
TEST(ConfigFile, WhatIsNotAConfigurationIsNamedAndNothingThrows) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("stac_cfg_dir_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto write = [&](const std::string& name, const std::string& text) {
    const auto path = dir / name;
    std::ofstream(path) << text;
    return path;
  };
  struct Case {
    std::filesystem::path file;
    std::string expected;
  };
  const Case cases[] = {
      {dir, "is a directory"},
      {dir / "absent.yaml", "no such configuration file"},
      {write("scalar.yaml", "42\n"),
       "the configuration is a single value; it must be a map of sections"},
      {write("list.yaml", "- velodyne\n- ego\n"), "the configuration is a list"},
      {write("empty.yaml", ""), "the configuration is empty"},
      {write("binary.yaml", std::string("\x01\x02\xff\xfe\x00garbage", 12)),
       "cannot read the configuration"},
      {write("section_list.yaml", "velodyne: [1, 2]\n"),
       "the 'velodyne:' section (line 1) is a list; it must be a map of keys"},
  };
  for (const auto& c : cases) {
    auto s = load_velodyne_settings(c.file);
    ASSERT_FALSE(s) << c.file;
    EXPECT_NE(s.error().message.find(c.expected), std::string::npos) << s.error().message;
  }
  std::filesystem::remove_all(dir);
}

TEST(ConfigFile, AMisspelledKeyOrSectionIsAnErrorWithTheNearestKnownName) {
  auto typo =
      load_velodyne_settings(with_line(R"(sender_address: "")", R"(sender_adress: "10.9.9.9")"));
  ASSERT_FALSE(typo);
  EXPECT_NE(typo.error().message.find("unknown key 'velodyne.sender_adress' (line "),
            std::string::npos)
      << typo.error().message;
  EXPECT_NE(typo.error().message.find("did you mean 'sender_address'?"), std::string::npos)
      << typo.error().message;
  // Any section's loader checks every section's name.
  auto section = load_velodyne_settings(with_line("\nsegmentation:", "\nsegmentaton:"));
  ASSERT_FALSE(section);
  EXPECT_NE(section.error().message.find("unknown section 'segmentaton:'"), std::string::npos)
      << section.error().message;
  EXPECT_NE(section.error().message.find("did you mean 'segmentation'?"), std::string::npos)
      << section.error().message;
  auto far =
      load_ego_settings(with_line("  ins_port: 5602", "  ins_port: 5602\n  wheelbase_m: 2.7"));
  ASSERT_FALSE(far);
  EXPECT_NE(far.error().message.find("unknown key 'ego.wheelbase_m'"), std::string::npos)
      << far.error().message;
}

// One form for every value a check refuses (issue 51): "FILE: 'section.key' WHAT (line N)", N the
// line of the key in the file, whichever section and whoever checks it (the reader, or the
// library's own validation: segmentation::validate, the tracker's).
TEST(ConfigFile, EveryRefusedValueNamesTheFileTheKeyAndItsLine) {
  std::ifstream in(kShipped);
  std::vector<std::string> lines;
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  const auto line_of = [&](const std::string& start) {
    for (std::size_t i = 0; i < lines.size(); ++i)
      if (lines[i].rfind(start, 0) == 0) return std::to_string(i + 1);
    ADD_FAILURE() << "no line starts with " << start;
    return std::string("?");
  };
  const auto expect = [](const std::string& message, const std::string& wanted) {
    EXPECT_NE(message.find(wanted), std::string::npos) << message << "\nwanted: " << wanted;
  };
  const auto port = with_line("\n  port: 2368", "\n  port: 70000");
  auto velodyne = load_velodyne_settings(port);
  ASSERT_FALSE(velodyne);
  expect(velodyne.error().message, port.string() + ": 'velodyne.port' must be 1..65535 (line " +
                                       line_of("  port: 2368") + ")");
  const auto bitrate = with_line("\n  bitrate_bps: ([0-9]+)", "\n  bitrate_bps: 5");
  auto can = load_can_settings(bitrate);
  ASSERT_FALSE(can);
  expect(can.error().message, bitrate.string() +
                                  ": 'can.bitrate_bps' must be in 10000..1000000 "
                                  "(classic CAN) (line " +
                                  line_of("  bitrate_bps:") + ")");
  const auto cell = with_line("\n  cell_m: 0.15", "\n  cell_m: 0.0");
  auto segmentation = load_segmentation_settings(cell);
  ASSERT_FALSE(segmentation);
  expect(segmentation.error().message, cell.string() +
                                           ": 'segmentation.cell_m' must be in "
                                           "[0.02, 5] m (line " +
                                           line_of("  cell_m: 0.15") + ")");
  const auto smoothing = with_line("\n  box_smoothing: ([0-9.]+)", "\n  box_smoothing: 2");
  auto tracking = load_tracking_config(smoothing);
  ASSERT_FALSE(tracking);
  expect(tracking.error().message, smoothing.string() +
                                       ": 'tracking.box_smoothing' must be in "
                                       "(0, 1] (line " +
                                       line_of("  box_smoothing:") + ")");
}

TEST(ConfigFile, AKeyWrittenTwiceIsAnError) {
  auto twice =
      load_tracking_config(with_line("  max_tracks: 512", "  max_tracks: 512\n  max_tracks: 0"));
  ASSERT_FALSE(twice);
  EXPECT_NE(twice.error().message.find("key 'tracking.max_tracks' (line "), std::string::npos)
      << twice.error().message;
  EXPECT_NE(twice.error().message.find("appears twice"), std::string::npos)
      << twice.error().message;
}

TEST(ConfigFile, CapacitiesOfTwoSectionsAreCheckedTogether) {
  auto s =
      load_pipeline_settings(with_line("accumulated_points: 1024", "accumulated_points: 1000000"));
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().message.find(
                "'tracking.max_tracks' and 'classification:': max_tracks x accumulated_points"),
            std::string::npos)
      << s.error().message;
}

TEST(ConfigFile, TheShippedFileHasEveryKeyTheLoadersRead) {
  EXPECT_TRUE(load_pipeline_settings(kShipped)) << load_pipeline_settings(kShipped).error().message;
}

// Issue 31: .nan and .inf are numbers to YAML, and NaN passes every range check written as
// "x < lo || x > hi". Every number of the shipped file, made .nan, .inf or -.inf in turn, is
// refused naming its key (a float as not finite; an integer as the wrong type).
TEST(ConfigFile, EveryNumberMustBeFinite) {
  std::ifstream in(kShipped);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  const std::regex section_line(R"(^([a-z_]+):.*)");
  const std::regex key_line(R"(^  ([a-z_0-9]+): *([-+0-9.eE]+)( +#.*)?$)");
  const std::filesystem::path name = kShipped.parent_path() / "finite_numbers_in_memory.yaml";
  std::size_t numbers = 0;
  std::string section;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    std::smatch m;
    if (std::regex_match(lines[i], m, section_line)) section = m[1];
    if (!std::regex_match(lines[i], m, key_line)) continue;
    char* end = nullptr;
    const std::string value = m[2];
    std::strtod(value.c_str(), &end);
    if (*end != '\0') continue;
    ++numbers;
    const std::string key = section + "." + std::string(m[1]);
    for (const char* bad : {".nan", ".inf", "-.inf"}) {
      std::string text;
      for (std::size_t j = 0; j < lines.size(); ++j)
        text += (j == i ? "  " + std::string(m[1]) + ": " + bad : lines[j]) + "\n";
      const ConfigSnapshot snapshot(name, text);
      std::string errors;
      if (auto p = load_pipeline_settings(name); !p) errors += p.error().message + "\n";
      if (auto r = load_run_settings(name); !r) errors += r.error().message + "\n";
      if (auto c = load_can_settings(name); !c) errors += c.error().message + "\n";
      if (auto d = load_dds_settings(name); !d) errors += d.error().message + "\n";
      EXPECT_NE(errors.find("'" + key + "'"), std::string::npos)
          << key << ": " << bad << " was accepted" << (errors.empty() ? "" : ": " + errors);
    }
  }
  EXPECT_GT(numbers, 40u);  // the file's numbers were found
  auto nan_rpm = load_velodyne_settings(with_line("min_rpm: [0-9.]+", "min_rpm: .nan"));
  ASSERT_FALSE(nan_rpm);
  EXPECT_NE(nan_rpm.error().message.find("'velodyne.min_rpm' must be a finite number, not '.nan'"),
            std::string::npos)
      << nan_rpm.error().message;
}

// Issue 33: the sensor model names every supported Velodyne or "auto"; a model's calibration
// for --model/--sensor comes from velodyne.model_calibrations, paths relative to the file; what
// does not fit is named, and nothing throws.
TEST(VelodyneSettings, ModelsAndTheirCalibrationsAreReadAndBrokenOnesNamed) {
  auto shipped = load_velodyne_settings(kShipped);
  ASSERT_TRUE(shipped) << shipped.error().message;
  EXPECT_EQ(shipped->assembler.decoder.model, velodyne::Model::kS2_1);
  EXPECT_FALSE(shipped->model_auto);
  ASSERT_EQ(shipped->model_calibrations.count(velodyne::Model::kVlp32c), 1u);
  EXPECT_EQ(shipped->model_calibrations.at(velodyne::Model::kVlp32c),
            kShipped.parent_path() / "calib/vlp32c.yaml");
  EXPECT_EQ(shipped->model_calibrations.size(), 5u);
  // Switching to a model with other lasers takes its calibration; the same lasers keep the file.
  VelodyneSettings s = *shipped;
  ASSERT_TRUE(use_velodyne_model(s, velodyne::Model::kS3, false));
  EXPECT_EQ(s.calibration, shipped->calibration);
  ASSERT_TRUE(use_velodyne_model(s, velodyne::Model::kVlp16, false));
  EXPECT_EQ(s.calibration, kShipped.parent_path() / "calib/vlp16.yaml");
  s = *shipped;
  ASSERT_TRUE(use_velodyne_model(s, velodyne::Model::kHdl32e, true));  // --calib given: kept
  EXPECT_EQ(s.calibration, shipped->calibration);
  s = *shipped;
  s.model_calibrations.clear();
  const auto none = use_velodyne_model(s, velodyne::Model::kVlp16, false);
  ASSERT_FALSE(none);
  EXPECT_NE(none.error().message.find("pass --calib, or name one in velodyne.model_calibrations"),
            std::string::npos)
      << none.error().message;

  auto automatic = load_velodyne_settings(with_line("  model: S2.1 ", "  model: auto "));
  ASSERT_TRUE(automatic) << automatic.error().message;
  EXPECT_TRUE(automatic->model_auto);
  auto vlp = load_velodyne_settings(with_line("  model: S2.1 ", "  model: VLP-16 "));
  ASSERT_TRUE(vlp) << vlp.error().message;
  EXPECT_EQ(vlp->assembler.decoder.model, velodyne::Model::kVlp16);
  const std::pair<std::string, std::string> broken[] = {
      {"  model: S2.1 ", "  model: VLS-128 "},
      {"    VLP-32C: calib/vlp32c.yaml", "    VLP-64: calib/vlp32c.yaml"},
      {"    VLP-32C: calib/vlp32c.yaml", "    VLP-32C: [calib/vlp32c.yaml]"},
      {"    VLP-32C: calib/vlp32c.yaml", "    [a, b]: calib/vlp32c.yaml"},
  };
  for (const auto& [pattern, replacement] : broken) {
    auto b = load_velodyne_settings(with_line(pattern, replacement));
    ASSERT_FALSE(b) << replacement;
    EXPECT_NE(b.error().message.find("velodyne.model"), std::string::npos) << b.error().message;
  }
}

// classification.model's line (velodyne.model is another key of the same name).
const char* const kModelLine = R"(model: \S+( +# track classifier))";

// A configuration in memory reads as its file would: the same sections from a name no file has,
// paths relative to that name, the same errors; gone with the snapshot, the name is a missing
// file again.
TEST(ConfigSnapshot, SectionsAreReadFromMemoryUnderTheFilesName) {
  std::ifstream in(kShipped);
  std::stringstream text;
  text << in.rdbuf();
  // Beside the shipped file, so that its relative paths (the calibration) lead where they do.
  const std::filesystem::path name = kShipped.parent_path() / "no_such_file_in_memory.yaml";
  {
    const ConfigSnapshot snapshot(name, text.str());
    auto pipeline = load_pipeline_settings(name);
    ASSERT_TRUE(pipeline) << pipeline.error().message;
    auto from_file = load_pipeline_settings(kShipped);
    ASSERT_TRUE(from_file);
    EXPECT_EQ(pipeline->ego.estimator.ins_timeout_ns, from_file->ego.estimator.ins_timeout_ns);
    EXPECT_EQ(pipeline->velodyne.calibration, from_file->velodyne.calibration);
    auto classification = load_classification_settings(name);
    ASSERT_TRUE(classification);
    EXPECT_EQ(classification->model, name.parent_path() / "models/stac_default.stacmodel");
    {
      const ConfigSnapshot newer(name, "velodyne: [1, 2]\n");  // the newest of a name wins
      auto bad = load_ego_settings(name);
      ASSERT_FALSE(bad);
      EXPECT_NE(bad.error().message.find(name.string() + ": missing the 'ego:' section"),
                std::string::npos)
          << bad.error().message;
    }
    EXPECT_TRUE(load_ego_settings(name));
    const ConfigSnapshot broken("/nonexistent/broken.yaml", "a: [1, 2\n");
    auto unreadable = load_ego_settings("/nonexistent/broken.yaml");
    ASSERT_FALSE(unreadable);
    EXPECT_NE(unreadable.error().message.find("/nonexistent/broken.yaml: cannot read the "
                                              "configuration"),
              std::string::npos)
        << unreadable.error().message;
  }
  auto gone = load_ego_settings(name);
  ASSERT_FALSE(gone);
  EXPECT_NE(gone.error().message.find("no such configuration file"), std::string::npos);
}

TEST(ClassificationSettings, TheShippedConfigLoadsAndPathsAreRelativeToTheFile) {
  auto s = load_classification_settings(kShipped);
  ASSERT_TRUE(s) << s.error().message;
  EXPECT_EQ(s->classifier.accumulated_points, 1024u);
  EXPECT_EQ(s->classifier.holistic_every, 5u);
  EXPECT_EQ(s->classifier.descriptors.max_points, 1024u);
  const auto edited = with_line(kModelLine, "model: models/x.stacmodel$1");
  auto m = load_classification_settings(edited);
  ASSERT_TRUE(m) << m.error().message;
  EXPECT_EQ(m->model, edited.parent_path() / "models/x.stacmodel");
  auto none = load_classification_settings(with_line(kModelLine, "model:  none$1"));
  ASSERT_TRUE(none) << none.error().message;
  EXPECT_TRUE(none->model.empty());
}

TEST(ClassificationSettings, EveryBrokenKeyIsNamed) {
  const std::pair<std::string, std::string> cases[] = {
      {kModelLine, "model: \"\"$1"},
      {"accumulated_points: 1024", "accumulated_points: 0"},
      {"holistic_every: 5", "holistic_every: 0"},
      {"holistic_every: 5", "holistic_every: often"},
      {"max_segment_points: 1024", "max_segment_pts: 1024"},
  };
  for (const auto& [pattern, replacement] : cases) {
    auto s = load_classification_settings(with_line(pattern, replacement));
    ASSERT_FALSE(s) << replacement;
    const std::string key = replacement.substr(0, replacement.find(':'));  // a misspelling: itself
    EXPECT_NE(s.error().message.find("classification." + key), std::string::npos)
        << s.error().message;
  }
}

}  // namespace
}  // namespace stac::settings
