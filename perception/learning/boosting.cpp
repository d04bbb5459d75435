#include "perception/learning/boosting.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

namespace stac::learning {
namespace {

using classification::GridModel;

double sign(ClassIndex label, std::size_t k) noexcept {
  return static_cast<std::size_t>(label) == k ? 1.0 : -1.0;
}

struct Candidate {
  std::size_t grid = 0;
  std::uint32_t bin = 0;
  LogOdds response{};
  double gain = 0;  // change of the total loss (negative: better)
};

}  // namespace

void TrainingSet::add(std::span<const float> x, ClassIndex label) {
  features.insert(features.end(), x.begin(), x.end());
  labels.push_back(label);
}

const char* validate(const BoostingConfig& config) noexcept {
  if (config.candidates_per_round == 0) return "candidates_per_round must be at least 1";
  if (config.resolutions.empty()) return "resolutions must name at least one grid";
  for (const auto bins : config.resolutions)
    if (bins == 0 || bins > 65535) return "every resolution must be 1..65535 bins";
  if (!(config.range_percentile >= 0.0 && config.range_percentile < 0.5))
    return "range_percentile must be in [0, 0.5)";
  if (!(config.range_widen >= 0.0 && config.range_widen <= 1.0))
    return "range_widen must be in [0, 1]";
  if (!(config.max_response > 0.0f && config.max_response < 1e6f))
    return "max_response must be positive";
  return "";
}

float newton_response(const CellStats& s, float max_response) noexcept {
  const double denominator = s.positive + s.negative;
  if (!(denominator > 0.0)) return 0.0f;
  const double c = 2.0 * (s.positive - s.negative) / denominator;
  return static_cast<float>(std::clamp(c, -double{max_response}, double{max_response}));
}

double loss_after(const CellStats& s, float c) noexcept {
  return s.positive * std::exp(-0.5 * c) + s.negative * std::exp(0.5 * c);
}

LogOdds prior_log_odds(const TrainingSet& data) noexcept {
  LogOdds prior{};
  const double n = static_cast<double>(data.size());
  for (std::size_t k = 0; k < data.classes && k < prior.size(); ++k) {
    double positives = 0;
    for (const auto label : data.labels) positives += sign(label, k) > 0 ? 1 : 0;
    prior[k] = static_cast<float>(std::log((positives + 1.0) / (n - positives + 1.0)));
  }
  return prior;
}

rt::Result<GridClassifier> initial_classifier(const TrainingSet& data,
                                              const classification::Layout& layout,
                                              const BoostingConfig& config) {
  const std::size_t n = data.size(), d = data.dimensions;
  if (n == 0) return rt::make_error("training set is empty");
  if (classification::layout_dimensions(layout) != d || data.features.size() != n * d)
    return rt::make_error("training set has " + std::to_string(d) + " dimensions, the layout " +
                          std::to_string(classification::layout_dimensions(layout)));
  if (const char* bad = validate(config); *bad != '\0')
    return rt::make_error(std::string("boosting configuration: ") + bad);
  if (data.classes == 0 || data.classes > classification::kMaxClasses)
    return rt::make_error("training set has " + std::to_string(data.classes) + " classes, not 1.." +
                          std::to_string(classification::kMaxClasses));
  for (const ClassIndex label : data.labels)
    if (label != classification::kBackground && label >= data.classes)
      return rt::make_error("training set has label " + std::to_string(label) + " of " +
                            std::to_string(data.classes) + " classes");
  GridModel m;
  m.classes = data.classes;
  m.layout = layout;
  m.resolutions = config.resolutions;
  std::vector<float> values;
  values.reserve(n);
  for (std::size_t e = 0; e < d; ++e) {
    values.clear();
    for (std::size_t i = 0; i < n; ++i)
      if (const float v = data.features[i * d + e]; std::isfinite(v)) values.push_back(v);
    double lo = 0.0, hi = 1.0;
    if (!values.empty()) {
      std::sort(values.begin(), values.end());
      const double last = static_cast<double>(values.size() - 1);
      lo = values[static_cast<std::size_t>(std::floor(config.range_percentile * last))];
      hi = values[static_cast<std::size_t>(std::ceil((1.0 - config.range_percentile) * last))];
    }
    double span = hi - lo;
    if (!(span > 0.0)) span = std::max(1.0, std::fabs(lo)) * 1e-3;  // constant element
    lo -= config.range_widen * span;
    hi += config.range_widen * span;
    for (const auto bins : config.resolutions) {
      m.lower.push_back(static_cast<float>(lo));
      m.scale.push_back(static_cast<float>(bins / (hi - lo)));
    }
  }
  m.prior = prior_log_odds(data);
  std::size_t cells = 0;
  for (const auto bins : config.resolutions) cells += bins;
  m.table.assign(cells * d * data.classes, 0.0f);
  return GridClassifier::create(std::move(m));
}

BoostingTrainer::BoostingTrainer(const TrainingSet& data, GridClassifier initial,
                                 const BoostingConfig& config)
    : data_(data), classifier_(std::move(initial)), config_(config), rng_(config.seed) {
  const std::size_t n = data.size(), grids = classifier_.grid_count();
  const std::size_t per_element = classifier_.model().resolutions.size();
  bins_.resize(grids * n);
  for (std::size_t g = 0; g < grids; ++g)
    for (std::size_t i = 0; i < n; ++i)
      bins_[g * n + i] = static_cast<std::uint16_t>(
          classifier_.bin(g, data.features[i * data.dimensions + g / per_element]));
  const std::size_t classes = classifier_.classes();
  weights_.resize(n * classes);
  cumulative_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    LogOdds h{};
    (void)classifier_.classify(data.row(i), h);
    for (std::size_t k = 0; k < classes; ++k)
      weights_[i * classes + k] = std::exp(-0.5 * sign(data.labels[i], k) * h[k]);
  }
}

double BoostingTrainer::loss() const noexcept {
  double sum = 0;
  for (const double w : weights_) sum += w;
  return sum;
}

void BoostingTrainer::run(std::size_t rounds) {
  for (std::size_t r = 0; r < rounds; ++r) round();
}

void BoostingTrainer::round() {
  const std::size_t n = data_.size(), grids = classifier_.grid_count();
  const std::size_t classes = classifier_.classes();
  const auto taught = [this](std::size_t k) { return ((config_.frozen >> k) & 1u) == 0; };
  double total = 0;
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t k = 0; k < classes; ++k)
      if (taught(k)) total += weights_[i * classes + k];
    cumulative_[i] = total;
  }
  if (!(total > 0)) {  // every class frozen: nothing to learn
    ++rounds_;
    return;
  }
  Candidate best;
  bool have = false;
  for (std::size_t j = 0; j < config_.candidates_per_round; ++j) {
    // An example drawn in proportion to its weight, a grid drawn uniformly: the example's cell.
    const double u = rng_.uniform() * total;
    const auto it = std::upper_bound(cumulative_.begin(), cumulative_.end(), u);
    const std::size_t i = std::min<std::size_t>(it - cumulative_.begin(), n - 1);
    Candidate c;
    c.grid = static_cast<std::size_t>(rng_.next() % grids);
    c.bin = bins_[c.grid * n + i];
    if (c.bin >= classifier_.bins(c.grid)) continue;  // NaN element: no cell
    std::array<CellStats, classification::kMaxClasses> stats{};
    const std::uint16_t* column = bins_.data() + c.grid * n;
    for (std::size_t m = 0; m < n; ++m) {
      if (column[m] != c.bin) continue;
      for (std::size_t k = 0; k < classes; ++k)
        (sign(data_.labels[m], k) > 0 ? stats[k].positive : stats[k].negative) +=
            weights_[m * classes + k];
    }
    for (std::size_t k = 0; k < classes; ++k) {
      if (!taught(k)) continue;  // response 0: its column and weights stay
      c.response[k] = newton_response(stats[k], config_.max_response);
      c.gain += loss_after(stats[k], c.response[k]) - (stats[k].positive + stats[k].negative);
    }
    if (!have || c.gain < best.gain) best = c, have = true;
  }
  ++rounds_;
  if (!have) return;
  const std::size_t cell = classifier_.cell_offset(best.grid) + best.bin;
  auto table = classifier_.table();
  for (std::size_t k = 0; k < classes; ++k) table[cell * classes + k] += best.response[k];
  const std::uint16_t* column = bins_.data() + best.grid * n;
  for (std::size_t m = 0; m < n; ++m) {
    if (column[m] != best.bin) continue;
    for (std::size_t k = 0; k < classes; ++k)
      weights_[m * classes + k] *= std::exp(-0.5 * sign(data_.labels[m], k) * best.response[k]);
  }
}

rt::Result<GridClassifier> train_boosting(const TrainingSet& data,
                                          const classification::Layout& layout,
                                          const BoostingConfig& config,
                                          const std::function<void(std::size_t)>& on_rounds) {
  auto initial = initial_classifier(data, layout, config);
  if (!initial) return initial;
  BoostingTrainer trainer(data, std::move(initial).value(), config);
  const std::size_t chunk = std::max<std::size_t>(1, config.rounds / 100);
  while (trainer.rounds_done() < config.rounds) {
    trainer.run(std::min(chunk, config.rounds - trainer.rounds_done()));
    if (on_rounds) on_rounds(trainer.rounds_done());
  }
  return trainer.classifier();
}

rt::Result<GridClassifier> average_classifiers(std::span<const GridClassifier> members) {
  if (members.empty()) return rt::make_error("no classifier to average");
  const classification::GridModel& first = members.front().model();
  classification::GridModel mean = first;
  for (std::size_t k = 1; k < members.size(); ++k) {
    const classification::GridModel& m = members[k].model();
    if (m.layout != first.layout || m.resolutions != first.resolutions || m.lower != first.lower ||
        m.scale != first.scale || m.classes != first.classes || m.prior != first.prior ||
        m.table.size() != first.table.size())
      return rt::make_error("classifier " + std::to_string(k) +
                            " has other grids or priors than the first: not averageable");
  }
  const double inv = 1.0 / static_cast<double>(members.size());
  for (std::size_t i = 0; i < mean.table.size(); ++i) {
    double sum = 0.0;
    for (const GridClassifier& m : members) sum += m.model().table[i];
    mean.table[i] = static_cast<float>(sum * inv);
  }
  return GridClassifier::create(std::move(mean));
}

}  // namespace stac::learning
