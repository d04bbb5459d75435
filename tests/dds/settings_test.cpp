// The `dds:` section of config/stac.yaml: the shipped file loads, a missing or bad key names it.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "settings/dds_settings.hpp"
#include "test_paths.hpp"

namespace stac::settings {
namespace {

const std::filesystem::path kConfig =
    std::filesystem::path(::stac::testing::source_dir()) / "config/stac.yaml";

std::filesystem::path write_yaml(const std::string& name, const std::string& text) {
  const auto p =
      std::filesystem::temp_directory_path() / (name + std::to_string(getpid()) + ".yaml");
  std::ofstream(p) << text;
  return p;
}

TEST(DdsSettings, ShippedConfigUsesTheLoopbackXml) {
  auto s = load_dds_settings(kConfig);
  ASSERT_TRUE(s) << s.error().message;
  EXPECT_EQ(s->domain_id, 0u);
  EXPECT_EQ(s->topic_prefix, "stac");
  EXPECT_FALSE(s->ros2_names);
  EXPECT_EQ(s->frame_id, "map");
  EXPECT_FALSE(s->tentative_tracks);
  EXPECT_EQ(s->point_cloud_stride, 8u);  // built and written while a viewer reads it
  EXPECT_EQ(s->config_uri.rfind("file:///", 0), 0u);
  EXPECT_NE(s->config_uri.find("config/dds/loopback.xml"), std::string::npos);
}

// A whole dds: section with these three values: the error it is refused with ("" if loaded).
std::string refusal(const std::string& name, const std::string& domain,
                    const std::string& config_file, const std::string& stride) {
  auto s = load_dds_settings(write_yaml(name, "dds:\n  domain_id: " + domain +
                                                  "\n  topic_prefix: stac\n  ros2_names: true\n"
                                                  "  config_file: " +
                                                  config_file +
                                                  "\n  frame_id: map\n  tentative_tracks: false\n"
                                                  "  point_cloud_stride: " +
                                                  stride + "\n"));
  EXPECT_FALSE(s) << name << " loaded";
  return s ? "" : s.error().message;
}

TEST(DdsSettings, MissingAndInvalidKeysAreNamed) {
  auto p = write_yaml("dds_missing",
                      "dds:\n  domain_id: 3\n  topic_prefix: stac\n  ros2_names: true\n"
                      "  config_file: \"\"\n");
  auto s = load_dds_settings(p);
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().message.find("missing required key 'dds.frame_id'"), std::string::npos)
      << s.error().message;
  const std::string domain = refusal("dds_domain", "300", "\"\"", "8");
  EXPECT_NE(domain.find("'dds.domain_id' must be 0..230"), std::string::npos) << domain;
  const std::string file = refusal("dds_file", "1", "nowhere.xml", "8");
  EXPECT_NE(file.find("'dds.config_file'"), std::string::npos) << file;
  EXPECT_NE(file.find("is not a file"), std::string::npos);
  const std::string stride = refusal("dds_stride", "1", "\"\"", "-1");
  EXPECT_NE(stride.find("'dds.point_cloud_stride'"), std::string::npos) << stride;
}

}  // namespace
}  // namespace stac::settings
