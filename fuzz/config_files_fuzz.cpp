// Files read by path at start-up: the input as the YAML configuration (every section a run
// reads), as a ROS yaml calibration and as an HDL-64E db.xml.
#include <cstddef>
#include <cstdint>

#include "drivers/velodyne/calibration.hpp"
#include "fuzz_common.hpp"
#include "settings/run_settings.hpp"
#include "settings/settings.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto yaml = stac::fuzz::as_file(data, size, ".yaml");
  (void)stac::settings::load_pipeline_settings(yaml);
  (void)stac::settings::load_run_settings(yaml);
  (void)stac::settings::load_can_settings(yaml);
  (void)stac::velodyne::load_ros_yaml(yaml);
  const auto xml = stac::fuzz::as_file(data, size, ".xml");
  (void)stac::velodyne::load_db_xml(xml);
  return 0;
}
