#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "settings/settings.hpp"
#include "test_paths.hpp"

namespace stac::settings {
namespace {

const std::filesystem::path kShipped =
    std::filesystem::path(::stac::testing::source_dir()) / "config" / "stac.yaml";

// The shipped file with the line holding `key:` in the tracking section replaced.
std::filesystem::path edited(const std::string& name, const std::string& key,
                             const std::string& replacement) {
  std::ifstream in(kShipped);
  const auto path = std::filesystem::temp_directory_path() / ("stac_tracking_" + name + ".yaml");
  std::ofstream out(path);
  std::string line;
  bool in_tracking = false;
  while (std::getline(in, line)) {
    if (line.rfind("tracking:", 0) == 0) in_tracking = true;
    if (in_tracking && line.find("  " + key + ":") == 0) line = replacement;
    out << line << "\n";
  }
  return path;
}

TEST(TrackingSettings, ShippedConfigMatchesTheDefaults) {
  auto c = load_tracking_config(kShipped);
  ASSERT_TRUE(c) << c.error().message;
  const tracking::TrackerConfig d;
  EXPECT_EQ(c->max_tracks, d.max_tracks);
  EXPECT_EQ(c->max_detections, d.max_detections);
  EXPECT_DOUBLE_EQ(c->gate.mahalanobis_sq, d.gate.mahalanobis_sq);
  EXPECT_DOUBLE_EQ(c->gate.distance_m, d.gate.distance_m);
  EXPECT_DOUBLE_EQ(c->life.max_position_std_m, d.life.max_position_std_m);
  EXPECT_EQ(c->life.confirm_hits, d.life.confirm_hits);
  EXPECT_EQ(c->life.max_coast_scans, d.life.max_coast_scans);
  EXPECT_DOUBLE_EQ(c->kalman.accel_std_mps2, d.kalman.accel_std_mps2);
  EXPECT_DOUBLE_EQ(c->box_smoothing, d.box_smoothing);
}

TEST(TrackingSettings, FlatKeysFillTheNestedFieldOfTheirPart) {
  const auto loaded = [](const std::string& key, const std::string& value) {
    auto c = load_tracking_config(edited("nested_" + key, key, "  " + key + ": " + value));
    EXPECT_TRUE(c) << c.error().message;
    return c ? *c : tracking::TrackerConfig{};
  };
  EXPECT_DOUBLE_EQ(loaded("accel_std_mps2", "2.5").kalman.accel_std_mps2, 2.5);
  EXPECT_DOUBLE_EQ(loaded("gate_distance_m", "2.75").gate.distance_m, 2.75);
  EXPECT_EQ(loaded("max_coast_scans", "7").life.max_coast_scans, 7u);
  EXPECT_DOUBLE_EQ(loaded("absorb_max_width_m", "2.4").object.max_width_m, 2.4);
  EXPECT_DOUBLE_EQ(loaded("absorb_keep_wide_height_m", "1.7").person.wide_min_height_m, 1.7);
  EXPECT_DOUBLE_EQ(loaded("absorb_narrow_gap_m", "0.25").person.gap_m, 0.25);
  EXPECT_DOUBLE_EQ(loaded("overlap_margin_m", "0.75").fragments.overlap_margin_m, 0.75);
  EXPECT_DOUBLE_EQ(loaded("end_on_max_depth_m", "1.5").end_on.max_depth_m, 1.5);
  EXPECT_DOUBLE_EQ(loaded("extent_memory_length_m", "7").body.memory_length_m, 7.0);
  EXPECT_FALSE(loaded("body_gating", "false").body.gating);
}

TEST(TrackingSettings, MissingWrongOrInvalidKeysAreNamed) {
  auto missing = load_tracking_config(edited("missing", "gate_distance_m", ""));
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().message.find("missing required key 'tracking.gate_distance_m'"),
            std::string::npos)
      << missing.error().message;
  auto wrong = load_tracking_config(edited("wrong", "confirm_hits", "  confirm_hits: three"));
  ASSERT_FALSE(wrong);
  EXPECT_NE(wrong.error().message.find("'tracking.confirm_hits' has the wrong type"),
            std::string::npos)
      << wrong.error().message;
  auto invalid = load_tracking_config(edited("invalid", "box_smoothing", "  box_smoothing: 0"));
  ASSERT_FALSE(invalid);
  EXPECT_NE(invalid.error().message.find("box_smoothing"), std::string::npos)
      << invalid.error().message;
  auto absent = load_tracking_config("/nonexistent/stac.yaml");
  ASSERT_FALSE(absent);
  EXPECT_NE(absent.error().message.find("/nonexistent/stac.yaml"), std::string::npos);
}

}  // namespace
}  // namespace stac::settings
