#include "evaluation/truth_composition.hpp"

#include <cmath>
#include <cstdlib>

namespace stac::evaluation {

using namespace stac::settings;

pipeline::PipelineConfig offline_pipeline_config(
    const PipelineSettings& settings,
    std::shared_ptr<const classification::TrackClassifierModel> model, bool describe) {
  return {.deskew = settings.ego.deskew,
          .segmenter = settings.segmenter,
          .tracker = settings.tracker,
          .classifier = settings.classification.classifier,
          .model = std::move(model),
          .describe = describe,
          .split_classification = false,
          .trailer = velodyne::traits(settings.velodyne.assembler.decoder.model).trailer,
          .clock = pipeline::StageClock::kThreadCpu};
}

const TruthScanRecord* nearest_truth_scan(const std::vector<TruthScanRecord>& truth,
                                          std::size_t& next, std::int64_t stamp_ns) {
  // The last truth scan starting by the time (1 ms of slack): the scan itself when the time is
  // its first firing, or the one whose sweep holds it (a scan placed mid-sweep, as KITTI's are).
  constexpr std::int64_t kSlackNs = 1'000'000;
  while (next + 1 < truth.size() && truth[next + 1].stamp_ns <= stamp_ns + kSlackNs) ++next;
  const TruthScanRecord& t = truth[next];
  const bool near = std::llabs(t.stamp_ns - stamp_ns) <= kSlackNs;
  const bool in_sweep =
      t.end_stamp_ns > t.stamp_ns && stamp_ns >= t.stamp_ns && stamp_ns <= t.end_stamp_ns;
  return near || in_sweep ? &t : nullptr;
}

// Which truth object each segment point lies in (the smallest box holding it, grown by 5 cm),
// counted per segment; -1 for points in no box.
void truth_composition(const TruthScanRecord& truth, const velodyne::Scan& scan,
                       const segmentation::Segments& segments,
                       const Eigen::Isometry3d& world_T_sensor, std::vector<SegmentRecord>& out) {
  constexpr double kGrow = 0.05;
  for (std::size_t si = 0; si < segments.segments.size(); ++si) {
    const segmentation::Segment& seg = segments.segments[si];
    const Eigen::Vector3d c =
        world_T_sensor * Eigen::Vector3d(seg.centroid[0], seg.centroid[1], seg.centroid[2]);
    const double reach = 0.5 * std::hypot(seg.box.length, seg.box.width) + 1.0;
    std::vector<const TruthObjectRecord*> near;
    for (const TruthObjectRecord& o : truth.objects) {
      if (std::hypot(o.x - c.x(), o.y - c.y()) < reach + 0.5 * std::hypot(o.length, o.width))
        near.push_back(&o);
    }
    std::vector<std::pair<std::int64_t, std::uint32_t>> counts;
    auto add = [&](std::int64_t id) {
      for (auto& [k, n] : counts) {
        if (k == id) return void(++n);
      }
      counts.emplace_back(id, 1);
    };
    for (std::uint32_t idx : segments.indices(seg)) {
      const velodyne::Point& p = scan.points[idx];
      const Eigen::Vector3d w = world_T_sensor * Eigen::Vector3d(p.x, p.y, p.z);
      const TruthObjectRecord* best = nullptr;
      double best_volume = 0;
      for (const TruthObjectRecord* o : near) {
        const double dx = w.x() - o->x, dy = w.y() - o->y;
        const double u = std::cos(o->yaw) * dx + std::sin(o->yaw) * dy;
        const double v = -std::sin(o->yaw) * dx + std::cos(o->yaw) * dy;
        if (std::abs(u) > o->length / 2 + kGrow || std::abs(v) > o->width / 2 + kGrow ||
            std::abs(w.z() - o->z) > o->height / 2 + kGrow) {
          continue;
        }
        const double volume = o->length * o->width * o->height;
        if (best == nullptr || volume < best_volume) best = o, best_volume = volume;
      }
      add(best == nullptr ? -1 : static_cast<std::int64_t>(best->id));
    }
    out[si].truth = std::move(counts);
    out[si].has_truth = true;
  }
}

}  // namespace stac::evaluation
