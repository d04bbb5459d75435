#include "perception/learning/induction.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <utility>

namespace stac::learning {
namespace {

using classification::kBackground;

double sign(ClassIndex label, std::size_t k) noexcept {
  return static_cast<std::size_t>(label) == k ? 1.0 : -1.0;
}

// The segment log odds of every row of `rows`.
std::vector<LogOdds> log_odds_of(const GridClassifier& segment, std::span<const float> rows,
                                 std::size_t dimensions) {
  std::vector<LogOdds> out(dimensions == 0 ? 0 : rows.size() / dimensions);
  for (std::size_t u = 0; u < out.size(); ++u)
    (void)segment.classify(rows.subspan(u * dimensions, dimensions), out[u]);
  return out;
}

}  // namespace

std::string validate(const InductionConfig& config) {
  if (config.max_group_size < 1 || config.max_group_size > 1000)
    return "group size must be 1..1000 segments";
  if (!(config.eps_max >= 0.0 && config.eps_max <= 100.0))
    return "eps_max must be in [0, 100] (log odds)";
  if (config.buffer_groups < 1 || config.buffer_groups > 10'000'000)
    return "the buffer must hold 1..10,000,000 groups";
  return "";
}

std::vector<Group> cut_into_groups(std::uint32_t source, std::uint64_t track,
                                   std::span<const float> segment_rows,
                                   std::span<const float> holistic_rows,
                                   std::size_t segment_dimensions, std::size_t holistic_dimensions,
                                   std::size_t max_group_size) {
  std::vector<Group> groups;
  if (segment_dimensions == 0 || holistic_dimensions == 0 || max_group_size == 0) return groups;
  const std::size_t n = std::min(segment_rows.size() / segment_dimensions,
                                 holistic_rows.size() / holistic_dimensions);
  for (std::size_t first = 0; first < n; first += max_group_size) {
    const std::size_t count = std::min(max_group_size, n - first);
    Group g;
    g.source = source;
    g.track = track;
    g.first = static_cast<std::uint32_t>(first);
    const auto rows = segment_rows.subspan(first * segment_dimensions, count * segment_dimensions);
    g.segments.assign(rows.begin(), rows.end());
    const auto last =
        holistic_rows.subspan((first + count - 1) * holistic_dimensions, holistic_dimensions);
    g.holistic.assign(last.begin(), last.end());
    groups.push_back(std::move(g));
  }
  return groups;
}

LogOdds uniform_noise(double eps) noexcept {
  LogOdds e{};
  e.fill(static_cast<float>(eps));
  return e;
}

InductionSummary induction_phase(const GridClassifier& segment, std::span<Group> groups,
                                 const InductionConfig& config, const LogOdds& eps) {
  const std::size_t classes = segment.classes(), d = segment.dimensions();
  InductionSummary summary;
  summary.inducted.assign(classes + 1, 0);
  for (std::size_t gi = 0; gi < groups.size(); ++gi) {
    Group& g = groups[gi];
    const std::vector<LogOdds> h = log_odds_of(segment, g.segments, d);
    const double zero = static_cast<double>(h.size());  // y = 0: exp(0) per segment
    ClassIndex label = kUninducted;
    double best_plus = std::numeric_limits<double>::infinity();
    bool all_minus = config.dual && !h.empty();
    double margin = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < classes; ++k) {
      const double e = static_cast<double>(eps[k]);
      double plus = 0, minus = 0;
      for (const LogOdds& x : h) {
        plus += std::exp(0.5 * (-static_cast<double>(x[k]) + e));
        minus += std::exp(0.5 * (static_cast<double>(x[k]) + e));
      }
      // y_k: the smallest objective of the choices allowed; a tie goes to y = 0 (no induction).
      const bool plus_wins = plus < zero && (!config.dual || plus < minus);
      const bool minus_wins = config.dual && minus < zero && minus < plus;
      if (plus_wins && plus < best_plus) best_plus = plus, label = static_cast<ClassIndex>(k);
      if (!minus_wins) all_minus = false;
      const double per_segment = std::max(zero, 1.0);
      margin = std::min(margin, (plus - zero) / per_segment);
      if (config.dual) margin = std::min(margin, (minus - zero) / per_segment);
    }
    if (label == kUninducted && all_minus) label = kBackground;
    if (label != g.label) summary.changes.push_back({gi, g.label, label});
    g.label = label;
    g.usefulness = 0.0;
    g.margin = 0.0;
    if (label == kUninducted) {
      ++summary.uninducted;
      g.margin = std::max(0.0, margin);
      continue;
    }
    ++summary.inducted[label == kBackground ? classes : label];
    for (const LogOdds& x : h)
      for (std::size_t k = 0; k < classes; ++k)
        g.usefulness += std::exp(-0.5 * sign(label, k) * static_cast<double>(x[k]));
  }
  return summary;
}

LogOdds retrospection_noise(const GridClassifier& segment, std::span<const TrackExample> new_labels,
                            std::size_t segment_dimensions, double floor,
                            std::size_t max_group_size) {
  LogOdds eps = uniform_noise(floor);
  const std::size_t classes = segment.classes();
  const std::size_t group = std::max<std::size_t>(max_group_size, 1);
  for (const TrackExample& t : new_labels) {
    const std::vector<LogOdds> h = log_odds_of(segment, t.segments, segment_dimensions);
    for (std::size_t first = 0; first < h.size(); first += group) {
      const std::size_t end = std::min(h.size(), first + group);
      for (std::size_t k = 0; k < classes; ++k) {
        // log(mean exp(a_u)), a_u = y H / 2, taken about the largest a_u: finite for any H.
        const double y = sign(t.label, k);
        double top = -std::numeric_limits<double>::infinity();
        for (std::size_t u = first; u < end; ++u)
          top = std::max(top, 0.5 * y * static_cast<double>(h[u][k]));
        double sum = 0;
        for (std::size_t u = first; u < end; ++u)
          sum += std::exp(0.5 * y * static_cast<double>(h[u][k]) - top);
        const double log_mean = top + std::log(sum / static_cast<double>(end - first));
        eps[k] = std::max(eps[k], static_cast<float>(-2.0 * log_mean));
      }
    }
  }
  for (std::size_t k = classes; k < eps.size(); ++k) eps[k] = 0.0f;
  return eps;
}

void keep_most_useful(std::vector<Group>& groups, std::size_t capacity) {
  const auto inducted = [](const Group& g) { return g.label != kUninducted; };
  std::stable_sort(groups.begin(), groups.end(), [&](const Group& a, const Group& b) {
    if (inducted(a) != inducted(b)) return inducted(a);
    if (inducted(a)) {
      if (a.usefulness != b.usefulness) return a.usefulness > b.usefulness;
    } else if (a.margin != b.margin) {
      return a.margin < b.margin;
    }
    if (a.source != b.source) return a.source < b.source;
    if (a.track != b.track) return a.track < b.track;
    return a.first < b.first;
  });
  if (groups.size() > capacity) groups.resize(capacity);
}

RoundData round_data(std::span<const TrackExample> labels, std::span<const TrackExample> background,
                     std::span<const Group> groups, std::size_t classes,
                     std::size_t segment_dimensions, std::size_t holistic_dimensions) {
  RoundData r;
  r.segments = TrainingSet{segment_dimensions, classes, {}, {}};
  r.holistic = TrainingSet{holistic_dimensions, classes, {}, {}};
  const auto add = [&](std::span<const float> segments, std::span<const float> holistic,
                       ClassIndex label) {
    for (std::size_t i = 0; i + segment_dimensions <= segments.size(); i += segment_dimensions)
      r.segments.add(segments.subspan(i, segment_dimensions), label);
    if (holistic.size() >= holistic_dimensions)
      r.holistic.add(holistic.last(holistic_dimensions), label);
  };
  for (const TrackExample& t : labels) add(t.segments, t.holistic, t.label), ++r.user_tracks;
  for (const TrackExample& t : background)
    add(t.segments, t.holistic, kBackground), ++r.background_tracks;
  for (const Group& g : groups) {
    if (g.label == kUninducted) continue;
    add(g.segments, g.holistic, g.label);
    ++r.inducted_groups;
  }
  return r;
}

rt::Result<GridClassifier> reset_classifier(const GridClassifier& grids, const TrainingSet& data,
                                            std::uint32_t kept) {
  if (data.size() == 0) return rt::make_error("no training example to take priors from");
  if (data.classes != grids.classes())
    return rt::make_error("the data has " + std::to_string(data.classes) +
                          " classes, the classifier " + std::to_string(grids.classes()));
  classification::GridModel m = grids.model();
  const std::size_t classes = m.classes;
  const LogOdds prior = prior_log_odds(data);
  for (std::size_t k = 0; k < classes; ++k) {
    if (((kept >> k) & 1u) != 0) continue;
    for (std::size_t i = k; i < m.table.size(); i += classes) m.table[i] = 0.0f;
    m.prior[k] = prior[k];
  }
  return GridClassifier::create(std::move(m));
}

rt::Result<classification::TrackClassifierModel> training_phase(
    const classification::TrackClassifierModel& current, const RoundData& data, bool reset,
    const TrainingPhaseConfig& config) {
  if (data.segments.size() == 0 || data.holistic.size() == 0)
    return rt::make_error("nothing to train on: no labelled track, background or inducted group");
  const auto train = [&](const GridClassifier& now, const TrainingSet& set,
                         const BoostingConfig& boosting,
                         const char* what) -> rt::Result<GridClassifier> {
    if (set.dimensions != now.dimensions())
      return rt::make_error(std::string(what) + ": the data has " + std::to_string(set.dimensions) +
                            " dimensions, the classifier " + std::to_string(now.dimensions()));
    GridClassifier start = now;
    if (reset) {
      auto zeroed = reset_classifier(now, set, config.kept);
      if (!zeroed) return rt::make_error(std::string(what) + ": " + zeroed.error().message);
      start = std::move(zeroed).value();
    }
    BoostingConfig kept_as_they_are = boosting;
    kept_as_they_are.frozen = config.kept;
    BoostingTrainer trainer(set, std::move(start), kept_as_they_are);
    trainer.run(reset ? config.reset_rounds : config.warm_rounds);
    return trainer.classifier();
  };
  if (const char* bad = validate(config.segment); *bad != '\0')
    return rt::make_error(std::string("segment boosting: ") + bad);
  if (const char* bad = validate(config.holistic); *bad != '\0')
    return rt::make_error(std::string("holistic boosting: ") + bad);
  auto seg = train(current.segment, data.segments, config.segment, "segment classifier");
  if (!seg) return rt::make_error(seg.error().message);
  auto hol = train(current.holistic, data.holistic, config.holistic, "holistic classifier");
  if (!hol) return rt::make_error(hol.error().message);
  classification::TrackClassifierModel next;
  next.classes = current.classes;
  next.adbf = current.adbf;
  next.segment = std::move(seg).value();
  next.holistic = std::move(hol).value();
  return next;
}

rt::Result<classification::TrackClassifierModel> initial_model(
    const classification::ClassNames& classes, const RoundData& range, const RoundData& data,
    const classification::ExpectedLayouts& layouts, const TrainingPhaseConfig& config) {
  if (const std::string bad = classification::check_class_names(classes); !bad.empty())
    return rt::make_error("classes: " + bad);
  const auto make = [&](const TrainingSet& r, const TrainingSet& d,
                        const classification::Layout& layout, const BoostingConfig& boosting,
                        const char* what) -> rt::Result<GridClassifier> {
    if (r.classes != classes.size() || d.classes != classes.size())
      return rt::make_error(std::string(what) + ": the data's class count is not the classes'");
    auto grids = initial_classifier(r, layout, boosting);
    if (!grids) return rt::make_error(std::string(what) + ": " + grids.error().message);
    auto zeroed = reset_classifier(*grids, d);
    if (!zeroed) return rt::make_error(std::string(what) + ": " + zeroed.error().message);
    return zeroed;
  };
  auto seg =
      make(range.segments, data.segments, layouts.segment, config.segment, "segment classifier");
  if (!seg) return rt::make_error(seg.error().message);
  auto hol =
      make(range.holistic, data.holistic, layouts.holistic, config.holistic, "holistic classifier");
  if (!hol) return rt::make_error(hol.error().message);
  classification::TrackClassifierModel m;
  m.classes = classes;
  m.segment = std::move(seg).value();
  m.holistic = std::move(hol).value();
  return m;
}

rt::Result<classification::TrackClassifierModel> with_added_classes(
    const classification::TrackClassifierModel& model, const classification::ClassNames& added,
    float added_prior) {
  classification::ClassNames names = model.classes;
  names.insert(names.end(), added.begin(), added.end());
  if (const std::string bad = classification::check_class_names(names); !bad.empty())
    return rt::make_error("the model's classes and the added ones (" +
                          classification::joined(names) + "): " + bad);
  const std::size_t before = model.classes.size(), after = names.size();
  const auto widen = [&](const GridClassifier& c) {
    classification::GridModel m = c.model();
    std::vector<float> table(m.table.size() / before * after, 0.0f);
    for (std::size_t cell = 0; cell < m.table.size() / before; ++cell)
      std::copy_n(m.table.begin() + static_cast<std::ptrdiff_t>(cell * before), before,
                  table.begin() + static_cast<std::ptrdiff_t>(cell * after));
    m.table = std::move(table);
    m.classes = after;
    for (std::size_t k = before; k < after; ++k) m.prior[k] = added_prior;
    return GridClassifier::create(std::move(m));
  };
  auto seg = widen(model.segment);
  if (!seg) return rt::make_error("segment classifier: " + seg.error().message);
  auto hol = widen(model.holistic);
  if (!hol) return rt::make_error("holistic classifier: " + hol.error().message);
  classification::TrackClassifierModel out;
  out.classes = std::move(names);
  out.segment = std::move(seg).value();
  out.holistic = std::move(hol).value();
  out.adbf = model.adbf;
  for (std::size_t k = before; k < after; ++k)
    out.adbf.alpha[k] = out.adbf.beta[k] = out.adbf.gamma[k] = 1.0f;
  return out;
}

std::vector<std::size_t> choose_queries(std::span<const QueryCandidate> candidates,
                                        std::size_t classes, QueryCounts counts,
                                        std::uint32_t kept) {
  std::vector<std::size_t> chosen;
  std::vector<bool> taken(candidates.size(), false);
  std::vector<std::size_t> order(candidates.size());
  const auto pick = [&](std::size_t wanted, auto&& better, auto&& eligible) {
    if (wanted == 0) return;
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::stable_sort(order.begin(), order.end(), better);
    std::size_t n = 0;
    for (const std::size_t i : order) {
      if (n == wanted) break;
      if (candidates[i].seen || taken[i] || !eligible(i)) continue;
      taken[i] = true;
      chosen.push_back(i);
      ++n;
    }
  };
  for (std::size_t k = 0; k < classes; ++k) {
    if (((kept >> k) & 1u) != 0) continue;
    pick(
        counts.least_confident,
        [&](std::size_t a, std::size_t b) {
          return std::fabs(candidates[a].log_odds[k]) < std::fabs(candidates[b].log_odds[k]);
        },
        [](std::size_t) { return true; });
    pick(
        counts.confident_positives,
        [&](std::size_t a, std::size_t b) {
          return candidates[a].log_odds[k] > candidates[b].log_odds[k];
        },
        [&](std::size_t i) {
          return classification::predict(candidates[i].log_odds, classes) == ClassIndex(k);
        });
  }
  return chosen;
}

}  // namespace stac::learning
