#include "perception/classification/grid_classifier.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "perception/descriptors/descriptors.hpp"

namespace stac::classification {
namespace {

// Limits that keep every size product far from overflow (a model from a corrupt file).
constexpr std::uint32_t kMaxBins = 65535;
constexpr std::size_t kMaxDimensions = std::size_t{1} << 24;
constexpr std::size_t kMaxResolutions = 16;

bool all_finite(std::span<const float> v) noexcept {
  for (const float x : v)
    if (!std::isfinite(x)) return false;
  return true;
}
// Responses and priors (log odds) beyond this are no trained model's (training caps a weak
// classifier at a few units): with at most 2^24 grids, a sum of them stays a finite float.
constexpr float kMaxLogOdds = 1e6f;
bool all_bounded(std::span<const float> v) noexcept {
  for (const float x : v)
    if (!(std::fabs(x) <= kMaxLogOdds)) return false;
  return true;
}

}  // namespace

ClassNames default_class_names() {
  return {"car", "pedestrian", "bicyclist"};
}

const char* class_name(const ClassNames& names, ClassIndex c) noexcept {
  if (c == kBackground) return "background";
  return c < names.size() ? names[c].c_str() : "unknown";
}

std::string joined(const ClassNames& names) {
  std::string s;
  for (const std::string& n : names) s += (s.empty() ? "" : ", ") + n;
  return s;
}

std::string check_class_names(const ClassNames& names) {
  if (names.empty() || names.size() > kMaxClasses)
    return std::to_string(names.size()) + " classes, not 1.." + std::to_string(kMaxClasses);
  for (std::size_t k = 0; k < names.size(); ++k) {
    const std::string& n = names[k];
    const std::string which = "class " + std::to_string(k) + " ";
    if (n.empty()) return which + "has an empty name";
    if (n.size() > kMaxClassNameLength)
      return which + "name is longer than " + std::to_string(kMaxClassNameLength) + " characters";
    for (const char ch : n)
      if (ch <= ' ' || ch > '~')
        return which + "name has a character that is not printable ASCII (or is a space)";
    if (n == "background" || n == "unknown")
      return which + "is named '" + n + "', a name reserved for no class";
    for (std::size_t j = 0; j < k; ++j)
      if (names[j] == n) return which + "'" + n + "' repeats class " + std::to_string(j);
  }
  return {};
}

ClassIndex predict(const LogOdds& log_odds, std::size_t classes) noexcept {
  std::size_t best = 0;
  for (std::size_t k = 1; k < classes && k < kMaxClasses; ++k)
    if (log_odds[k] > log_odds[best]) best = k;
  return log_odds[best] < 0.0f ? kBackground : static_cast<ClassIndex>(best);
}

std::size_t layout_dimensions(const Layout& layout) noexcept {
  std::size_t n = 0;
  for (const auto& s : layout) n += s.size;
  return n;
}

std::uint64_t fnv1a64(std::span<const std::uint8_t> bytes, std::uint64_t state) noexcept {
  for (const std::uint8_t b : bytes) state = (state ^ b) * 1099511628211ull;
  return state;
}

std::uint64_t layout_hash(const Layout& layout) noexcept {
  std::uint64_t h = kFnv1a64Offset;
  for (const auto& s : layout) {
    h = fnv1a64({reinterpret_cast<const std::uint8_t*>(s.name.data()), s.name.size()}, h);
    const std::uint8_t tail[5] = {
        0, static_cast<std::uint8_t>(s.size), static_cast<std::uint8_t>(s.size >> 8),
        static_cast<std::uint8_t>(s.size >> 16), static_cast<std::uint8_t>(s.size >> 24)};
    h = fnv1a64(tail, h);
  }
  return h;
}

Layout segment_layout() {
  Layout layout;
  for (const auto& s : descriptors::spaces())
    layout.push_back({std::string(s.name), static_cast<std::uint32_t>(s.size)});
  return layout;
}

rt::Result<GridClassifier> GridClassifier::create(GridModel model) {
  GridClassifier c;
  c.dimensions_ = layout_dimensions(model.layout);
  if (c.dimensions_ == 0) return rt::make_error("classifier layout has no element");
  if (c.dimensions_ > kMaxDimensions)
    return rt::make_error("classifier layout has " + std::to_string(c.dimensions_) +
                          " elements, more than " + std::to_string(kMaxDimensions));
  if (model.resolutions.empty() || model.resolutions.size() > kMaxResolutions)
    return rt::make_error("classifier has " + std::to_string(model.resolutions.size()) +
                          " grid resolutions, not 1.." + std::to_string(kMaxResolutions));
  for (const auto r : model.resolutions) {
    if (r == 0 || r > kMaxBins)
      return rt::make_error("grid resolution " + std::to_string(r) + " is not in 1.." +
                            std::to_string(kMaxBins));
    c.bin_offset_.push_back(static_cast<std::uint32_t>(c.cells_per_element_));
    c.last_bin_.push_back(static_cast<float>(r - 1));
    c.cells_per_element_ += r;
  }
  const std::size_t grids = c.dimensions_ * model.resolutions.size();
  if (model.lower.size() != grids || model.scale.size() != grids)
    return rt::make_error("classifier has " + std::to_string(model.lower.size()) + " lower and " +
                          std::to_string(model.scale.size()) + " scale values for " +
                          std::to_string(grids) + " grids");
  if (model.classes == 0 || model.classes > kMaxClasses)
    return rt::make_error("classifier has " + std::to_string(model.classes) + " classes, not 1.." +
                          std::to_string(kMaxClasses));
  for (std::size_t k = model.classes; k < kMaxClasses; ++k)
    if (model.prior[k] != 0.0f)
      return rt::make_error("classifier prior of unused class " + std::to_string(k) + " is not 0");
  const std::size_t table = c.dimensions_ * c.cells_per_element_ * model.classes;
  if (model.table.size() != table)
    return rt::make_error("classifier table has " + std::to_string(model.table.size()) +
                          " responses, its grids need " + std::to_string(table));
  if (!all_finite(model.prior) || !all_finite(model.lower) || !all_finite(model.table))
    return rt::make_error("classifier holds a value that is not finite");
  if (!all_bounded(model.prior) || !all_bounded(model.table))
    return rt::make_error(
        "classifier holds a log odds over 1e6 in magnitude (no trained model has one; corrupt?)");
  for (const float s : model.scale)
    if (!(std::isfinite(s) && s > 0.0f))
      return rt::make_error("classifier grid scale " + std::to_string(s) + " is not positive");
  c.model_ = std::move(model);
  return c;
}

std::size_t GridClassifier::cell_offset(std::size_t grid) const noexcept {
  const std::size_t r = model_.resolutions.size();
  return (grid / r) * cells_per_element_ + bin_offset_[grid % r];
}

std::uint32_t GridClassifier::bins(std::size_t grid) const noexcept {
  return model_.resolutions[grid % model_.resolutions.size()];
}

std::uint32_t GridClassifier::bin(std::size_t grid, float value) const noexcept {
  const std::uint32_t n = bins(grid);
  const float t = (value - model_.lower[grid]) * model_.scale[grid];
  if (std::isnan(t)) return n;
  if (!(t > 0.0f)) return 0;
  if (t >= static_cast<float>(n)) return n - 1;
  return static_cast<std::uint32_t>(t);
}

bool GridClassifier::classify(std::span<const float> x, LogOdds& out) const noexcept {
  out = model_.prior;
  if (x.size() != dimensions_) return false;
  LogOdds sum{};
  (void)partial(x, 0, dimensions_, sum);
  for (std::size_t k = 0; k < model_.classes; ++k) out[k] += sum[k];
  return true;
}

bool GridClassifier::partial(std::span<const float> x, std::size_t begin, std::size_t end,
                             LogOdds& sum) const noexcept {
  if (x.size() != end - begin) return false;
  const float* row = x.data();
  return partial_batch({&row, 1}, begin, end, {&sum, 1});
}

namespace {
constexpr std::size_t kAhead = 8;  // partial_batch: elements prefetched ahead
}  // namespace

// Same bins as bin(), without its branches; two accumulators (even and odd elements) halve the
// chain of dependent adds. NaN elements add nothing (then no t below is NaN: lower, scale are
// finite, scale > 0). K is the model's class count, a constant here so the column add unrolls.
template <std::size_t K>
void GridClassifier::partial_batch_k(std::span<const float* const> rows, std::size_t begin,
                                     std::size_t end, std::span<LogOdds> sums) const noexcept {
  const std::size_t resolutions = model_.resolutions.size();
  const float* table = model_.table.data();
  const float* lower = model_.lower.data();
  const float* scale = model_.scale.data();
  for (std::size_t first = 0; first < rows.size(); first += kBatch) {
    const std::size_t n = std::min(kBatch, rows.size() - first);
    float acc[kBatch][2][K];
    std::fill_n(&acc[0][0][0], n * 2 * K, 0.0f);
    // The responses of element e's grid r for a value v (not NaN).
    const auto cell_of = [&](std::size_t e, std::size_t r, float v) {
      const std::size_t g = e * resolutions + r;
      const float t = std::min(std::max((v - lower[g]) * scale[g], 0.0f), last_bin_[r]);
      return table + (e * cells_per_element_ + bin_offset_[r] + static_cast<std::uint32_t>(t)) * K;
    };
    for (std::size_t e = begin; e < end; ++e) {
      // The cells kAhead elements on are fetched now: the table (MBs) is not in the nearer
      // caches, and which cell of an element is read depends on the input (no effect on sums).
      if (const std::size_t ahead = e + kAhead; ahead < end) {
        for (std::size_t j = 0; j < n; ++j) {
          const float w = rows[first + j][ahead - begin];
          if (std::isnan(w)) continue;
          for (std::size_t r = 0; r < resolutions; ++r) __builtin_prefetch(cell_of(ahead, r, w));
        }
      }
      for (std::size_t j = 0; j < n; ++j) {
        const float v = rows[first + j][e - begin];
        if (std::isnan(v)) continue;
        float* a = acc[j][e & 1];
        for (std::size_t r = 0; r < resolutions; ++r) {
          const float* cell = cell_of(e, r, v);
          for (std::size_t k = 0; k < K; ++k) a[k] += cell[k];
        }
      }
    }
    for (std::size_t j = 0; j < n; ++j)
      for (std::size_t k = 0; k < K; ++k) sums[first + j][k] += acc[j][0][k] + acc[j][1][k];
  }
}

bool GridClassifier::partial_batch(std::span<const float* const> rows, std::size_t begin,
                                   std::size_t end, std::span<LogOdds> sums) const noexcept {
  if (begin > end || end > dimensions_ || rows.size() != sums.size()) return false;
  static_assert(kMaxClasses == 8, "one case per class count below");
  switch (model_.classes) {
    case 1:
      partial_batch_k<1>(rows, begin, end, sums);
      break;
    case 2:
      partial_batch_k<2>(rows, begin, end, sums);
      break;
    case 3:
      partial_batch_k<3>(rows, begin, end, sums);
      break;
    case 4:
      partial_batch_k<4>(rows, begin, end, sums);
      break;
    case 5:
      partial_batch_k<5>(rows, begin, end, sums);
      break;
    case 6:
      partial_batch_k<6>(rows, begin, end, sums);
      break;
    case 7:
      partial_batch_k<7>(rows, begin, end, sums);
      break;
    case 8:
      partial_batch_k<8>(rows, begin, end, sums);
      break;
    default:
      return false;  // create() refuses other counts
  }
  return true;
}

}  // namespace stac::classification
