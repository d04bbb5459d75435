// Group induction (thesis ch. 2, sections 2.3-2.5; docs/learning.md): a classifier trained with
// few user labels harvests training examples from unlabeled tracks, a group (a run of at most 10
// segments of one track) at a time. The induction phase holds the segment classifier H fixed and
// gives each group the label minimising its exponential loss against worst-case noise (eq. 2.3);
// the training phase runs parametric boosting on the user's labels, the automatically labelled
// background set B0 and the inducted groups, warm-started from the current classifier, so the
// model stays a fixed table and classification never costs more. Retrospection (2.3.2) de-inducts
// when new labels reveal confident mistakes; a bounded buffer keeps the most useful groups of an
// unbounded stream (2.3.3). Offline code: it allocates.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "perception/classification/model.hpp"
#include "perception/learning/boosting.hpp"
#include "perception/learning/track_training.hpp"

namespace stac::learning {

// A group's label before (or without) induction: it adds nothing to training.
inline constexpr ClassIndex kUninducted = 0xFE;

struct InductionConfig {
  std::size_t max_group_size = 10;  // segments per group (thesis 2.5.2: long tracks are cut)
  // Single induction (the thesis's experiment): y in {0, +1} per class, with B0 for negatives.
  // Dual: y in {-1, 0, +1}; a group every class problem calls -1 is inducted as background.
  bool dual = false;
  double eps_max = 0.0;                // worst-case classifier noise, log odds (eq. 2.3), >= 0
  std::size_t buffer_groups = 20'000;  // unlabeled groups kept (2.3.3)
};

// Empty when usable, else what is wrong.
std::string validate(const InductionConfig& config);

// One unlabeled group: up to max_group_size consecutive segments of a track of `source`.
struct Group {
  std::uint32_t source = 0;        // the caller's index of where the track came from
  std::uint64_t track = 0;         // its tracker id there
  std::uint32_t first = 0;         // its first segment's index in the track
  std::vector<float> segments;     // segment descriptors, one row per segment
  std::vector<float> holistic;     // the track's holistic descriptor after the group's last segment
  ClassIndex label = kUninducted;  // the induction phase's answer: a class, kBackground (dual)
  // The group's term of the training objective under its label, sum over its segments and every
  // class k of exp(-y_k H_k / 2) (0: uninducted); the buffer keeps the largest.
  double usefulness = 0.0;
  // How near an uninducted group came to induction: min over classes of the +1 objective minus
  // the 0 objective, per segment (>= 0; the buffer keeps the smallest after the inducted ones).
  double margin = 0.0;
  [[nodiscard]] std::size_t size(std::size_t dimensions) const noexcept {
    return dimensions == 0 ? 0 : segments.size() / dimensions;
  }
};

// A track's segments cut into groups of at most `max_group_size` (the last may be shorter);
// `holistic_rows` holds the holistic descriptor after each segment (DatasetTrack's layout).
std::vector<Group> cut_into_groups(std::uint32_t source, std::uint64_t track,
                                   std::span<const float> segment_rows,
                                   std::span<const float> holistic_rows,
                                   std::size_t segment_dimensions, std::size_t holistic_dimensions,
                                   std::size_t max_group_size);

// What the induction phase did to the groups it saw.
struct InductionChange {
  std::size_t group = 0;  // index in the buffer passed
  ClassIndex from = kUninducted, to = kUninducted;
};
struct InductionSummary {
  std::vector<std::size_t> inducted;  // per class, then background: groups so labelled now
  std::size_t uninducted = 0;
  std::vector<InductionChange> changes;  // groups whose label changed (de-induction: to == 0xFE)
};

// Per-class worst-case noise: every class gets `eps` (an InductionConfig's eps_max).
LogOdds uniform_noise(double eps) noexcept;

// The induction phase (eq. 2.3) on every group with the segment classifier held fixed: per class
// k, with H_k(x_u) the segment log odds, the objective of y is sum_u exp((-y H_k(x_u) + |y| eps_k)
// / 2) (the boosting loss exp(-yH/2) of this model, docs/classification.md, with its worst-case
// noise |eps_u| <= eps_k), and y = 0 scores the group's size; each class takes the smallest. The
// group's label: the +1 class of smallest objective, else (dual) background when every class says
// -1, else kUninducted. Also sets usefulness and margin.
InductionSummary induction_phase(const GridClassifier& segment, std::span<Group> groups,
                                 const InductionConfig& config, const LogOdds& eps);

// Retrospection's noise (2.3.2): eps_max = max over the new labelled examples of -y H(x), with
// the example the unit that induction decides on, a group. Each new label's segments are cut as
// an unlabeled track is (at most `max_group_size` consecutive ones); per class k (y_k = +1 for
// the track's class, -1 otherwise) a group's W_k = -2 log(mean_u exp(y_k H_k(x_u) / 2)) is the
// margin by which induction would have given it the wrong label (it would iff W_k > eps), and
// eps_k is the largest W_k, at least `floor`. Every group inducted with no more confidence than
// the worst new mistake is then de-inducted. (The max over single segments, which one noisy
// segment decides, was log odds 15-150 on simulated drives and de-inducted nearly the whole
// buffer at every answer; docs/learning.md.)
LogOdds retrospection_noise(const GridClassifier& segment, std::span<const TrackExample> new_labels,
                            std::size_t segment_dimensions, double floor,
                            std::size_t max_group_size);

// Keeps at most `capacity` groups (2.3.3): the inducted ones of largest usefulness first, then
// the uninducted nearest to induction. Order of the kept groups: that ranking. Deterministic.
void keep_most_useful(std::vector<Group>& groups, std::size_t capacity);

// The training data of one round: the user's labelled tracks, the background set B0 (every track
// labelled background) and the inducted groups. Rows: every segment, and one holistic row per
// track or group (its last).
struct RoundData {
  TrainingSet segments, holistic;
  std::size_t user_tracks = 0, background_tracks = 0, inducted_groups = 0;
};
RoundData round_data(std::span<const TrackExample> labels, std::span<const TrackExample> background,
                     std::span<const Group> groups, std::size_t classes,
                     std::size_t segment_dimensions, std::size_t holistic_dimensions);

// `grids` with its table zeroed and its priors those of `data` (log((n_pos+1)/(n_neg+1))): the
// reset H of retrospection, on the same grids. The classes of `kept` (bit k: class k) keep their
// responses and priors.
rt::Result<GridClassifier> reset_classifier(const GridClassifier& grids, const TrainingSet& data,
                                            std::uint32_t kept = 0);

struct TrainingPhaseConfig {
  BoostingConfig segment, holistic;  // seeds, candidates, caps (their `rounds` are not used)
  std::size_t warm_rounds = 200;     // rounds added to the current classifiers
  std::size_t reset_rounds = 1000;   // rounds from a reset classifier
  // Bit k: class k is kept as it is, neither reset nor boosted (a model's classes while new ones
  // are taught, `stac induct --add-classes`); overrides the boosting configs' `frozen`.
  std::uint32_t kept = 0;
};

// The training phase: both classifiers warm-started from `current` (or, with `reset`, restarted
// on its grids) and boosted on `data`; the kept classes stay as they are. The filter's parameters
// are `current`'s.
rt::Result<classification::TrackClassifierModel> training_phase(
    const classification::TrackClassifierModel& current, const RoundData& data, bool reset,
    const TrainingPhaseConfig& config);

// A first model for a new set of classes: grids from every row of `range` (labelled, B0 and
// unlabeled alike), priors from `data`, tables zero, the filter's parameters all 1.
rt::Result<classification::TrackClassifierModel> initial_model(
    const classification::ClassNames& classes, const RoundData& range, const RoundData& data,
    const classification::ExpectedLayouts& layouts, const TrainingPhaseConfig& config);

// `model` with the classes `added` after its own: their responses 0, their priors
// `added_prior`, their filter parameters 1; its own classes unchanged, so they classify as before.
// Fails when the names together are not a model's classes (check_class_names: at most
// kMaxClasses, unique).
rt::Result<classification::TrackClassifierModel> with_added_classes(
    const classification::TrackClassifierModel& model, const classification::ClassNames& added,
    float added_prior = 0.0f);

// Active learning: one track the user has not labelled, with the model's log odds for it.
struct QueryCandidate {
  LogOdds log_odds{};
  bool seen = false;  // the user has already answered about it
};
// How many questions per class of each kind.
struct QueryCounts {
  std::size_t least_confident = 5;      // smallest |log odds| (the thesis's 2.5.2 protocol)
  std::size_t confident_positives = 5;  // largest log odds among those predicted the class
};
// Per class, up to `counts.least_confident` of the least confident tracks (smallest |log odds|),
// then up to `counts.confident_positives` of the most confident positives (largest log odds,
// predicted that class): indices into `candidates`, never a seen one, none twice, in the order
// asked. Nothing is asked about the classes of `kept` (bit k: class k; classes not being taught).
std::vector<std::size_t> choose_queries(std::span<const QueryCandidate> candidates,
                                        std::size_t classes, QueryCounts counts,
                                        std::uint32_t kept = 0);

}  // namespace stac::learning
