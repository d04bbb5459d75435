// The sections of config/stac.yaml, each validated once at start-up. Missing or invalid keys
// give an error naming the file and the key (settings/config_section.hpp).
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>

#include "drivers/can/config.hpp"
#include "drivers/velodyne/scan_assembler.hpp"
#include "ego/deskew.hpp"
#include "ego/ego_estimator.hpp"
#include "ego/local_frame.hpp"
#include "perception/classification/track_classifier.hpp"
#include "perception/segmentation/segmenter.hpp"
#include "perception/tracking/tracker.hpp"
#include "rt/expected.hpp"

namespace stac::settings {

// What `stac` and `stac-node` say when start-up cannot allocate every capacity the configuration
// asks for (a std::bad_alloc escaping a command), after "<program>: ".
inline constexpr const char* kOutOfMemoryAtStartUp =
    "out of memory while allocating what the configuration asks for; lower the capacities (max_* "
    "keys, classification.accumulated_points) or free memory";

struct VelodyneSettings {
  velodyne::ScanAssemblerConfig assembler;
  // 'velodyne.model: auto': a capture's packets name the model (commands that read a capture
  // resolve it there; assembler.decoder.model holds S2.1 until then).
  bool model_auto = false;
  std::filesystem::path calibration;  // empty: from the status stream
  // velodyne.model_calibrations: the calibration for a model other than the configured one.
  std::map<velodyne::Model, std::filesystem::path> model_calibrations;
  std::string bind_address = "0.0.0.0";
  std::uint16_t port = velodyne::kPortData;
  std::string sender_address;  // empty: any sender
  int receive_buffer_bytes = 16 << 20;
  int scan_slots = 4;
};

rt::Result<VelodyneSettings> load_velodyne_settings(const std::filesystem::path& config_file);
// Switches `s` to another sensor model: the decoder's model, and (unless `calibration_given`)
// the calibration velodyne.model_calibrations names for it when the configured one is not for
// a sensor with the model's lasers. Errors say what to pass.
rt::Status use_velodyne_model(VelodyneSettings& s, velodyne::Model model, bool calibration_given);
// The `ego:` section: extrinsics, local frame, pose history, INS, deskew.
struct EgoSettings {
  std::optional<ego::Geodetic> origin;  // empty: the first INS fix
  ego::PoseHistoryConfig history;
  ego::EgoEstimatorConfig estimator;
  ego::DeskewConfig deskew;  // vehicle_T_sensor is the extrinsics
  std::uint16_t ins_port = 5602;
};
rt::Result<EgoSettings> load_ego_settings(const std::filesystem::path& config_file);
// A geodetic origin written LAT,LON,ALT (deg, deg, m) on a command line (--origin).
rt::Result<ego::Geodetic> parse_origin(const std::string& text);

// The `segmentation:` section, checked by the segmenter's own validation too.
rt::Result<segmentation::SegmenterConfig> load_segmentation_settings(
    const std::filesystem::path& config_file);

// The `tracking:` section, checked by the tracker's own validation too.
rt::Result<tracking::TrackerConfig> load_tracking_config(const std::filesystem::path& config_file);

// The `can:` section: transport, DBC and signal map. Errors name `can.<key>`.
rt::Result<can::CanConfig> load_can_settings(const std::filesystem::path& config_file);

// The `classification:` section: the model file and the stage's capacities (its max_tracks is
// the tracker's, set by the pipeline).
struct ClassificationSettings {
  classification::TrackClassifierConfig classifier;
  std::filesystem::path model;  // empty ("none"): tracks are not classified
};
rt::Result<ClassificationSettings> load_classification_settings(
    const std::filesystem::path& config_file);

// The sections every per-scan job reads (stac process, stac run): velodyne, ego, segmentation,
// tracking, classification; the first error is returned.
struct PipelineSettings {
  VelodyneSettings velodyne;
  EgoSettings ego;
  segmentation::SegmenterConfig segmenter;
  tracking::TrackerConfig tracker;
  ClassificationSettings classification;
};
rt::Result<PipelineSettings> load_pipeline_settings(const std::filesystem::path& config_file);

// Where the Debian package puts the configuration (deploy/CMakeLists.txt).
inline constexpr const char* kInstalledConfigPath = "/etc/stac/stac.yaml";
// The --config option's help, as every command says it.
inline constexpr const char* kConfigOptionHelp =
    "configuration file (default: $STAC_CONFIG, else config/stac.yaml of the source tree, or\n"
    "/etc/stac/stac.yaml when installed from the package)";
// The default config file: $STAC_CONFIG; else, for an executable run from its build folder,
// config/stac.yaml of the source tree; else (installed) kInstalledConfigPath.
std::filesystem::path default_config_path();
// The --config option's value, or the default when it is empty.
std::filesystem::path config_path(const std::string& option);

}  // namespace stac::settings
