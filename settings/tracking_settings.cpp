// The `tracking:` section of config/stac.yaml (see settings/settings.hpp).
#include <stdexcept>
#include <string>

#include "settings/config_section.hpp"
#include "settings/settings.hpp"

namespace stac::settings {

rt::Result<tracking::TrackerConfig> load_tracking_config(const std::filesystem::path& config_file) {
  auto section = ConfigSection::open(config_file, "tracking");
  if (!section) return rt::Unexpected<rt::Error>{section.error()};
  const ConfigSection& t = *section;

  tracking::TrackerConfig c;
  std::uint64_t max_tracks = 0, max_detections = 0;
#define STAC_GET(type, key, dst) STAC_CONFIG_GET(t, type, key, dst)
  STAC_GET(std::uint64_t, "max_tracks", max_tracks);
  STAC_GET(std::uint64_t, "max_detections", max_detections);
  STAC_GET(double, "accel_std_mps2", c.kalman.accel_std_mps2);
  STAC_GET(double, "z_velocity_std_mps", c.kalman.z_velocity_std_mps);
  STAC_GET(double, "measurement_std_m", c.kalman.measurement_std_m);
  STAC_GET(double, "measurement_z_std_m", c.kalman.measurement_z_std_m);
  STAC_GET(double, "initial_velocity_std_mps", c.kalman.initial_velocity_std_mps);
  STAC_GET(double, "gate_mahalanobis_sq", c.gate.mahalanobis_sq);
  STAC_GET(double, "gate_distance_m", c.gate.distance_m);
  STAC_GET(std::uint32_t, "confirm_hits", c.life.confirm_hits);
  STAC_GET(std::uint32_t, "confirm_large_points", c.life.confirm_large_points);
  STAC_GET(std::uint32_t, "confirm_large_hits", c.life.confirm_large_hits);
  STAC_GET(std::uint32_t, "tentative_max_misses", c.life.tentative_max_misses);
  STAC_GET(std::uint32_t, "max_coast_scans", c.life.max_coast_scans);
  STAC_GET(double, "max_position_std_m", c.life.max_position_std_m);
  STAC_GET(bool, "position_from_box", c.position_from_box);
  STAC_GET(double, "absorb_gap_m", c.fragments.gap_m);
  STAC_GET(double, "absorb_max_length_m", c.object.max_length_m);
  STAC_GET(double, "absorb_max_width_m", c.object.max_width_m);
  STAC_GET(double, "absorb_tall_height_m", c.object.tall_height_m);
  STAC_GET(double, "absorb_tall_length_m", c.object.tall_length_m);
  STAC_GET(double, "absorb_velocity_mps", c.fragments.velocity_mps);
  STAC_GET(double, "absorb_keep_length_m", c.person.max_length_m);
  STAC_GET(double, "absorb_keep_width_m", c.person.max_width_m);
  STAC_GET(double, "absorb_keep_height_m", c.person.min_height_m);
  STAC_GET(double, "absorb_keep_wide_m", c.person.wide_m);
  STAC_GET(double, "absorb_keep_wide_height_m", c.person.wide_min_height_m);
  STAC_GET(double, "absorb_strip_length_m", c.person.strip_length_m);
  STAC_GET(double, "absorb_strip_width_m", c.person.strip_width_m);
  STAC_GET(double, "absorb_narrow_gap_m", c.person.gap_m);
  STAC_GET(std::uint32_t, "absorb_established_hits", c.fragments.established_hits);
  STAC_GET(double, "absorb_known_margin_m", c.fragments.known_margin_m);
  STAC_GET(double, "overlap_margin_m", c.fragments.overlap_margin_m);
  STAC_GET(double, "end_on_length_m", c.end_on.length_m);
  STAC_GET(double, "end_on_min_range_m", c.end_on.min_range_m);
  STAC_GET(double, "end_on_min_width_m", c.end_on.min_width_m);
  STAC_GET(double, "end_on_max_width_m", c.end_on.max_width_m);
  STAC_GET(double, "end_on_max_depth_m", c.end_on.max_depth_m);
  STAC_GET(double, "end_on_min_height_m", c.end_on.min_height_m);
  STAC_GET(double, "extent_memory_length_m", c.body.memory_length_m);
  STAC_GET(bool, "body_gating", c.body.gating);
  STAC_GET(double, "box_smoothing", c.box_smoothing);
  STAC_GET(double, "min_heading_speed_mps", c.min_heading_speed_mps);
#undef STAC_GET
  c.max_tracks = static_cast<std::size_t>(max_tracks);
  c.max_detections = static_cast<std::size_t>(max_detections);
  try {
    const tracking::Tracker probe(c);  // the tracker's own validation, with its message
  } catch (const std::invalid_argument& e) {
    // "tracking config: KEY must ...": the key named as every other check names it.
    std::string message = e.what();
    const std::string prefix = "tracking config: ";
    if (message.rfind(prefix, 0) == 0) message.erase(0, prefix.size());
    return t.error_about(message);
  }
  return c;
}

}  // namespace stac::settings
