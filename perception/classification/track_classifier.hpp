// The per-scan classification stage (thesis ch. 1; docs/classification.md "In the pipeline"):
// every track updated with a segment this scan has the segment described and classified, its
// evidence (TrackEvidence) updated, the segment added to the track's accumulated cloud, and its
// log odds taken from the augmented discrete Bayes filter with the holistic descriptor. Tracks
// that coast keep their last class. State lives in one slot per tracker pool slot
// (tracking::Track::slot), all allocated at construction; classify() allocates nothing, throws
// nothing and does no I/O, so its cost per scan is bounded by the number of tracks.
//
// The accumulated cloud's descriptors cost more than a segment's (up to accumulated_points
// points), so they are recomputed at a track's first segment and then every
// `holistic_every` segments; the motion elements of the holistic descriptor are current every
// scan. `stac dataset` runs this same stage (through an Observer), so training sees exactly the
// descriptors the runtime classifies. The holistic classifier's sum over the accumulated cloud's
// elements is kept with them, so an update costs the segment classifier and 9 holistic elements.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
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
  std::size_t accumulated_points = 4096;  // points kept per track's accumulated cloud
  std::uint32_t holistic_every = 5;  // accumulated cloud described every N segments (1: always)
  std::size_t max_points = 300'000;  // = the segmenter's max_points (defer()'s copy of indices)
  descriptors::DescriptorConfig descriptors;
};

// Empty when usable, else what is wrong (start-up checks).
const char* validate(const TrackClassifierConfig& config) noexcept;

// A track's class after this scan (ScanResult::classes[i] is for tracked.tracks[i]).
struct TrackClass {
  std::uint64_t id = 0;
  bool classified = false;  // a model is loaded and the track has had a segment
  ObjectClass label = ObjectClass::kBackground;
  LogOdds log_odds{};          // augmented DBF, per foreground class (natural log odds)
  std::uint32_t segments = 0;  // segments classified so far
};

struct TrackClassifierCounters {
  std::uint64_t segments_described = 0;
  std::uint64_t holistic_described = 0;  // accumulated clouds described
  std::uint64_t segments_empty = 0;      // no finite point: not classified
  std::uint64_t slot_mismatch = 0;       // a track whose slot is out of range (never expected)
  std::uint64_t deferred_overflow = 0;   // segments defer() could not keep (never expected)
};

class TrackClassifier {
 public:
  // Sees every classified update (stac dataset records the descriptors). Called from classify().
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
  [[nodiscard]] bool has_model() const noexcept { return model_ != nullptr; }

  // One scan. `xyzi` + `stride_bytes`: the scan's points (x, y, z, intensity first), which
  // `segments` index; `out` gets one TrackClass per tracked.tracks entry (capacity >= max_tracks).
  void classify(const float* xyzi, std::size_t stride_bytes, const segmentation::Segments& segments,
                const tracking::TrackerOutput& tracked, rt::FixedVector<TrackClass>& out) noexcept;

  // The same in two steps, for a loop that publishes a scan's tracks before it classifies the
  // scan's segments (stac run, docs/run.md): report() gives the tracks' classes as the scans
  // before left them (a track new in this scan: unclassified), defer() keeps a copy of what the
  // update needs (tracks, their segments' point indices), and update_deferred() classifies them
  // later, with the scan's points still valid. Same classes one scan later than classify().
  void report(const tracking::TrackerOutput& tracked,
              rt::FixedVector<TrackClass>& out) const noexcept;
  void defer(const segmentation::Segments& segments,
             const tracking::TrackerOutput& tracked) noexcept;
  void update_deferred(const float* xyzi, std::size_t stride_bytes) noexcept;
  [[nodiscard]] bool has_deferred() const noexcept { return !deferred_tracks_.empty(); }

  [[nodiscard]] const TrackClassifierCounters& counters() const noexcept { return counters_; }
  [[nodiscard]] const TrackClassifierConfig& config() const noexcept { return config_; }

 private:
  struct Slot {
    AccumulatedCloud cloud;
    TrackEvidence evidence;
    TrackClass cls;  // cls.id: the track this slot holds; 0: none yet (track ids start at 1)
    std::uint32_t since_holistic = 0;  // segments added since the accumulated cloud was described
    bool accumulated_ok = false;
    descriptors::Descriptors accumulated;  // the accumulated cloud's last descriptors
    LogOdds accumulated_sum{};  // their part of the holistic log odds (GridClassifier::partial)
    bool pending = false;       // described in this scan, waiting for classify_pending()
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

  void update(const float* xyzi, std::size_t stride_bytes, const segmentation::Segments& segments,
              std::span<const tracking::Track> tracks) noexcept;
  // The model's update of every pending slot. The classifiers' tables are walked once for all
  // of them (GridClassifier::partial_batch), so they stay in cache; each slot's arithmetic is
  // the same as classifying it alone.
  void classify_pending() noexcept;

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
  rt::FixedVector<tracking::Track> deferred_tracks_;
  segmentation::Segments deferred_;
  TrackClassifierCounters counters_;
};

}  // namespace stac::classification
