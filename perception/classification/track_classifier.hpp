// The per-scan classification stage (thesis ch. 1; docs/classification.md "In the pipeline"):
// every track updated with a segment this scan has the segment described and classified, its
// evidence (TrackEvidence) updated and its log odds taken from the augmented discrete Bayes
// filter with the holistic descriptor; then the segment is added to the track's accumulated
// cloud. Tracks that coast keep their last class. State lives in one slot per tracker pool slot
// (tracking::Track::slot), all allocated at construction; nothing here allocates, throws or does
// I/O after it, so a scan's cost is bounded by the number of tracks.
//
// The holistic descriptor is the track's motion now and the descriptors of its accumulated
// cloud as last described: at a track's first segment, that segment's own descriptors; after
// every `holistic_every` segments added to the cloud, the cloud's (up to accumulated_points
// points). So a class needs only its segment described, and the costly cloud descriptions can
// wait until the scan's tracks are published (stac run, docs/run.md). `stac dataset` runs this
// same stage (through an Observer), so training sees exactly the descriptors the runtime
// classifies. The holistic classifier's sum over the accumulated cloud's elements is kept with
// them, so an update costs the segment classifier and 9 holistic elements.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "perception/classification/accumulated_cloud.hpp"
#include "perception/classification/holistic.hpp"
#include "perception/classification/model.hpp"
#include "perception/descriptors/descriptors.hpp"
#include "perception/segmentation/segments.hpp"
#include "perception/tracking/tracker.hpp"
#include "rt/fixed_vector.hpp"

namespace stac::classification {

struct TrackClassifierConfig {
  std::size_t max_tracks = 512;           // = the tracker's max_tracks (one slot per pool slot)
  std::size_t accumulated_points = 1024;  // points kept per track's accumulated cloud
  std::uint32_t holistic_every = 5;  // accumulated cloud described after every N segments added
  std::size_t max_points = 300'000;  // = the segmenter's max_points (begin()'s copy of indices)
  // A segment or accumulated cloud of more points is described from max_points evenly spaced
  // ones (config/stac.yaml's classification.max_segment_points).
  descriptors::DescriptorConfig descriptors{.max_points = 1024};
};

// Empty when usable, else what is wrong (start-up checks).
const char* validate(const TrackClassifierConfig& config) noexcept;

// A track's class after this scan (ScanResult::classes[i] is for tracked.tracks[i]).
struct TrackClass {
  std::uint64_t id = 0;
  bool classified = false;         // a model is loaded and the track has had a segment
  ClassIndex label = kBackground;  // an index into the model's classes
  LogOdds log_odds{};              // augmented DBF, per model class (natural log odds; 0 past them)
  std::uint32_t segments = 0;      // segments classified so far
  // Scans since the class last took a segment of the track (report()): 0 when this scan's
  // segment is in it; 1 when it waits for finish() (stac run's budget, a tentative track) or the
  // track coasted one scan; n after n scans without a segment.
  std::uint32_t age = 0;
};

struct TrackClassifierCounters {
  std::uint64_t segments_described = 0;
  std::uint64_t holistic_described = 0;  // accumulated clouds described
  std::uint64_t segments_empty = 0;      // no finite point: not classified
  // A track whose slot is out of range, or that another track of the same scan holds (the
  // later one is classified): never expected.
  std::uint64_t slot_mismatch = 0;
  std::uint64_t kept_overflow = 0;  // segments begin() could not keep (never expected)
};

// Which of the kept tracks update() classifies.
struct UpdateLimit {
  static constexpr std::int64_t kNoLimit = std::numeric_limits<std::int64_t>::max();
  bool tentative = true;  // false: tentative tracks (not published by default) wait for finish()
  // CLOCK_REALTIME (ns): no track is started at or after this; the ones left wait for finish().
  std::int64_t until_ns = kNoLimit;
};
struct UpdateCount {
  std::size_t classified = 0;  // tracks update() classified
  std::size_t late = 0;        // tracks it would have taken but for its time limit
};

class TrackClassifier {
 public:
  // Sees every classified update (stac dataset records the descriptors), from update().
  class Observer {
   public:
    virtual ~Observer() = default;
    virtual void on_update(const tracking::Track& track, std::span<const float> segment,
                           std::span<const float> holistic) noexcept = 0;
  };

  // `model` null: descriptors are computed (for an observer), no track is classified. Throws
  // std::invalid_argument on a bad configuration (start-up only).
  TrackClassifier(const TrackClassifierConfig& config,
                  std::shared_ptr<const TrackClassifierModel> model);

  void set_observer(Observer* observer) noexcept { observer_ = observer; }

  // Whether `model` can replace the current one: a model is loaded (the classifier was built
  // with one), and `model` has this build's descriptor sizes and the same class names (what the
  // outputs were sized and named for). Empty when it can, else what is wrong. Allocates the
  // message: call it where that is allowed (the loading thread).
  [[nodiscard]] std::string check_swap(const TrackClassifierModel& model) const;
  // Swaps in `model` (check_swap() accepted it) between scans (not between begin() and
  // finish()): every track's evidence restarts (its segments are classified by the new model
  // from the next scan on, its class stays until then) and its accumulated cloud's holistic
  // part is summed again. No allocation (a shared_ptr copy); the old model is released here, so
  // the caller keeps a reference to it and drops it off the real-time thread.
  void set_model(const std::shared_ptr<const TrackClassifierModel>& model) noexcept;
  [[nodiscard]] const TrackClassifierModel* model() const noexcept { return model_.get(); }
  [[nodiscard]] bool has_model() const noexcept { return model_ != nullptr; }

  // One scan. `xyzi` + `stride_bytes`: the scan's points (x, y, z, intensity first), which
  // `segments` index; `out` gets one TrackClass per tracked.tracks entry (capacity >= max_tracks).
  // The same as begin(), update(), finish(), report().
  void classify(const float* xyzi, std::size_t stride_bytes, const segmentation::Segments& segments,
                const tracking::TrackerOutput& tracked, rt::FixedVector<TrackClass>& out) noexcept;

  // The same in steps, for a loop that publishes a scan's tracks in between (stac run):
  // begin() keeps the scan's tracks that have a segment and a copy of their segments' point
  // indices (`segments` may change afterwards; the points must stay until finish()), ordered
  // by the segments each has been classified with, fewest first. update() classifies the kept
  // tracks `limit` allows, in that order, and counts them and those its time limit left.
  // finish() classifies every kept track left, then adds their segments to the accumulated
  // clouds and describes the clouds that are due. report() gives
  // the tracks' classes as they are: a track not yet classified this scan has the class the
  // scans before left (a track first seen: unclassified). Whatever the steps' timing, the
  // classes after finish() are classify()'s.
  void begin(const segmentation::Segments& segments,
             const tracking::TrackerOutput& tracked) noexcept;
  UpdateCount update(const float* xyzi, std::size_t stride_bytes,
                     const UpdateLimit& limit) noexcept;
  void finish(const float* xyzi, std::size_t stride_bytes) noexcept;
  void report(const tracking::TrackerOutput& tracked,
              rt::FixedVector<TrackClass>& out) const noexcept;
  [[nodiscard]] bool has_kept() const noexcept { return !kept_tracks_.empty(); }

  [[nodiscard]] const TrackClassifierCounters& counters() const noexcept { return counters_; }
  [[nodiscard]] const TrackClassifierConfig& config() const noexcept { return config_; }

 private:
  struct Slot {
    AccumulatedCloud cloud;
    TrackEvidence evidence;
    TrackClass cls;  // cls.id: the track this slot holds; 0: none yet (track ids start at 1)
    std::uint32_t described = 0;       // segments of this track described (with a finite point)
    std::uint32_t since_holistic = 0;  // segments added since the accumulated cloud was described
    // The holistic descriptor's 931 accumulated elements (valid once described > 0).
    descriptors::Descriptors accumulated;
    LogOdds accumulated_sum{};     // their part of the holistic log odds (GridClassifier::partial)
    std::uint64_t class_scan = 0;  // scans_ when cls last took a segment
    explicit Slot(std::size_t points) : cloud(points) {}
  };
  // A described update waiting for the model (its segment's descriptors: batch_[index]). No
  // member initialisers: FixedVector checks default construction inside this class, where they
  // are not usable yet; append() callers set every member.
  struct Pending {
    Slot* slot;
    bool refresh;  // the accumulated part of the holistic descriptor is new
    std::array<float, kHolisticMotionDimensions> motion;
  };
  // A track kept by begin() (its segment: kept_segments_.segments[track.segment]). No member
  // initialisers, as for Pending: begin() sets every member.
  struct Kept {  // NOLINT(cppcoreguidelines-pro-type-member-init)
    tracking::Track track;
    std::uint32_t priority;  // segments described before this scan (0: a new track)
    bool classified;         // update() has taken it
    bool accumulate;         // its segment had a finite point: finish() adds it to the cloud
    std::uint32_t position;  // in tracked.tracks (ties keep this order)
  };

  // Describes one kept track's segment and queues the model's update (classify_pending()).
  void update_one(const float* xyzi, std::size_t stride_bytes, Kept& k) noexcept;
  // The model's update of every pending slot. The classifiers' tables are walked once for all
  // of them (GridClassifier::partial_batch), so they stay in cache; each slot's arithmetic is
  // the same as classifying it alone.
  void classify_pending() noexcept;
  // The holistic classifier's sums over the accumulated elements of `slots_to_sum_`.
  void sum_accumulated() noexcept;

  TrackClassifierConfig config_;
  std::shared_ptr<const TrackClassifierModel> model_;
  Observer* observer_ = nullptr;
  descriptors::DescriptorPipeline describer_;
  HolisticDescriptor holistic_{};
  std::vector<Slot> slots_;
  std::vector<descriptors::Descriptors> batch_;  // max_tracks segments' descriptors
  rt::FixedVector<Pending> pending_;
  std::vector<const float*> rows_;  // partial_batch's inputs and sums (max_tracks each)
  std::vector<LogOdds> sums_;
  std::vector<LogOdds> segment_log_odds_;
  std::vector<Slot*> slots_to_sum_;       // sum_accumulated()'s slots (max_tracks)
  rt::FixedVector<Kept> kept_tracks_;     // begin()'s tracks, in their order of classification
  std::vector<std::uint64_t> slot_scan_;  // per slot: begin()'s scan count when it kept it
  std::vector<std::uint32_t> slot_kept_;  // per slot: its entry in kept_tracks_ then
  std::uint64_t scans_ = 0;               // begin() calls
  segmentation::Segments kept_segments_;
  TrackClassifierCounters counters_;
};

}  // namespace stac::classification
