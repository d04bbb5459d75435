#include "settings/settings.hpp"

#include <cmath>
#include <cstdlib>
#include <system_error>

#include "drivers/io/datagram.hpp"
#include "drivers/velodyne/calibration.hpp"
#include "settings/build_tree.hpp"
#include "settings/config_section.hpp"

namespace stac::settings {

namespace {

// Whether this executable lies under the build folder it was built in (else it is installed).
bool running_from_build_tree() {
  std::error_code error;
  const auto exe = std::filesystem::read_symlink("/proc/self/exe", error);
  if (error) return true;  // unknown: keep the developer's default
  const std::string build = kBinaryDir;
  const std::string path = exe.string();
  return path.size() > build.size() && path.compare(0, build.size(), build) == 0 &&
         path[build.size()] == '/';
}

}  // namespace

std::filesystem::path default_config_path() {
  if (const char* env = std::getenv("STAC_CONFIG"); env != nullptr && *env != '\0') return env;
  if (!running_from_build_tree()) return kInstalledConfigPath;
  return std::filesystem::path(kSourceDir) / "config" / "stac.yaml";
}

std::filesystem::path config_path(const std::string& option) {
  return option.empty() ? default_config_path() : std::filesystem::path(option);
}

rt::Result<VelodyneSettings> load_velodyne_settings(const std::filesystem::path& config_file) {
  auto section = ConfigSection::open(config_file, "velodyne");
  if (!section) return rt::Unexpected<rt::Error>{section.error()};
  const ConfigSection& v = *section;

  VelodyneSettings s;
  auto& a = s.assembler;
#define STAC_GET(type, key, dst) STAC_CONFIG_GET(v, type, key, dst)
  std::string model, calibration;
  double cut_deg = 0, min_range = 0, max_range = 0;
  int port = 0;
  STAC_GET(std::string, "model", model);
  STAC_GET(std::string, "calibration", calibration);
  STAC_GET(std::string, "bind_address", s.bind_address);
  STAC_GET(int, "port", port);
  auto sender = v.get_or<std::string>("sender_address", std::string{});
  if (!sender) return rt::Unexpected<rt::Error>{sender.error()};
  s.sender_address = *sender;
  STAC_GET(int, "receive_buffer_bytes", s.receive_buffer_bytes);
  STAC_GET(double, "cut_angle_deg", cut_deg);
  STAC_GET(double, "min_rpm", a.min_rpm);
  STAC_GET(double, "min_range_m", min_range);
  STAC_GET(double, "max_range_m", max_range);
  STAC_GET(bool, "gate_two_point_correction", a.decoder.gate_two_point_correction);
  STAC_GET(bool, "ros_intensity_units", a.decoder.ros_intensity_units);
  STAC_GET(double, "max_gap_s", a.max_gap_s);
  STAC_GET(double, "max_scan_duration_s", a.max_scan_duration_s);
  STAC_GET(double, "min_scan_completeness", a.min_completeness);
  STAC_GET(int, "scan_slots", s.scan_slots);
#undef STAC_GET

  const auto parsed = velodyne::parse_model(model);
  s.model_auto = model == "auto";
  if (!parsed && !s.model_auto) {
    return v.error("model",
                   "is '" + model + "'; use " + std::string(velodyne::model_names()) + " or auto");
  }
  a.decoder.model = parsed ? *parsed : velodyne::Model::kS2_1;
  if (const YAML::Node& m = v.node()["model_calibrations"]; m && !m.IsNull()) {
    if (!m.IsMap())
      return v.error("model_calibrations", "must be a map of model name: calibration file");
    for (const auto& kv : m) {
      if (!kv.first.IsScalar())
        return v.error("model_calibrations", "has a key that is not a model name");
      const auto name = kv.first.Scalar();
      const auto which = velodyne::parse_model(name);
      if (!which) {
        return v.error("model_calibrations", "names '" + name + "', not a model (" +
                                                 std::string(velodyne::model_names()) + ")");
      }
      if (!kv.second.IsScalar())
        return v.error("model_calibrations", "'" + name + "' must be a file name");
      s.model_calibrations[*which] = v.path(kv.second.Scalar());
    }
  }
  if (calibration != "stream") {
    s.calibration = v.path(calibration);
  } else if (!s.model_auto &&
             velodyne::traits(a.decoder.model).trailer != velodyne::TrailerKind::kGpsStatus) {
    return v.error("calibration", "is 'stream', which needs an S2.1 or S3; the " + model +
                                      " sends no calibration in its packets");
  }
  // Parsed as the UDP receiver parses them at start-up (io::parse_ipv4).
  if (std::uint32_t ip = 0; !io::parse_ipv4(s.bind_address.c_str(), ip)) {
    return v.error("bind_address", "is '" + s.bind_address +
                                       "'; give a dotted IPv4 address of this machine (0.0.0.0: "
                                       "every interface)");
  }
  if (std::uint32_t ip = 0;
      !s.sender_address.empty() && !io::parse_ipv4(s.sender_address.c_str(), ip)) {
    return v.error("sender_address", "is '" + s.sender_address +
                                         "'; give the sensor's dotted IPv4 address, or \"\" "
                                         "to accept any sender");
  }
  if (port <= 0 || port > 65535) return v.error("port", "must be 1..65535");
  s.port = static_cast<std::uint16_t>(port);
  if (cut_deg < 0 || cut_deg >= 360) return v.error("cut_angle_deg", "must be in [0, 360)");
  a.cut_angle = static_cast<std::uint16_t>(std::lround(cut_deg * 100.0) % 36000);
  if (a.min_rpm < 60 || a.min_rpm > 1200) return v.error("min_rpm", "must be in 60..1200");
  if (min_range < 0 || max_range <= min_range) {
    return v.error("min_range_m", "must be >= 0 and below 'velodyne.max_range_m'");
  }
  a.decoder.min_range_m = static_cast<float>(min_range);
  a.decoder.max_range_m = static_cast<float>(max_range);
  if (a.max_gap_s <= 0 || a.max_scan_duration_s <= 0) {
    return v.error("max_gap_s", "and 'velodyne.max_scan_duration_s' must be > 0");
  }
  if (!(a.min_completeness >= 0.0 && a.min_completeness <= 1.0))
    return v.error("min_scan_completeness", "must be in [0, 1]");
  if (s.scan_slots < 2 || s.scan_slots > 64) return v.error("scan_slots", "must be in 2..64");
  if (s.receive_buffer_bytes < 65536) {
    return v.error("receive_buffer_bytes", "must be at least 65536");
  }
  return s;
}

rt::Status use_velodyne_model(VelodyneSettings& s, velodyne::Model model, bool calibration_given) {
  const velodyne::Model before = s.assembler.decoder.model;
  const bool was_auto = s.model_auto;
  s.assembler.decoder.model = model;
  s.model_auto = false;
  if (calibration_given) return {};
  // The configured calibration stays for the same sensor (the HDL-64E's variants, the VLP-16 and
  // the Puck LITE share a product id), and with 'auto' when it fits the model the packets name
  // (the unit's own file); else the model's from velodyne.model_calibrations.
  if (!was_auto && velodyne::traits(before).product_id == velodyne::traits(model).product_id)
    return {};
  if (was_auto && !s.calibration.empty()) {
    const auto configured = velodyne::load_calibration(s.calibration);
    if (configured && velodyne::check_calibration_for(*configured, model)) return {};
  }
  const auto it = s.model_calibrations.find(model);
  if (it == s.model_calibrations.end()) {
    return rt::make_error("the configured calibration is not a " +
                          std::string(velodyne::traits(model).name) +
                          "'s: pass --calib, or name one in velodyne.model_calibrations");
  }
  s.calibration = it->second;
  return {};
}

rt::Result<PipelineSettings> load_pipeline_settings(const std::filesystem::path& config_file) {
  PipelineSettings s;
  auto velodyne = load_velodyne_settings(config_file);
  if (!velodyne) return rt::Unexpected<rt::Error>{velodyne.error()};
  auto ego = load_ego_settings(config_file);
  if (!ego) return rt::Unexpected<rt::Error>{ego.error()};
  auto segmenter = load_segmentation_settings(config_file);
  if (!segmenter) return rt::Unexpected<rt::Error>{segmenter.error()};
  auto tracker = load_tracking_config(config_file);
  if (!tracker) return rt::Unexpected<rt::Error>{tracker.error()};
  auto classification = load_classification_settings(config_file);
  if (!classification) return rt::Unexpected<rt::Error>{classification.error()};
  // The classifier keeps one accumulated cloud per track: capacities of two sections together.
  classification::TrackClassifierConfig together = classification->classifier;
  together.max_tracks = tracker->max_tracks;
  if (const char* why = classification::validate(together); *why != '\0') {
    return rt::make_error(config_file.string() +
                          ": 'tracking.max_tracks' and 'classification:': " + why);
  }
  return PipelineSettings{std::move(*velodyne), std::move(*ego), *segmenter, *tracker,
                          std::move(*classification)};
}

}  // namespace stac::settings
