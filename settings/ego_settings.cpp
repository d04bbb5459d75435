// The `ego:` section of config/stac.yaml (see settings/settings.hpp).
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

#include "settings/config_section.hpp"
#include "settings/settings.hpp"

namespace stac::settings {
namespace {

rt::Result<Eigen::Vector3d> triple(const ConfigSection& s, const char* key) {
  auto v = s.get<std::vector<double>>(key);
  if (!v) return rt::Unexpected<rt::Error>{v.error()};
  if (v->size() != 3) return s.error(key, "must be a list of 3 numbers");
  for (double x : *v) {
    if (!std::isfinite(x)) return s.error(key, "must be finite");
  }
  return Eigen::Vector3d((*v)[0], (*v)[1], (*v)[2]);
}

}  // namespace

rt::Result<ego::Geodetic> parse_origin(const std::string& text) {
  ego::Geodetic g;
  char tail = 0;
  if (std::sscanf(text.c_str(), "%lf,%lf,%lf%c", &g.lat_deg, &g.lon_deg, &g.alt_m, &tail) != 3 ||
      !(std::abs(g.lat_deg) < 90.0) || !(std::abs(g.lon_deg) <= 180.0) || !std::isfinite(g.alt_m)) {
    return rt::make_error(
        "--origin '" + text +
        "': expected LAT,LON,ALT (deg, deg, m), e.g. 44.2449408681,-76.5096210157,77");
  }
  return g;
}

rt::Result<EgoSettings> load_ego_settings(const std::filesystem::path& config_file) {
  auto section = ConfigSection::open(config_file, "ego");
  if (!section) return rt::Unexpected<rt::Error>{section.error()};
  const ConfigSection& e = *section;
  EgoSettings s;

  if (auto text = e.get<std::string>("origin"); text && *text == "auto") {
    s.origin.reset();
  } else {
    auto o = triple(e, "origin");
    if (!o) return e.error("origin", "must be 'auto' or [lat_deg, lon_deg, alt_m]");
    if (std::abs(o->x()) > 90 || std::abs(o->y()) > 180)
      return e.error("origin", "is not a latitude/longitude");
    s.origin = ego::Geodetic{o->x(), o->y(), o->z()};
  }
  auto xyz = triple(e, "sensor_xyz_m");
  if (!xyz) return rt::Unexpected<rt::Error>{xyz.error()};
  auto rpy = triple(e, "sensor_rpy_deg");
  if (!rpy) return rt::Unexpected<rt::Error>{rpy.error()};
  if (xyz->cwiseAbs().maxCoeff() > 20)
    return e.error("sensor_xyz_m", "must be within 20 m of the vehicle origin");
  const Eigen::Vector3d rad = *rpy * (std::numbers::pi / 180.0);
  s.deskew.vehicle_T_sensor = Eigen::Isometry3d::Identity();
  s.deskew.vehicle_T_sensor.linear() =
      ego::from_roll_pitch_yaw(rad.x(), rad.y(), rad.z()).toRotationMatrix();
  s.deskew.vehicle_T_sensor.translation() = *xyz;

  int port = 0, alignment = 0;
  double history_s = 0, rate = 0, extrapolation_s = 0, gap_s = 0, timeout_s = 0, bucket_us = 0;
  STAC_CONFIG_GET(e, int, "ins_port", port);
  STAC_CONFIG_GET(e, double, "pose_history_s", history_s);
  STAC_CONFIG_GET(e, double, "pose_rate_hz", rate);
  STAC_CONFIG_GET(e, double, "max_extrapolation_s", extrapolation_s);
  STAC_CONFIG_GET(e, double, "max_pose_gap_s", gap_s);
  STAC_CONFIG_GET(e, double, "ins_timeout_s", timeout_s);
  STAC_CONFIG_GET(e, int, "max_alignment_status", alignment);
  STAC_CONFIG_GET(e, double, "deskew_bucket_us", bucket_us);
  if (port <= 0 || port > 65535) return e.error("ins_port", "must be 1..65535");
  s.ins_port = static_cast<std::uint16_t>(port);
  if (!(history_s >= 1 && history_s <= 600))
    return e.error("pose_history_s", "must be in 1..600 s");
  if (!(rate >= 1 && rate <= 1000)) return e.error("pose_rate_hz", "must be in 1..1000 Hz");
  s.history.capacity = static_cast<std::size_t>(std::ceil(history_s * rate * 1.25));  // 25% margin
  if (!(extrapolation_s >= 0 && extrapolation_s <= 1))
    return e.error("max_extrapolation_s", "must be in 0..1 s");
  s.history.max_extrapolation_ns = std::llround(extrapolation_s * 1e9);
  if (!(gap_s > 0 && gap_s <= 10)) return e.error("max_pose_gap_s", "must be in (0, 10] s");
  s.history.max_gap_ns = std::llround(gap_s * 1e9);
  if (!(timeout_s > 0 && timeout_s <= 10)) return e.error("ins_timeout_s", "must be in (0, 10] s");
  s.estimator.ins_timeout_ns = std::llround(timeout_s * 1e9);
  s.estimator.dead_reckoning_period_ns = std::llround(1e9 / rate);
  if (alignment < 0 || alignment > 8) return e.error("max_alignment_status", "must be in 0..8");
  s.estimator.max_alignment_status = alignment;
  if (!(bucket_us >= 1 && bucket_us <= 10'000))
    return e.error("deskew_bucket_us", "must be in 1..10000 us");
  s.deskew.bucket_ns = std::llround(bucket_us * 1000);
  return s;
}

}  // namespace stac::settings
