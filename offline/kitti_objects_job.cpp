// The KITTI objects job (kitti_objects_job.hpp): each frame segmented, each labelled object
// within range matched to the segment holding most of its obstacle points, that segment
// classified, the tables and the report.
#include "offline/kitti_objects_job.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "formats/durable_file.hpp"
#include "formats/kitti_files.hpp"
#include "formats/model_file.hpp"
#include "perception/classification/track_classifier.hpp"
#include "perception/segmentation/segmenter.hpp"
#include "pictures/birds_eye.hpp"
#include "rt/formatted.hpp"
#include "settings/settings.hpp"

namespace stac::offline {

using namespace stac::settings;
using namespace stac::formats;
namespace {

// What became of one labelled object.
struct ObjectResult {
  std::string frame, type;
  int occluded = 0;
  double range_m = 0;
  std::uint32_t points = 0;          // scan points in its box
  std::uint32_t segment_points = 0;  // of those, points in some segment
  std::uint32_t best_inside = 0;     // the best segment's points in the box
  std::uint32_t best_size = 0;       // the best segment's points
  std::string status;  // segmented, under-segmented, over-segmented, missed, no points
  std::string segment_class = "-", track_class = "-";
  classification::LogOdds track_log_odds{};
};

// The STAC class a KITTI type is expected as.
const char* expected_class(const std::string& type) {
  if (type == "Car" || type == "Van" || type == "Truck" || type == "Tram") return "car";
  if (type == "Pedestrian" || type == "Person_sitting") return "pedestrian";
  if (type == "Cyclist") return "bicyclist";
  return "background";  // Misc
}

std::string status_of(const ObjectResult& r) {
  if (r.points == 0) return "no points";
  if (r.segment_points == 0) return "missed";
  if (2 * r.best_inside < r.best_size) return "under-segmented";      // mostly something else
  if (2 * r.best_inside < r.segment_points) return "over-segmented";  // split in several
  return "segmented";
}

// The segment classifier's log odds of each segment the classify stage describes.
struct SegmentClass : classification::TrackClassifier::Observer {
  explicit SegmentClass(const classification::TrackClassifierModel& m) : model(m) {}
  void on_update(const tracking::Track&, std::span<const float> segment,
                 std::span<const float>) noexcept override {
    valid = model.segment.classify(segment, hs);
  }
  const classification::TrackClassifierModel& model;
  classification::LogOdds hs{};
  bool valid = false;
};

}  // namespace

rt::Status run_kitti_objects_job(const KittiObjectsJobOptions& o, const JobOutput& output) {
  const std::filesystem::path dir = o.dir;
  auto seg_config = load_segmentation_settings(config_path(o.config));
  if (!seg_config) return rt::make_error(seg_config.error().message);
  auto classification = load_classification_settings(config_path(o.config));
  if (!classification) return rt::make_error(classification.error().message);
  auto model = job_model(o.model, classification->model);
  if (!model) return rt::make_error(model.error().message);
  if (*model == nullptr)
    return rt::make_error("no model: give --model FILE or set classification.model");

  std::vector<std::string> frames;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(dir / "velodyne", ec)) {
    if (e.path().extension() == ".bin") frames.push_back(e.path().stem().string());
  }
  if (ec || frames.empty()) {
    return rt::make_error(o.dir +
                          ": no velodyne/*.bin (a KITTI object folder has velodyne/, calib/, "
                          "label_2/)");
  }
  std::sort(frames.begin(), frames.end());

  segmentation::Segmenter segmenter(*seg_config);
  segmentation::Segments segments = segmenter.make_segments();
  // The pipeline's classify stage, one track at a time (a fresh id each: nothing carries over).
  classification::TrackClassifierConfig cc = classification->classifier;
  cc.descriptors.intensity_full_scale = 1.0;  // KITTI reflectance is 0..1
  cc.max_tracks = 1;
  cc.max_points = seg_config->max_points;
  classification::TrackClassifier stage(cc, *model);
  SegmentClass segment_class(**model);  // the segment classifier alone, on the stage's descriptors
  const classification::ClassNames& names = (*model)->classes;
  stage.set_observer(&segment_class);
  tracking::TrackerOutput tracked(1);
  (void)tracked.tracks.resize(1);
  rt::FixedVector<classification::TrackClass> classes(1);
  std::uint64_t next_id = 1;
  std::vector<ObjectResult> results;
  const std::filesystem::path report = o.report;
  if (!o.report.empty()) {
    std::filesystem::create_directories(report, ec);
    if (ec)
      return rt::make_error(o.report + ": cannot create the report folder (" + ec.message() + ")");
  }

  for (const std::string& frame : frames) {
    auto scan = load_kitti_scan((dir / "velodyne" / (frame + ".bin")).string());
    if (!scan) return rt::make_error(scan.error().message);
    auto rect_T_velo = load_kitti_rect_T_velo((dir / "calib" / (frame + ".txt")).string());
    if (!rect_T_velo) return rt::make_error(rect_T_velo.error().message);
    auto labels = load_kitti_labels((dir / "label_2" / (frame + ".txt")).string());
    if (!labels) return rt::make_error(labels.error().message);
    const std::vector<float>& v = *scan;
    const std::size_t n = v.size() / 4;
    segmenter.segment({v.data(), n, 16}, segments);
    std::vector<int> owner(n, -1);
    for (std::size_t s = 0; s < segments.segments.size(); ++s)
      for (const std::uint32_t p : segments.indices(segments.segments[s]))
        owner[p] = static_cast<int>(s);
    std::vector<Eigen::Vector3d> rect(n);
    for (std::size_t i = 0; i < n; ++i)
      rect[i] = *rect_T_velo * Eigen::Vector3d(v[4 * i], v[4 * i + 1], v[4 * i + 2]);
    const Eigen::Isometry3d velo_T_rect = rect_T_velo->inverse();

    pictures::BirdsEye picture(pictures::BirdsEyeOptions{
        .range_m = o.max_range_m + 5, .size_px = 1000, .height_bar = false});
    for (std::size_t i = 0; i < n; ++i) {
      picture.add_point(v[4 * i], v[4 * i + 1],
                        owner[i] < 0 ? pictures::Bgr{80, 80, 80} : pictures::Bgr{200, 200, 200});
    }
    for (const KittiObject& obj : *labels) {
      const Eigen::Vector3d centre_rect = obj.bottom_centre - Eigen::Vector3d(0, obj.height / 2, 0);
      const Eigen::Vector3d c = velo_T_rect * centre_rect;
      ObjectResult r;
      r.frame = frame;
      r.type = obj.type;
      r.occluded = obj.occluded;
      r.range_m = std::hypot(c.x(), c.y());
      if (r.range_m > o.max_range_m) continue;
      std::map<int, std::uint32_t> inside;  // segment -> its points in the box
      for (std::size_t i = 0; i < n; ++i) {
        if (!obj.contains(rect[i], o.margin_m)) continue;
        ++r.points;
        if (owner[i] >= 0) {
          ++r.segment_points;
          ++inside[owner[i]];
        }
      }
      int best = -1;
      for (const auto& [s, k] : inside) {
        if (best < 0 || k > inside[best]) best = s;
      }
      if (best >= 0) {
        const segmentation::Segment& seg = segments.segments[static_cast<std::size_t>(best)];
        r.best_inside = inside[best];
        r.best_size = seg.count;
        // The segment as a track's first update (no motion): the segment classifier, and the
        // ADBF with the holistic descriptor of one segment.
        tracking::Track& t = tracked.tracks[0];
        t = tracking::Track{};
        t.id = next_id++;
        t.segment = best;
        t.length = seg.box.length;
        t.width = seg.box.width;
        t.height = seg.box.height;
        t.features.add_segment(Eigen::Vector3f(seg.centroid[0], seg.centroid[1], seg.centroid[2]),
                               0, 0.5);
        segment_class.valid = false;
        stage.classify(v.data(), 16, segments, tracked, classes);
        if (segment_class.valid && classes[0].classified) {
          r.segment_class = classification::class_name(
              names, classification::predict(segment_class.hs, names.size()));
          r.track_log_odds = classes[0].log_odds;
          r.track_class = classification::class_name(names, classes[0].label);
        }
      }
      r.status = status_of(r);
      const double yaw = -obj.rotation_y - M_PI / 2;  // about the velodyne's z
      const pictures::Bgr colour = r.status == "segmented"   ? pictures::Bgr{80, 220, 80}
                                   : r.status == "no points" ? pictures::Bgr{120, 120, 120}
                                                             : pictures::Bgr{60, 60, 240};
      picture.add_box(static_cast<float>(c.x()), static_cast<float>(c.y()),
                      static_cast<float>(obj.length), static_cast<float>(obj.width),
                      static_cast<float>(yaw), colour);
      picture.add_label(static_cast<float>(c.x()), static_cast<float>(c.y()),
                        obj.type + " -> " + r.track_class, colour);
      results.push_back(r);
    }
    if (!o.report.empty()) {
      picture.add_legend("KITTI object frame " + frame + ": labelled objects within " +
                         std::to_string(static_cast<int>(o.max_range_m)) + " m");
      picture.add_legend("green: segmented, red: under/over-segmented or missed, grey: no points");
      picture.add_legend("label: KITTI type -> STAC class (ADBF after one segment)");
      picture.add_legend("light points: in a segment; dark: ground and the rest");
      if (auto s = picture.save(report / ("frame_" + frame + ".png")); !s)
        return rt::make_error(s.error().message);
    }
  }

  // Per KITTI type: how many were segmented, and how often the class was the expected one.
  output.tell(rt::formatted(
      "stac kitti-objects: %zu frames, %zu labelled objects within %.0f m; model %s\n",
      frames.size(), results.size(), o.max_range_m,
      o.model.empty() ? classification->model.string().c_str() : o.model.c_str()));
  output.tell(rt::formatted("%-7s %-15s %5s %6s %4s %6s %-15s %-11s %-11s\n", "frame", "type",
                            "range", "points", "occl", "in seg", "status", "segment", "track"));
  for (const ObjectResult& r : results) {
    output.tell(rt::formatted("%-7s %-15s %5.1f %6u %4d %6u %-15s %-11s %-11s\n", r.frame.c_str(),
                              r.type.c_str(), r.range_m, r.points, r.occluded, r.segment_points,
                              r.status.c_str(), r.segment_class.c_str(), r.track_class.c_str()));
  }
  struct Tally {
    int objects = 0, segmented = 0, with_points = 0, segment_right = 0, track_right = 0;
  };
  std::map<std::string, Tally> by_type;
  Tally all;
  for (const ObjectResult& r : results) {
    for (Tally* t : {&by_type[r.type], &all}) {
      ++t->objects;
      t->with_points += r.points > 0 ? 1 : 0;
      t->segmented += r.status == "segmented" ? 1 : 0;
      t->segment_right += r.segment_class == expected_class(r.type) ? 1 : 0;
      t->track_right += r.track_class == expected_class(r.type) ? 1 : 0;
    }
  }
  output.tell(rt::formatted("\n%-15s %7s %11s %9s %13s %11s\n", "type", "objects", "with points",
                            "segmented", "segment class", "track class"));
  nlohmann::json metrics = {{"frames", frames.size()}, {"objects", results.size()}};
  for (const auto& [type, t] : by_type) {
    output.tell(rt::formatted("%-15s %7d %11d %9d %13d %11d\n", type.c_str(), t.objects,
                              t.with_points, t.segmented, t.segment_right, t.track_right));
    metrics["by_type"][type] = {{"objects", t.objects},
                                {"with_points", t.with_points},
                                {"segmented", t.segmented},
                                {"segment_class_right", t.segment_right},
                                {"track_class_right", t.track_right}};
  }
  output.tell(rt::formatted("%-15s %7d %11d %9d %13d %11d\n", "all", all.objects, all.with_points,
                            all.segmented, all.segment_right, all.track_right));
  metrics["segmented_fraction"] =
      all.objects > 0 ? static_cast<double>(all.segmented) / all.objects : 0.0;
  metrics["track_class_fraction"] =
      all.objects > 0 ? static_cast<double>(all.track_right) / all.objects : 0.0;

  if (!o.report.empty()) {
    std::ostringstream csv;
    csv << "frame,type,expected_class,range_m,occluded,points,segment_points,best_segment_inside,"
           "best_segment_points,status,segment_class,track_class";
    for (const std::string& n : names) csv << ',' << n << "_log_odds";
    csv << '\n';
    for (const ObjectResult& r : results) {
      char line[512];
      std::snprintf(line, sizeof(line), "%s,%s,%s,%.2f,%d,%u,%u,%u,%u,%s,%s,%s", r.frame.c_str(),
                    r.type.c_str(), expected_class(r.type), r.range_m, r.occluded, r.points,
                    r.segment_points, r.best_inside, r.best_size, r.status.c_str(),
                    r.segment_class.c_str(), r.track_class.c_str());
      csv << line;
      for (std::size_t k = 0; k < names.size(); ++k) {
        std::snprintf(line, sizeof(line), ",%.3f", static_cast<double>(r.track_log_odds[k]));
        csv << line;
      }
      csv << '\n';
    }
    if (auto w = formats::write_text_durably(report / "objects.csv", csv.str()); !w)
      return rt::make_error(w.error().message);
    if (auto w = formats::write_text_durably(report / "metrics.json", metrics.dump(2) + "\n"); !w)
      return rt::make_error(w.error().message);
    output.tell(
        rt::formatted("report: %s/objects.csv, metrics.json, frame_*.png\n", o.report.c_str()));
  }
  return {};
}

}  // namespace stac::offline
