// YAML files read at start-up: the input as the configuration (every section a run reads, from
// memory through a ConfigSnapshot: no file per input) and as a ROS yaml calibration (from memory
// too). Inputs of at most 8,448 bytes (fuzz/options/config_files_fuzz.options): yaml-cpp's time
// grows with the input; the db.xml calibrations have their own harness, calibration_xml_fuzz.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>

#include "drivers/velodyne/calibration.hpp"
#include "settings/config_section.hpp"
#include "settings/dds_settings.hpp"
#include "settings/run_settings.hpp"
#include "settings/settings.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  // Relative paths in it (calibration, model, DBC) point into a folder that does not exist.
  const std::filesystem::path config = "/nonexistent/stac_fuzz/stac.yaml";
  {
    const stac::settings::ConfigSnapshot snapshot(config, text);
    (void)stac::settings::load_pipeline_settings(config);
    (void)stac::settings::load_run_settings(config);
    (void)stac::settings::load_can_settings(config);
    (void)stac::settings::load_dds_settings(config);
  }
  (void)stac::velodyne::parse_ros_yaml(text, "fuzz.yaml");
  return 0;
}
