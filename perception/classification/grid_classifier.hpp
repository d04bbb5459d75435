// Parametric (binned) boosting classifier of thesis ch. 2 (docs/classification.md): every
// descriptor element has one 1-D grid per resolution (10 and 100 bins); a weak classifier is one
// bin with a response per class, responses of the same bin add, so the model is a dense table and
// classify() costs one bin look-up and one K-float column add per grid, however long training ran.
// Outputs are log odds per foreground class (1-vs-all against background).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "rt/expected.hpp"

namespace stac::classification {

// A model's classes (docs/classification.md, "Classes"): up to kMaxClasses foreground classes,
// each an index 0..K-1 into the model's class names; background is none of them (every log odds
// negative). The default model's classes are "car", "pedestrian", "bicyclist".
inline constexpr std::size_t kMaxClasses = 8;
using ClassIndex = std::uint8_t;
inline constexpr ClassIndex kBackground = 0xFF;
inline constexpr ClassIndex kCar = 0, kPedestrian = 1, kBicyclist = 2;  // the default model's
inline constexpr std::size_t kDefaultClassCount = 3;
inline constexpr std::size_t kMaxClassNameLength = 31;  // the DDS class_name bound
using ClassNames = std::vector<std::string>;            // index k: foreground class k's name
ClassNames default_class_names();                       // {"car", "pedestrian", "bicyclist"}
// names[c], "background" for kBackground, "unknown" for an index past the names.
const char* class_name(const ClassNames& names, ClassIndex c) noexcept;
// Empty when `names` can be a model's classes (1..kMaxClasses non-empty, unique names of
// printable ASCII other than space, none "background" or "unknown"), else what is wrong.
std::string check_class_names(const ClassNames& names);
// "car, pedestrian, bicyclist": the names for messages.
std::string joined(const ClassNames& names);

// log P(class | x) / P(not class | x) per foreground class; entries from the model's class count
// on are unused (0).
using LogOdds = std::array<float, kMaxClasses>;

// Of the first `classes` log odds, the index of the largest; kBackground when every one is
// negative (thesis ch. 1).
ClassIndex predict(const LogOdds& log_odds, std::size_t classes) noexcept;

// A named run of descriptor elements; a model records the layout it was trained for.
struct LayoutSpace {
  std::string name;
  std::uint32_t size = 0;
  bool operator==(const LayoutSpace&) const = default;
};
using Layout = std::vector<LayoutSpace>;
std::size_t layout_dimensions(const Layout& layout) noexcept;
std::uint64_t layout_hash(const Layout& layout) noexcept;  // FNV-1a 64 of names and sizes

// FNV-1a 64 of the bytes, continuing from `state` (the model format's checksum too).
inline constexpr std::uint64_t kFnv1a64Offset = 14695981039346656037ull;
std::uint64_t fnv1a64(std::span<const std::uint8_t> bytes,
                      std::uint64_t state = kFnv1a64Offset) noexcept;
Layout segment_layout();  // the 29 spaces of descriptors::spaces() (931 elements)

inline constexpr std::array<std::uint32_t, 2> kDefaultResolutions = {10, 100};  // bins per grid

// Everything a classifier is made of; create() checks it (start-up, model loading).
struct GridModel {
  Layout layout;
  std::vector<std::uint32_t> resolutions;    // bins of each grid of an element, e.g. {10, 100}
  std::size_t classes = kDefaultClassCount;  // K: foreground classes, 1..kMaxClasses
  LogOdds prior{};                           // L0: log prior odds per class, the table's offset
  std::vector<float> lower;                  // per grid: value at the lower edge of bin 0
  std::vector<float> scale;                  // per grid: bins per unit of value (> 0)
  std::vector<float> table;                  // cell_count() * classes responses
};

class GridClassifier {
 public:
  GridClassifier() = default;
  // Fails (message says what) when the class count is not 1..kMaxClasses, prior entries past it
  // are not 0, sizes disagree, a scale is not finite and positive, a
  // resolution is 0 or over 65535, there are more than 16 resolutions or 2^24 elements, or a
  // number is not finite.
  static rt::Result<GridClassifier> create(GridModel model);

  // out = prior + sum over grids of the table column of the bin x[e] falls in. Values below the
  // range fall in bin 0, above it in the last bin; NaN elements add nothing. False (and out =
  // prior) when x.size() != dimensions(). No allocation, exception or I/O.
  [[nodiscard]] bool classify(std::span<const float> x, LogOdds& out) const noexcept;
  // The part of classify()'s sum that elements [begin, end) give (x holds just those elements),
  // added to `sum`: prior + partial(all) = classify() up to float rounding. False (sum
  // unchanged) when the range is outside the layout or x.size() != end - begin.
  [[nodiscard]] bool partial(std::span<const float> x, std::size_t begin, std::size_t end,
                             LogOdds& sum) const noexcept;
  // partial() for many inputs at once (partial() is this with one): rows[j] holds elements
  // [begin, end) of input j, and its part is added to sums[j]. The table is walked once per
  // kBatch inputs, element by element, so it stays in cache; each input's adds come in the
  // order of partial() alone, so every sum is exactly partial()'s. False (sums unchanged) when the
  // range is outside the layout or the spans' sizes differ.
  static constexpr std::size_t kBatch = 64;
  [[nodiscard]] bool partial_batch(std::span<const float* const> rows, std::size_t begin,
                                   std::size_t end, std::span<LogOdds> sums) const noexcept;

  // Grid g = element * resolutions.size() + r; its cells are [cell_offset(g), + resolutions[r]),
  // cell c's responses are table[c * classes() + k].
  [[nodiscard]] std::size_t dimensions() const noexcept { return dimensions_; }
  [[nodiscard]] std::size_t classes() const noexcept { return model_.classes; }
  [[nodiscard]] std::size_t grid_count() const noexcept { return model_.lower.size(); }
  [[nodiscard]] std::size_t cell_count() const noexcept { return cells_per_element_ * dimensions_; }
  [[nodiscard]] std::size_t cell_offset(std::size_t grid) const noexcept;
  [[nodiscard]] std::uint32_t bins(std::size_t grid) const noexcept;
  // The bin of `value` in grid g, clamped to the edge bins; bins(g) (no bin) for NaN.
  [[nodiscard]] std::uint32_t bin(std::size_t grid, float value) const noexcept;
  [[nodiscard]] const GridModel& model() const noexcept { return model_; }
  [[nodiscard]] std::span<float> table() noexcept { return model_.table; }  // training only
  void set_prior(const LogOdds& prior) noexcept { model_.prior = prior; }

 private:
  template <std::size_t K>
  void partial_batch_k(std::span<const float* const> rows, std::size_t begin, std::size_t end,
                       std::span<LogOdds> sums) const noexcept;

  GridModel model_;
  std::size_t dimensions_ = 0;
  std::size_t cells_per_element_ = 0;
  std::vector<std::uint32_t> bin_offset_;  // per resolution: first cell within an element
  std::vector<float> last_bin_;            // per resolution: bins - 1
};

}  // namespace stac::classification
