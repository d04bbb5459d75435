// The binned classifier's table arithmetic: bin edges, out-of-range and NaN values, the column
// sums, model validation, and no allocation in classify().
#include "perception/classification/grid_classifier.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <type_traits>

#include "perception/classification/holistic.hpp"
#include "perception/descriptors/descriptors.hpp"
#include "rt/testing/alloc_counter.hpp"
#include "synthetic.hpp"

namespace stac::classification {
namespace {

static_assert(noexcept(std::declval<const GridClassifier&>().classify(
    std::declval<std::span<const float>>(), std::declval<LogOdds&>())));
static_assert(noexcept(predict(std::declval<const LogOdds&>(), std::size_t{3})));

// Two elements, grids of 10 and 4 bins over [0, 10) (element 0) and [-1, 1) (element 1); cell c
// of the table holds responses (c, 10c, 100c).
GridClassifier two_element_classifier() {
  GridModel m;
  m.layout = {{"a", 1}, {"b", 1}};
  m.resolutions = {10, 4};
  m.prior = {0.5f, -1.0f, -2.0f};
  m.lower = {0.0f, 0.0f, -1.0f, -1.0f};
  m.scale = {1.0f, 0.4f, 5.0f, 2.0f};
  for (int c = 0; c < 28; ++c)
    m.table.insert(m.table.end(), {float(c), 10.0f * float(c), 100.0f * float(c)});
  auto c = GridClassifier::create(std::move(m));
  EXPECT_TRUE(c.has_value()) << c.error().message;
  return std::move(c).value();
}

TEST(GridClassifier, BinEdgesAndOutOfRangeValuesFallInEdgeBins) {
  const GridClassifier c = two_element_classifier();
  const float inf = std::numeric_limits<float>::infinity();
  EXPECT_EQ(c.bin(0, 0.0f), 0u);
  EXPECT_EQ(c.bin(0, 0.999f), 0u);
  EXPECT_EQ(c.bin(0, 1.0f), 1u);
  EXPECT_EQ(c.bin(0, 9.999f), 9u);
  EXPECT_EQ(c.bin(0, 10.0f), 9u);  // upper edge of the range: last bin
  EXPECT_EQ(c.bin(0, 1e9f), 9u);
  EXPECT_EQ(c.bin(0, -5.0f), 0u);
  EXPECT_EQ(c.bin(0, -inf), 0u);
  EXPECT_EQ(c.bin(0, inf), 9u);
  EXPECT_EQ(c.bin(0, std::nanf("")), 10u);  // no bin
  EXPECT_EQ(c.bin(1, 2.4f), 0u);            // 4 bins of 2.5 over [0, 10)
  EXPECT_EQ(c.bin(1, 2.6f), 1u);
  EXPECT_EQ(c.bin(3, -0.51f), 0u);  // 4 bins of 0.5 over [-1, 1)
  EXPECT_EQ(c.bin(3, 0.49f), 2u);
}

TEST(GridClassifier, TableLayoutIsElementMajorThenResolutionThenBin) {
  const GridClassifier c = two_element_classifier();
  EXPECT_EQ(c.grid_count(), 4u);
  EXPECT_EQ(c.cell_count(), 28u);
  EXPECT_EQ(c.cell_offset(0), 0u);
  EXPECT_EQ(c.cell_offset(1), 10u);
  EXPECT_EQ(c.cell_offset(2), 14u);
  EXPECT_EQ(c.cell_offset(3), 24u);
}

TEST(GridClassifier, ClassifyAddsOneColumnPerGridToThePrior) {
  const GridClassifier c = two_element_classifier();
  const float x[2] = {3.5f, 0.3f};  // cells 3, 10 + 1, 14 + 6, 24 + 2
  LogOdds out{};
  ASSERT_TRUE(c.classify(x, out));
  const float cells = 3 + 11 + 20 + 26;
  EXPECT_FLOAT_EQ(out[0], 0.5f + cells);
  EXPECT_FLOAT_EQ(out[1], -1.0f + 10 * cells);
  EXPECT_FLOAT_EQ(out[2], -2.0f + 100 * cells);

  const float with_nan[2] = {std::nanf(""), 0.3f};  // element 0 adds nothing
  ASSERT_TRUE(c.classify(with_nan, out));
  EXPECT_FLOAT_EQ(out[0], 0.5f + 20 + 26);
}

TEST(GridClassifier, ClassifyEqualsTheSumOverBinOfEveryGrid) {
  // The branch-free look-up of classify() against bin(), on a trained model and inputs that are
  // often out of range, infinite or NaN.
  const auto data = testing::noisy(300, 8, 0.1, 3);
  const GridClassifier c = testing::trained(data, testing::flat_layout(8), {.rounds = 300});
  std::mt19937 rng(4);
  std::normal_distribution<float> g(0.0f, 4.0f);
  std::uniform_int_distribution<int> odd(0, 9);
  const float inf = std::numeric_limits<float>::infinity();
  std::vector<float> x(8);
  for (int t = 0; t < 500; ++t) {
    for (auto& v : x) {
      const int o = odd(rng);
      v = o == 0 ? std::nanf("") : o == 1 ? inf : o == 2 ? -inf : g(rng);
    }
    LogOdds expected = c.model().prior, out{};
    for (std::size_t grid = 0; grid < c.grid_count(); ++grid) {
      const std::uint32_t b = c.bin(grid, x[grid / 2]);
      if (b == c.bins(grid)) continue;
      for (std::size_t k = 0; k < kDefaultClassCount; ++k)
        expected[k] += c.model().table[(c.cell_offset(grid) + b) * kDefaultClassCount + k];
    }
    ASSERT_TRUE(c.classify(x, out));
    for (std::size_t k = 0; k < kDefaultClassCount; ++k) EXPECT_NEAR(out[k], expected[k], 1e-4f);
  }
}

TEST(GridClassifier, PartialSumsOfTwoRangesAddUpToClassify) {
  const auto data = testing::noisy(300, 8, 0.1, 7);
  const GridClassifier c = testing::trained(data, testing::flat_layout(8), {.rounds = 200});
  std::mt19937 rng(8);
  std::normal_distribution<float> g(0.0f, 3.0f);
  std::vector<float> x(8);
  for (int t = 0; t < 200; ++t) {
    for (auto& v : x) v = g(rng);
    if (t % 5 == 0) x[6] = std::nanf("");
    LogOdds full{}, parts = c.model().prior, tail{};
    ASSERT_TRUE(c.classify(x, full));
    const std::span<const float> all(x);
    ASSERT_TRUE(c.partial(all.subspan(3), 3, 8, tail));
    ASSERT_TRUE(c.partial(all.first(3), 0, 3, parts));
    for (std::size_t k = 0; k < kDefaultClassCount; ++k)
      EXPECT_NEAR(parts[k] + tail[k], full[k], 1e-4f);
  }
  LogOdds sum{};
  EXPECT_FALSE(c.partial(std::span<const float>(x).first(3), 6, 9, sum));  // past the layout
  EXPECT_FALSE(c.partial(std::span<const float>(x).first(2), 0, 3, sum));  // wrong size
  EXPECT_EQ(sum, LogOdds{});
}

TEST(GridClassifier, PartialBatchGivesEveryInputPartialsSumsBitForBit) {
  // More inputs than one batch holds (so two table walks), NaN and out-of-range values, a range
  // that starts inside the layout, and sums that do not start at zero.
  const auto data = testing::noisy(300, 8, 0.1, 11);
  const GridClassifier c = testing::trained(data, testing::flat_layout(8), {.rounds = 300});
  std::mt19937 rng(12);
  std::normal_distribution<float> g(0.0f, 4.0f);
  const std::size_t n = GridClassifier::kBatch + 13;
  std::vector<std::vector<float>> x(n, std::vector<float>(5));
  std::vector<const float*> rows;
  std::vector<LogOdds> batch(n), one(n);
  for (std::size_t j = 0; j < n; ++j) {
    for (auto& v : x[j]) v = g(rng);
    if (j % 7 == 0) x[j][1] = std::nanf("");
    if (j % 11 == 0) x[j][4] = std::numeric_limits<float>::infinity();
    rows.push_back(x[j].data());
    batch[j] = one[j] = {0.25f * float(j), -1.0f, 3.0f};
  }
  ASSERT_TRUE(c.partial_batch(rows, 3, 8, batch));
  for (std::size_t j = 0; j < n; ++j) {
    ASSERT_TRUE(c.partial(x[j], 3, 8, one[j]));
    for (std::size_t k = 0; k < kDefaultClassCount; ++k)
      EXPECT_EQ(batch[j][k], one[j][k]) << j << " " << k;
  }
  EXPECT_NE(batch[1], (LogOdds{0.25f, -1.0f, 3.0f}));  // the sums did move
  const std::vector<LogOdds> before = batch;
  EXPECT_FALSE(c.partial_batch(rows, 6, 9, batch));  // past the layout
  EXPECT_FALSE(c.partial_batch(std::span(rows).first(3), 3, 8, std::span(batch).first(2)));
  EXPECT_EQ(batch, before);
  EXPECT_TRUE(c.partial_batch({}, 0, 8, {}));  // nothing to do
}

TEST(GridClassifier, WrongInputSizeIsRefusedWithThePrior) {
  const GridClassifier c = two_element_classifier();
  const float x[3] = {1, 2, 3};
  LogOdds out{};
  EXPECT_FALSE(c.classify(x, out));
  EXPECT_EQ(out, c.model().prior);
}

TEST(GridClassifier, CreateRefusesInconsistentModels) {
  GridModel good = two_element_classifier().model();
  auto expect_refused = [](GridModel m, const char* what) {
    auto c = GridClassifier::create(std::move(m));
    ASSERT_FALSE(c.has_value()) << what;
    EXPECT_FALSE(c.error().message.empty());
  };
  GridModel m = good;
  m.table.pop_back();
  expect_refused(m, "short table");
  m = good;
  m.scale[2] = 0.0f;
  expect_refused(m, "zero scale");
  m = good;
  m.lower[0] = std::nanf("");
  expect_refused(m, "NaN lower");
  m = good;
  m.resolutions = {10, 0};
  expect_refused(m, "zero bins");
  m = good;
  m.layout.clear();
  expect_refused(m, "empty layout");
  m = good;
  m.layout = {{"huge", 0xFFFFFFFFu}, {"huge2", 0xFFFFFFFFu}};
  expect_refused(m, "layout too large for its products to be safe");
  m = good;
  m.resolutions.assign(17, 1);
  expect_refused(m, "too many resolutions");
  for (const std::size_t classes : {std::size_t{0}, kMaxClasses + 1}) {
    m = good;
    m.classes = classes;
    expect_refused(m, "class count not 1..kMaxClasses");
  }
  m = good;
  m.prior[kDefaultClassCount] = 1.0f;
  expect_refused(m, "prior of an unused class");
  EXPECT_TRUE(GridClassifier::create(good).has_value());
}

TEST(GridClassifier, EveryClassCountUpToTheMaximumClassifiesWithItsOwnStride) {
  // The table's stride is the model's class count: each count's classify() is the sum of the
  // bins' columns of that many responses, and the entries past the count stay 0.
  for (std::size_t classes = 1; classes <= kMaxClasses; ++classes) {
    const auto data = testing::separable(200, 4, static_cast<unsigned>(classes), classes);
    const GridClassifier c =
        testing::trained(data, testing::flat_layout(4), {.rounds = 60, .seed = 2});
    ASSERT_EQ(c.classes(), classes);
    ASSERT_EQ(c.model().table.size(), c.cell_count() * classes);
    std::mt19937 rng(static_cast<unsigned>(classes));
    std::uniform_real_distribution<float> u(-1.0f, 2.0f * static_cast<float>(classes) + 2.0f);
    std::vector<float> x(4);
    for (int t = 0; t < 50; ++t) {
      for (auto& v : x) v = u(rng);
      LogOdds expected = c.model().prior, out{};
      for (std::size_t grid = 0; grid < c.grid_count(); ++grid) {
        const std::uint32_t b = c.bin(grid, x[grid / 2]);
        for (std::size_t k = 0; k < classes; ++k)
          expected[k] += c.model().table[(c.cell_offset(grid) + b) * classes + k];
      }
      ASSERT_TRUE(c.classify(x, out));
      for (std::size_t k = 0; k < kMaxClasses; ++k) EXPECT_NEAR(out[k], expected[k], 1e-4f);
      for (std::size_t k = classes; k < kMaxClasses; ++k) EXPECT_EQ(out[k], 0.0f);
    }
    EXPECT_GT(testing::accuracy(c, data), 0.9) << classes << " classes";
  }
}

TEST(Predict, LargestLogOddsOrBackgroundWhenAllNegative) {
  EXPECT_EQ(predict({-0.1f, 2.0f, 1.0f}, 3), kPedestrian);
  EXPECT_EQ(predict({3.0f, 2.0f, 1.0f}, 3), kCar);
  EXPECT_EQ(predict({-3.0f, -0.5f, 0.25f}, 3), kBicyclist);
  EXPECT_EQ(predict({-3.0f, -0.5f, -0.25f}, 3), kBackground);
  // Only the model's classes count: entries past them are ignored.
  EXPECT_EQ(predict({-3.0f, -0.5f, -0.25f, 5.0f}, 3), kBackground);
  EXPECT_EQ(predict({-3.0f, -0.5f, -0.25f, 5.0f}, 4), 3);
  EXPECT_EQ(predict({-1, -1, -1, -1, -1, -1, -1, 0.5f}, kMaxClasses), kMaxClasses - 1);
  EXPECT_EQ(predict({0.5f, 2.0f}, 1), kCar);
}

TEST(ClassNames, DefaultNamesAndNamesOfTheModel) {
  const ClassNames names = default_class_names();
  EXPECT_EQ(names, (ClassNames{"car", "pedestrian", "bicyclist"}));
  EXPECT_STREQ(class_name(names, kBicyclist), "bicyclist");
  EXPECT_STREQ(class_name(names, kBackground), "background");
  EXPECT_STREQ(class_name(names, 3), "unknown");
  EXPECT_STREQ(class_name({"car", "pole"}, 1), "pole");
  EXPECT_EQ(check_class_names(names), "");
  EXPECT_EQ(check_class_names({"a", "b", "c", "d", "e", "f", "g", "h"}), "");
  EXPECT_NE(check_class_names({}), "");
  EXPECT_NE(check_class_names({"a", "b", "c", "d", "e", "f", "g", "h", "i"}).find("9 classes"),
            std::string::npos);
  EXPECT_NE(check_class_names({"pole", "pole"}).find("repeats"), std::string::npos);
  EXPECT_NE(check_class_names({"unknown"}).find("reserved"), std::string::npos);
}

TEST(Layouts, SegmentLayoutIsThe29DescriptorSpacesAndHashesDiffer) {
  const Layout seg = segment_layout();
  ASSERT_EQ(seg.size(), descriptors::kSpaceCount);
  EXPECT_EQ(layout_dimensions(seg), descriptors::kDimensions);
  EXPECT_EQ(layout_dimensions(holistic_layout()), kHolisticDimensions);
  Layout renamed = seg;
  renamed[5].name += "_v2";
  EXPECT_NE(layout_hash(seg), layout_hash(renamed));
  Layout resized = seg;
  resized[0].size += 1;
  EXPECT_NE(layout_hash(seg), layout_hash(resized));
}

TEST(GridClassifier, ClassifyOfASegmentAllocatesNothing) {
  auto data = testing::separable(200, descriptors::kDimensions, 5);
  const GridClassifier c = testing::trained(data, segment_layout(), {.rounds = 50});
  LogOdds out{};
  float sink = 0;
  ASSERT_TRUE(c.classify(data.row(0), out));  // warm-up
  rt::testing::AllocationCounter counter;
  for (std::size_t i = 0; i < data.size(); ++i) {
    (void)c.classify(data.row(i), out);
    sink += out[0];
  }
  counter.stop();
  EXPECT_EQ(counter.allocations(), 0u);
  EXPECT_TRUE(std::isfinite(sink));
}

}  // namespace
}  // namespace stac::classification
