// The truth composition of segments (which `stac sim` truth box each segment point lies in),
// shared by `stac process` and `stac dataset`.
#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "drivers/velodyne/scan.hpp"
#include "perception/segmentation/segments.hpp"
#include "tools/tracks_jsonl.hpp"

namespace stac::tools {

// Which truth object each segment point lies in (the smallest box holding it, grown by 5 cm),
// counted per segment; -1 for points in no box.
void truth_composition(const TruthScanRecord& truth, const velodyne::Scan& scan,
                       const segmentation::Segments& segments,
                       const Eigen::Isometry3d& world_T_sensor, std::vector<SegmentRecord>& out);

}  // namespace stac::tools
