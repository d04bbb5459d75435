// The dataset job (dataset_job.hpp): labelled (or unlabeled) tracks from drives. Each drive runs
// through the per-scan pipeline as in `stac process` (decode -> INS deskew -> segment -> track ->
// classify stage); every segment a track is updated with is described by the pipeline's
// classification stage (classification::TrackClassifier, the same code `stac run` classifies
// with), added to the track's accumulated cloud and gives the track's holistic descriptor at that
// time. A track's label is the majority truth class of its segments' points.
#include "offline/dataset_job.hpp"

#include <cstdio>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "drivers/io/pcap_reader.hpp"
#include "drivers/velodyne/scan_stream.hpp"
#include "evaluation/truth_composition.hpp"
#include "formats/capture_input.hpp"
#include "formats/capture_poses.hpp"
#include "formats/capture_sensor.hpp"
#include "formats/dataset_file.hpp"
#include "formats/kitti_raw.hpp"
#include "formats/recorded_drive.hpp"
#include "pipeline/scan_pipeline.hpp"
#include "rt/formatted.hpp"
#include "settings/settings.hpp"
#include "sim/world.hpp"

namespace stac::offline {

using namespace stac::settings;
using namespace stac::formats;
namespace {

using classification::ClassIndex;

using classification::kBackground;

// The thesis's dataset rule (REFERENCE.md §5).
constexpr std::uint32_t kMinSegments = 10;
constexpr std::uint32_t kMinLargestSegment = 75;  // points; at least one segment over this

// The dataset's classes: the default three, then each --class (a simulator background kind).
rt::Result<classification::ClassNames> dataset_classes(const DatasetJobOptions& o) {
  classification::ClassNames names = classification::default_class_names();
  for (const std::string& extra : o.extra_classes) {
    bool kind = false;
    std::string kinds;
    for (auto c = static_cast<int>(sim::ObjectClass::kBuilding);
         c <= static_cast<int>(sim::ObjectClass::kClutter); ++c) {
      const std::string_view n = sim::class_name(static_cast<sim::ObjectClass>(c));
      kind = kind || n == extra;
      kinds += std::string(kinds.empty() ? "" : ", ") + std::string(n);
    }
    if (!kind)
      return rt::make_error("--class " + extra + ": not a simulator background kind (one of " +
                            kinds + ")");
    names.push_back(extra);
  }
  if (const std::string bad = classification::check_class_names(names); !bad.empty())
    return rt::make_error("--class: the dataset would have " + bad);
  return names;
}

// A truth class name's index in `names`, background when none.
ClassIndex class_of(const classification::ClassNames& names, const std::string& cls) {
  for (std::size_t k = 0; k < names.size(); ++k)
    if (names[k] == cls) return static_cast<ClassIndex>(k);
  return kBackground;
}

struct TrackBuild {
  DatasetTrack track;
  std::uint32_t largest = 0;
  // Truth points per class, the last entry background.
  std::array<std::uint64_t, classification::kMaxClasses + 1> class_points{};
  std::vector<SegmentTruth> segment_truth;  // per segment, in order (consistency rule)
  std::vector<TrackSnapshot> samples;       // every segment's point sample; a few are kept
};

// Up to kMaxSnapshotPoints of a segment's points, evenly spread over its indices, relative to
// its centroid (what `stac label` draws).
TrackSnapshot snapshot_of(const velodyne::Scan& scan, const segmentation::Segments& segments,
                          const segmentation::Segment& segment, std::uint32_t index) {
  TrackSnapshot snap;
  snap.segment = index;
  const auto indices = segments.indices(segment);
  const std::size_t n = std::min(indices.size(), kMaxSnapshotPoints);
  snap.points.reserve(4 * n);
  for (std::size_t k = 0; k < n; ++k) {
    const velodyne::Point& p = scan.points[indices[k * indices.size() / n]];
    snap.points.insert(snap.points.end(), {p.x - segment.centroid[0], p.y - segment.centroid[1],
                                           p.z - segment.centroid[2], p.intensity});
  }
  return snap;
}

struct RunCounts {
  std::uint64_t scans = 0, tracks = 0, kept = 0, truth_matched = 0, inconsistent = 0;
};

class Builder : public classification::TrackClassifier::Observer {
 public:
  explicit Builder(Dataset& out) : out_(out) {}

  // The classify stage's descriptors of one track update (called inside pipeline.process()).
  void on_update(const tracking::Track& track, std::span<const float> segment,
                 std::span<const float> holistic) noexcept override {
    auto [it, added] = live_.try_emplace(track.id);
    counts_.tracks += added ? 1 : 0;
    TrackBuild& b = it->second;
    b.track.id = track.id;
    b.track.segment_rows.insert(b.track.segment_rows.end(), segment.begin(), segment.end());
    b.track.holistic_rows.insert(b.track.holistic_rows.end(), holistic.begin(), holistic.end());
    ++b.track.segments;
    updated_.insert(track.id);
  }

  rt::Result<RunCounts> run(const DatasetJobOptions& o, std::size_t k, const JobOutput& output) {
    const std::string& in = o.in[k];
    auto settings = load_pipeline_settings(config_path(o.config));
    if (!settings) return rt::Unexpected<rt::Error>{settings.error()};
    EgoSettings& ego_settings = settings->ego;
    truth_.clear();
    if (out_.labelled) {
      auto t = evaluation::read_truth_file(o.truth[k]);
      if (!t) return rt::Unexpected<rt::Error>{t.error()};
      truth_ = std::move(*t);
      if (truth_.empty()) return rt::make_error(o.truth[k] + ": no truth scans");
    }
    if (!truth_.empty() && truth_.front().origin && !ego_settings.origin) {
      const auto& g = *truth_.front().origin;
      ego_settings.origin = ego::Geodetic{g[0], g[1], g[2]};
    }
    // A KITTI raw drive folder (its OXTS records, and its mounting), or a capture.
    auto recorded = RecordedDrive::open(in, *settings, {o.calib, "", !o.no_deskew});
    if (!recorded) return rt::Unexpected<rt::Error>{recorded.error()};

    source_ = static_cast<std::uint32_t>(out_.sources.size());
    out_.sources.push_back(source_of(in, out_.labelled ? o.truth[k] : std::string()));
    const pipeline::PipelineConfig pc =
        evaluation::offline_pipeline_config(*settings, nullptr, true);
    pipeline::ScanPipeline pipeline(pc);
    pipeline.classifier()->set_observer(this);
    pipeline::ScanResult result = pipeline.make_result();
    counts_ = {};
    truth_next_ = 0;
    const std::string progress_label = "dataset " + std::filesystem::path(in).filename().string();
    auto read = recorded->for_each_scan(
        [&](velodyne::Scan& scan, std::int64_t) {
          pipeline.process(scan, recorded->pose_history(), result);
          handle(scan, result);
          return true;
        },
        [&](double done, double total) { output.advance(progress_label, done, total); });
    if (!read) return rt::Unexpected<rt::Error>{read.error()};
    if (!recorded->capture_error().empty())
      return rt::make_error(capture_breaks_off(recorded->capture_error()));
    for (auto& [id, b] : live_) finish(b);
    live_.clear();
    if (counts_.scans == 0) return rt::make_error(in + ": no complete scan in the capture");
    if (out_.labelled && counts_.truth_matched == 0) {
      return rt::make_error("no scan of " + in + " matches a scan of " + o.truth[k] +
                            " by time: give each capture its own truth file");
    }
    return counts_;
  }

 private:
  void handle(const velodyne::Scan& scan, const pipeline::ScanResult& result) {
    ++counts_.scans;
    // The truth scan of this scan (as `stac process`), and its segments' composition.
    const evaluation::TruthScanRecord* ts =
        truth_.empty() ? nullptr
                       : evaluation::nearest_truth_scan(truth_, truth_next_, result.stamp_ns);
    records_.assign(result.segments.segments.size(), evaluation::SegmentRecord{});
    if (ts != nullptr) {
      evaluation::truth_composition(*ts, scan, result.segments, result.world_T_sensor, records_);
      ++counts_.truth_matched;
    }

    current_.clear();
    for (const tracking::Track& track : result.tracked.tracks) {
      current_.insert(track.id);
      if (track.segment < 0 || updated_.count(track.id) == 0) continue;
      const auto si = static_cast<std::size_t>(track.segment);
      TrackBuild& b = live_.at(track.id);
      const segmentation::Segment& segment = result.segments.segments[si];
      b.largest = std::max(b.largest, segment.count);
      const Eigen::Vector3d at =
          result.world_T_sensor *
          Eigen::Vector3d(segment.centroid[0], segment.centroid[1], segment.centroid[2]);
      b.track.path.insert(b.track.path.end(),
                          {static_cast<float>(at.x()), static_cast<float>(at.y())});
      b.samples.push_back(snapshot_of(scan, result.segments, segment,
                                      static_cast<std::uint32_t>(b.samples.size())));
      std::uint64_t total = 0, most = 0;
      std::int64_t object = -1;
      ClassIndex object_class = kBackground;
      for (const auto& [truth_id, n] : records_[si].truth) {
        ClassIndex c = kBackground;
        for (const evaluation::TruthObjectRecord& obj : ts->objects) {
          if (static_cast<std::int64_t>(obj.id) == truth_id) c = class_of(out_.classes, obj.cls);
        }
        b.class_points[c == kBackground ? out_.classes.size() : c] += n;
        total += n;
        if (c != kBackground && n > most) {
          most = n;
          object = truth_id;
          object_class = c;
        }
      }
      if (2 * most <= total) {
        object = -1;
        object_class = kBackground;
      }
      b.segment_truth.push_back({object, object_class});
    }
    updated_.clear();
    // Tracks the tracker no longer reports are complete.
    for (auto it = live_.begin(); it != live_.end();) {
      if (current_.count(it->first) != 0) {
        ++it;
        continue;
      }
      finish(it->second);
      it = live_.erase(it);
    }
  }

  void finish(TrackBuild& b) {
    if (b.track.segments < kMinSegments || b.largest <= kMinLargestSegment) return;
    const std::size_t background = out_.classes.size();
    std::size_t best = background;
    for (std::size_t c = 0; c <= background; ++c) {
      if (b.class_points[c] > b.class_points[best]) best = c;
    }
    b.track.label = best == background ? kBackground : static_cast<ClassIndex>(best);
    b.track.off_label_segments = off_label_segments(b.track.label, b.segment_truth);
    b.track.source = source_;
    // The snapshots: kMaxSnapshots segments spread from the first to the last.
    const std::size_t n = b.samples.size();
    const std::size_t keep = std::min(n, kMaxSnapshots);
    for (std::size_t k = 0; k < keep; ++k) {
      TrackSnapshot& snap = b.samples[keep == 1 ? 0 : k * (n - 1) / (keep - 1)];
      if (snap.segment < b.track.segments) b.track.snapshots.push_back(std::move(snap));
    }
    if (b.track.path.size() != 2 * std::size_t{b.track.segments}) b.track.path.clear();
    if (!consistent(b.track)) ++counts_.inconsistent;
    out_.tracks.push_back(std::move(b.track));
    ++counts_.kept;
  }

  Dataset& out_;
  std::vector<evaluation::TruthScanRecord> truth_;
  std::size_t truth_next_ = 0;
  std::uint32_t source_ = 0;
  RunCounts counts_;
  std::map<std::uint64_t, TrackBuild> live_;
  std::vector<evaluation::SegmentRecord> records_;
  std::set<std::uint64_t> updated_, current_;  // updated this scan; reported this scan
};

// Writes `data` to `out` and prints a line of counts per class.
rt::Status write_and_summarize(const std::string& dir, const Dataset& data,
                               const JobOutput& output) {
  if (auto w = write_dataset(dir, data); !w) return rt::make_error(w.error().message);
  const std::size_t classes_n = data.classes.size();
  std::vector<std::size_t> per(classes_n + 1, 0);  // per class, then background
  std::size_t inconsistent = 0;
  for (const DatasetTrack& t : data.tracks) {
    ++per[t.label == kBackground ? classes_n : t.label];
    inconsistent += consistent(t) ? 0 : 1;
  }
  std::string listed;
  for (std::size_t c = 0; c < classes_n; ++c)
    listed += data.classes[c] + " " + std::to_string(per[c]) + ", ";
  if (!data.labelled) {
    output.tell(rt::formatted("%s: %zu unlabeled tracks\n", dir.c_str(), data.tracks.size()));
    return {};
  }
  output.tell(rt::formatted("%s: %zu tracks (%sbackground %zu; %zu inconsistent)\n", dir.c_str(),
                            data.tracks.size(), listed.c_str(), per[classes_n], inconsistent));
  return {};
}

// --merge: the datasets one after the other (their sources renumbered) in one, as the Slurm
// job array's last step does with one dataset per capture (deploy/slurm-dataset.sh).
rt::Status run_merge(const DatasetJobOptions& o, const JobOutput& output) {
  if (!o.in.empty() || !o.truth.empty())
    return rt::make_error("--merge joins datasets: give no --in or --truth");
  // One folder given twice would double its tracks, and --out among the inputs would replace an
  // input: both are refused, however the paths are spelt (the folders compared as files).
  for (std::size_t k = 0; k < o.merge.size(); ++k) {
    std::error_code ec;
    for (std::size_t j = 0; j < k; ++j)
      if (std::filesystem::equivalent(o.merge[j], o.merge[k], ec))
        return rt::make_error("--merge names " + o.merge[j] + " twice (also as " + o.merge[k] +
                              "): each dataset once");
    if (std::filesystem::equivalent(o.merge[k], o.out, ec))
      return rt::make_error("--out " + o.out + " is the input " + o.merge[k] +
                            ": write the merged dataset to a new folder");
  }
  Dataset data;
  for (std::size_t k = 0; k < o.merge.size(); ++k) {
    auto part = read_dataset(o.merge[k]);
    if (!part) return rt::make_error(part.error().message);
    if (k == 0) {
      data = std::move(*part);
    } else if (auto a = append_dataset(data, std::move(*part), o.merge[k]); !a) {
      return rt::make_error(a.error().message);
    }
  }
  output.say(rt::formatted("stac dataset: merged %zu datasets (%zu sources)\n", o.merge.size(),
                           data.sources.size()));
  return write_and_summarize(o.out, data, output);
}

}  // namespace

rt::Status run_dataset_job(const DatasetJobOptions& o, const JobOutput& output) {
  if (!o.merge.empty()) return run_merge(o, output);
  if (o.in.empty())
    return rt::make_error("give the captures (--in), or the datasets to join (--merge)");
  if (!o.truth.empty() && o.in.size() != o.truth.size()) {
    return rt::make_error("give one --truth per --in (" + std::to_string(o.in.size()) + " --in, " +
                          std::to_string(o.truth.size()) +
                          " --truth), or none for unlabeled tracks");
  }
  Dataset data;
  data.labelled = !o.truth.empty();
  auto classes = dataset_classes(o);
  if (!classes) return rt::make_error(classes.error().message);
  data.classes = std::move(*classes);
  Builder builder(data);
  for (std::size_t k = 0; k < o.in.size(); ++k) {
    auto r = builder.run(o, k, output);
    if (!r) return rt::make_error(r.error().message);
    output.say(rt::formatted(
        "stac dataset: %s: %llu scans, %llu tracks, %llu kept (>= %u segments, one over "
        "%u points), %llu of them inconsistent (over 10%% of segments tracking or "
        "under-segmentation errors)\n",
        o.in[k].c_str(), static_cast<unsigned long long>(r->scans),
        static_cast<unsigned long long>(r->tracks), static_cast<unsigned long long>(r->kept),
        kMinSegments, kMinLargestSegment, static_cast<unsigned long long>(r->inconsistent)));
  }
  return write_and_summarize(o.out, data, output);
}

}  // namespace stac::offline
