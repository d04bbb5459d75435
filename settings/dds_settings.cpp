#include "settings/dds_settings.hpp"

#include <string>

#include "settings/config_section.hpp"

namespace stac::settings {

rt::Result<dds::PublisherConfig> load_dds_settings(const std::filesystem::path& config_file) {
  auto section = ConfigSection::open(config_file, "dds");
  if (!section) return rt::Unexpected<rt::Error>{section.error()};
  const ConfigSection& d = *section;
  dds::PublisherConfig c;
  int domain = 0;
  std::string cyclone;
  STAC_CONFIG_GET(d, int, "domain_id", domain);
  STAC_CONFIG_GET(d, std::string, "topic_prefix", c.topic_prefix);
  STAC_CONFIG_GET(d, bool, "ros2_names", c.ros2_names);
  STAC_CONFIG_GET(d, std::string, "config_file", cyclone);
  STAC_CONFIG_GET(d, std::string, "frame_id", c.frame_id);
  STAC_CONFIG_GET(d, bool, "tentative_tracks", c.tentative_tracks);
  int stride = 0;
  STAC_CONFIG_GET(d, int, "point_cloud_stride", stride);
  if (stride < 0 || stride > 1000)
    return d.error("point_cloud_stride", "must be 0 (no point cloud) .. 1000");
  c.point_cloud_stride = static_cast<std::uint32_t>(stride);
  if (domain < 0 || domain > 230) return d.error("domain_id", "must be 0..230");
  c.domain_id = static_cast<std::uint32_t>(domain);
  if (c.topic_prefix.empty() || c.topic_prefix.front() == '/' || c.topic_prefix.back() == '/') {
    return d.error("topic_prefix", "must be a non-empty name without leading or trailing '/'");
  }
  if (c.frame_id.empty() || c.frame_id.size() > 31)
    return d.error("frame_id", "must be 1..31 characters");
  if (!cyclone.empty()) {
    const std::filesystem::path p = d.path(cyclone);
    if (!std::filesystem::is_regular_file(p))
      return d.error("config_file", "'" + p.string() + "' is not a file");
    c.config_uri = "file://" + std::filesystem::absolute(p).string();
  }
  return c;
}

void override_dds(dds::PublisherConfig& c, int domain, const std::string& cyclone_xml) {
  if (domain >= 0) c.domain_id = static_cast<std::uint32_t>(domain);
  if (!cyclone_xml.empty())
    c.config_uri = "file://" + std::filesystem::absolute(cyclone_xml).string();
}

}  // namespace stac::settings
