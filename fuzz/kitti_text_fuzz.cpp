// A KITTI raw drive's text files (issue 33): the input as a tracklet_labels.xml and as a
// calibration file (the "KEY:" lines of calib_imu_to_velo.txt and the object benchmark's
// calib.txt), and each of its lines as an OXTS record (turned into STAC's INS fix and written
// back) and as a timestamps line.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "formats/kitti_files.hpp"
#include "formats/kitti_raw.hpp"
#include "formats/kitti_tracklets.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  if (auto t = stac::formats::parse_kitti_tracklets(text, "fuzz.xml"))
    (void)stac::formats::parse_kitti_tracklets(stac::formats::format_kitti_tracklets(*t), "again");
  std::vector<double> values;
  for (const auto& [key, count] : {std::pair<const char*, std::size_t>{"R", 9},
                                   {"T", 3},
                                   {"R0_rect", 9},
                                   {"Tr_velo_to_cam", 12}})
    (void)stac::formats::kitti_calib_values(text, key, count, values);
  for (std::size_t start = 0; start <= text.size();) {
    const std::size_t end = std::min(text.find('\n', start), text.size());
    const std::string line = text.substr(start, end - start);
    if (auto r = stac::formats::parse_oxts_record(line)) {
      const stac::ego::InsFix fix = stac::formats::oxts_fix(*r);
      (void)stac::formats::format_oxts_record(stac::formats::oxts_record(fix));
    }
    std::int64_t ns = 0;
    if (stac::formats::parse_kitti_time(line, ns)) (void)stac::formats::format_kitti_time(ns);
    start = end + 1;
  }
  return 0;
}
