// The `segmentation:` section of config/stac.yaml (see settings/settings.hpp).
#include <cstdint>
#include <string>
#include <type_traits>

#include "settings/config_section.hpp"
#include "settings/settings.hpp"

namespace stac::settings {

rt::Result<segmentation::SegmenterConfig> load_segmentation_settings(
    const std::filesystem::path& config_file) {
  auto section = ConfigSection::open(config_file, "segmentation");
  if (!section) return rt::Unexpected<rt::Error>{section.error()};
  const ConfigSection& s = *section;
  segmentation::SegmenterConfig c;
  // Counts: integers in lowest..limit.
  auto count = [&](const char* key, std::uint64_t limit, auto& dst,
                   std::int64_t lowest = 1) -> rt::Status {
    std::int64_t v = 0;
    if (auto r = s.read(key, v); !r) return r;
    if (v < lowest || static_cast<std::uint64_t>(v) > limit) {
      return s.error(key, "must be in " + std::to_string(lowest) + ".." + std::to_string(limit));
    }
    dst = static_cast<std::remove_reference_t<decltype(dst)>>(v);
    return {};
  };
  constexpr std::uint64_t kMaxCount = 100'000'000;
  for (const auto& r : {s.read("cell_m", c.cell_m),
                        s.read("range_m", c.range_m),
                        s.read("min_range_m", c.min_range_m),
                        s.read("sensor_height_m", c.sensor_height_m),
                        s.read("below_ground_m", c.below_ground_m),
                        s.read("below_ground_slope", c.below_ground_slope),
                        s.read("ground_cell_m", c.ground_cell_m),
                        s.read("ground_radius_m", c.ground_radius_m),
                        s.read("ground_max_slope", c.ground_max_slope),
                        s.read("ground_clearance_m", c.ground_clearance_m),
                        s.read("obstacle_height_m", c.obstacle_height_m),
                        s.read("obstacle_spread_m", c.obstacle_spread_m),
                        s.read("max_height_m", c.max_height_m),
                        s.read("overhead_m", c.overhead_m),
                        count("weak_join_cells", 10, c.weak_join_cells, 0),
                        s.read("bridge_m", c.bridge_m),
                        s.read("bridge_height_m", c.bridge_height_m),
                        s.read("overhang_m", c.overhang_m),
                        s.read("overhang_max_m", c.overhang_max_m),
                        s.read("overhang_height_m", c.overhang_height_m),
                        s.read("split_height_m", c.split_height_m),
                        s.read("split_person_m", c.split_person_m),
                        count("split_min_points", kMaxCount, c.split_min_points),
                        count("min_segment_points", kMaxCount, c.min_segment_points),
                        count("max_segment_points", kMaxCount, c.max_segment_points),
                        s.read("max_segment_extent_m", c.max_segment_extent_m),
                        count("box_fit_points", 100000, c.box_fit_points, 0),
                        s.read("box_fit_min_length_m", c.box_fit_min_length_m),
                        count("max_points", 10'000'000, c.max_points),
                        count("max_occupied_cells", 4'194'304, c.max_occupied_cells),
                        count("max_segments", 1'000'000, c.max_segments)}) {
    if (!r) return rt::Unexpected<rt::Error>{r.error()};
  }
  if (const char* why = segmentation::validate(c); *why != '\0') {
    return s.error_about(why);
  }
  return c;
}

}  // namespace stac::settings
