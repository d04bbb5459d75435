#include "tools/segmentation_settings.hpp"

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <string>
#include <type_traits>
#include <utility>

namespace stac::tools {
namespace {

class Section {
 public:
  Section(YAML::Node node, std::string file) : node_(std::move(node)), file_(std::move(file)) {}

  template <class T>
  rt::Result<bool> get(const char* key, T& out) const {
    const YAML::Node v = node_[key];
    if (!v) return rt::make_error(file_ + ": missing required key 'segmentation." + key + "'");
    try {
      out = v.as<T>();
    } catch (const YAML::Exception&) {
      return rt::make_error(file_ + ": 'segmentation." + key + "' has the wrong type (line " +
                            std::to_string(v.Mark().line + 1) + ")");
    }
    return true;
  }

 private:
  YAML::Node node_;
  std::string file_;
};

}  // namespace

rt::Result<segmentation::SegmenterConfig> load_segmentation_settings(
    const std::filesystem::path& config_file) {
  const std::string file = config_file.string();
  YAML::Node root;
  try {
    root = YAML::LoadFile(file);
  } catch (const YAML::Exception& e) {
    return rt::make_error(file + ": cannot read the configuration: " + e.what());
  }
  const YAML::Node node = root["segmentation"];
  if (!node || !node.IsMap()) return rt::make_error(file + ": missing the 'segmentation:' section");
  const Section s(node, file);
  segmentation::SegmenterConfig c;
  // Counts: integers in lowest..limit.
  auto count = [&](const char* key, std::uint64_t limit, auto& dst,
                   std::int64_t lowest = 1) -> rt::Result<bool> {
    std::int64_t v = 0;
    if (auto r = s.get(key, v); !r) return r;
    if (v < lowest || static_cast<std::uint64_t>(v) > limit) {
      return rt::make_error(file + ": 'segmentation." + key + "' must be in " +
                            std::to_string(lowest) + ".." + std::to_string(limit));
    }
    dst = static_cast<std::remove_reference_t<decltype(dst)>>(v);
    return true;
  };
  constexpr std::uint64_t kMaxCount = 100'000'000;
  for (const auto& r : {s.get("cell_m", c.cell_m),
                        s.get("range_m", c.range_m),
                        s.get("min_range_m", c.min_range_m),
                        s.get("sensor_height_m", c.sensor_height_m),
                        s.get("below_ground_m", c.below_ground_m),
                        s.get("below_ground_slope", c.below_ground_slope),
                        s.get("ground_cell_m", c.ground_cell_m),
                        s.get("ground_radius_m", c.ground_radius_m),
                        s.get("ground_max_slope", c.ground_max_slope),
                        s.get("ground_clearance_m", c.ground_clearance_m),
                        s.get("obstacle_height_m", c.obstacle_height_m),
                        s.get("obstacle_spread_m", c.obstacle_spread_m),
                        s.get("max_height_m", c.max_height_m),
                        count("weak_join_cells", 10, c.weak_join_cells, 0),
                        s.get("bridge_m", c.bridge_m),
                        s.get("bridge_height_m", c.bridge_height_m),
                        count("min_segment_points", kMaxCount, c.min_segment_points),
                        count("max_segment_points", kMaxCount, c.max_segment_points),
                        s.get("max_segment_extent_m", c.max_segment_extent_m),
                        count("max_points", kMaxCount, c.max_points),
                        count("max_occupied_cells", kMaxCount, c.max_occupied_cells),
                        count("max_segments", kMaxCount, c.max_segments)}) {
    if (!r) return rt::Unexpected<rt::Error>{r.error()};
  }
  if (const char* why = segmentation::validate(c); *why != '\0') {
    return rt::make_error(file + ": segmentation." + why);
  }
  return c;
}

}  // namespace stac::tools
