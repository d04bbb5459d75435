// What `stac process` and `stac dataset` share: the offline pipeline configuration, the truth
// scan of a scan, and the truth composition of segments (which `stac sim` truth box each
// segment point lies in).
#pragma once

#include <Eigen/Geometry>
#include <memory>
#include <vector>

#include "drivers/velodyne/scan.hpp"
#include "evaluation/tracks_jsonl.hpp"
#include "perception/segmentation/segments.hpp"
#include "pipeline/scan_pipeline.hpp"
#include "settings/settings.hpp"

namespace stac::evaluation {

// The per-scan pipeline of the settings, timed by thread CPU time (offline, deterministic).
// `model` null: no classification (unless `describe`: the classify stage runs for an observer).
pipeline::PipelineConfig offline_pipeline_config(
    const settings::PipelineSettings& settings,
    std::shared_ptr<const classification::TrackClassifierModel> model = nullptr,
    bool describe = false);

// Advances `next` to the last truth scan starting by `stamp_ns` (1 ms of slack; truth in time
// order, not empty) and returns it when it starts within 1 ms of it or its sweep ("end_time")
// holds it (a scan placed mid-sweep), else null.
const TruthScanRecord* nearest_truth_scan(const std::vector<TruthScanRecord>& truth,
                                          std::size_t& next, std::int64_t stamp_ns);

// Which truth object each segment point lies in (the smallest box holding it, grown by 5 cm),
// counted per segment; -1 for points in no box.
void truth_composition(const TruthScanRecord& truth, const velodyne::Scan& scan,
                       const segmentation::Segments& segments,
                       const Eigen::Isometry3d& world_T_sensor, std::vector<SegmentRecord>& out);

}  // namespace stac::evaluation
