// `stac eval`: segmentation (over-/under-segmentation per truth object) and tracking (CLEAR MOT,
// HOTA) metrics of a tracks file against the simulator's truth. Definitions: docs/evaluation.md.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "evaluation/tracks_jsonl.hpp"

namespace stac::evaluation {

struct EvalConfig {
  double max_range_m = 50.0;         // truth objects farther from the ego (x,y) are not evaluated
  std::uint32_t min_points = 20;     // truth objects with fewer returns are not evaluated
  double range_band_m = 10.0;        // width of the range bands of the breakdown
  double max_time_offset_s = 0.001;  // a truth scan and an output scan pair when this close
  // Outputs are confirmed tracks (updated in the scan); coasting ones (predictions) only when set.
  bool count_coasting = false;
  // Labels that name only some objects (KITTI's tracklets: no background is labelled): a track
  // that matches no label counts as a false positive only when it is classified as a tracked
  // class; unclassified and background tracks are left out, as on the simulator's background.
  bool classified_outputs_only = false;
  // Segmentation: a segment holding at least this share of an object's segmented points is a
  // "piece" of it; two or more pieces = over-segmented.
  double piece_share = 0.10;
  // Under-segmented: a piece of the object also holds points of other truth objects, more than
  // this share of the piece's object points and at least under_min_points of them.
  double foreign_share = 0.05;
  std::uint32_t under_min_points = 3;
  // Tracking similarity s = max(0, 1 - d / zero_distance(class)), d = x,y centre distance (m).
  // CLEAR MOT matches need s >= 0.5, i.e. d <= zero_distance / 2.
  std::map<std::string, double> zero_distance_m = {
      {"car", 4.0}, {"pedestrian", 2.0}, {"bicyclist", 3.0}};
};

// Classes tracking is evaluated on (zero_distance_m's keys); the rest is background.
bool is_tracked_class(const EvalConfig& config, const std::string& cls);

struct ClearCounts {
  std::uint64_t gt = 0, tp = 0, fn = 0, fp = 0, id_switches = 0, fragmentations = 0;
  double similarity_sum = 0, distance_sum_m = 0;
  [[nodiscard]] double mota() const;  // 1 - (fn + fp + idsw) / gt (gt = 0: 1 if no errors)
  [[nodiscard]] double motp() const;  // mean similarity of matches (0 when none)
  [[nodiscard]] double motp_distance_m() const;
  [[nodiscard]] double recall() const;
};

constexpr int kHotaAlphas = 19;  // localisation thresholds 0.05, 0.10, ... 0.95

struct HotaCounts {
  std::array<double, kHotaAlphas> tp{}, fn{}, fp{}, ass_sum{}, loc_sum{};
  [[nodiscard]] double hota() const;  // mean over alphas of sqrt(DetA * AssA)
  [[nodiscard]] double deta() const;
  [[nodiscard]] double assa() const;
  [[nodiscard]] double detre() const;
  [[nodiscard]] double loca() const;
};

struct SegCounts {
  std::uint64_t objects = 0;      // evaluated object-scans with at least one segmented point
  std::uint64_t unsegmented = 0;  // evaluated object-scans with none (not in a rate)
  std::uint64_t over = 0, under = 0;
  [[nodiscard]] double over_rate() const;
  [[nodiscard]] double under_rate() const;
};

struct EvalResult {
  std::uint64_t truth_scans = 0, output_scans = 0, paired_scans = 0;
  std::uint64_t ignored_tracks = 0;  // track-scans on background, unevaluated truth, out of range
  bool has_segment_truth = false;    // segments carried truth compositions
  ClearCounts clear;                 // tracked classes
  HotaCounts hota;
  SegCounts segmentation;  // tracked classes
  // Per truth class. False positives are attributed by the track's class only when every output
  // scored is classified as an evaluated class (classified_outputs_only, `--tracklets`):
  // fp_by_class. Otherwise an unclassified track's false positive belongs to no class, and the
  // per-class counts hold none.
  bool fp_by_class = false;
  std::map<std::string, ClearCounts> clear_by_class;
  std::map<std::string, HotaCounts> hota_by_class;
  std::map<std::string, SegCounts> segmentation_by_class;  // every class, background included
  std::map<int, ClearCounts> clear_by_band;  // band index b: [b * range_band_m, (b + 1) * ...)
  std::map<int, HotaCounts> hota_by_band;
  std::map<int, SegCounts> segmentation_by_band;  // tracked classes
};

EvalResult evaluate(const std::vector<TruthScanRecord>& truth,
                    const std::vector<TracksScan>& tracks, const EvalConfig& config);

}  // namespace stac::evaluation
