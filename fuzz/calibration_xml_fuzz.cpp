// A Velodyne db.xml calibration (HDL-64E, VeloView's HDL-32E and VLP-16 files) from memory
// (`parse_db_xml`). Split from config_files_fuzz on 2026-12-06: an XML file is 40-50 KB, and the
// YAML harness runs faster on inputs of at most 8 KB.
#include <cstddef>
#include <cstdint>
#include <string>

#include "drivers/velodyne/calibration.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  (void)stac::velodyne::parse_db_xml(text, "fuzz.xml");
  return 0;
}
