// Model bytes: a bit-exact round trip that classifies the same, and refusal with a message of
// truncated, corrupted, wrong-version, wrong-class and wrong-layout buffers.
#include "perception/classification/model.hpp"

#include <gtest/gtest.h>

#include <bit>
#include <cstring>
#include <random>

#include "perception/classification/holistic.hpp"
#include "perception/descriptors/descriptors.hpp"
#include "synthetic.hpp"

namespace stac::classification {
namespace {

using testing::flat_layout;

constexpr std::size_t kHeader = 16;

// A small model: a 6-element segment classifier and a 2-element holistic one.
ExpectedLayouts small_layouts() {
  return {{{"box", 3}, {"spin", 3}}, {{"speed", 1}, {"count", 1}}};
}

GridClassifier trained(const Layout& layout, std::size_t n, std::size_t rounds, unsigned seed) {
  const auto set = testing::noisy(n, layout_dimensions(layout), 0.1, seed);
  return testing::trained(set, layout, {.rounds = rounds, .seed = seed});
}

TrackClassifierModel small_model() {
  const ExpectedLayouts l = small_layouts();
  return {trained(l.segment, 300, 40, 1),
          trained(l.holistic, 300, 20, 2),
          {{1.0f, 0.5f, 2.0f}, {0.25f, 1.0f, 1.5f}, {3.0f, 0.75f, 1.0f}}};
}

// Recomputes the trailing checksum after an edit of the payload.
void rechecksum(std::vector<std::uint8_t>& b) {
  const std::uint64_t h = fnv1a64(std::span(b).subspan(kHeader, b.size() - kHeader - 8));
  for (int i = 0; i < 8; ++i) b[b.size() - 8 + i] = static_cast<std::uint8_t>(h >> (8 * i));
}

void expect_same_outputs(const GridClassifier& a, const GridClassifier& b, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> g(0.0f, 3.0f);
  std::vector<float> x(a.dimensions());
  for (int t = 0; t < 200; ++t) {
    for (auto& v : x) v = g(rng);
    LogOdds ha{}, hb{};
    ASSERT_TRUE(a.classify(x, ha));
    ASSERT_TRUE(b.classify(x, hb));
    for (std::size_t k = 0; k < kMaxClasses; ++k)
      EXPECT_EQ(std::bit_cast<std::uint32_t>(ha[k]), std::bit_cast<std::uint32_t>(hb[k]));
  }
}

TEST(ModelFormat, RoundTripIsBitExactAndClassifiesTheSame) {
  const TrackClassifierModel model = small_model();
  const auto bytes = serialize(model);
  auto loaded = deserialize(bytes, small_layouts());
  ASSERT_TRUE(loaded.has_value()) << loaded.error().message;
  EXPECT_EQ(serialize(*loaded), bytes);
  EXPECT_EQ(loaded->segment.model().table, model.segment.model().table);
  for (std::size_t k = 0; k < kDefaultClassCount; ++k)
    EXPECT_EQ(loaded->adbf.gamma[k], model.adbf.gamma[k]);
  EXPECT_EQ(loaded->classes, default_class_names());
  expect_same_outputs(model.segment, loaded->segment, 1);
  expect_same_outputs(model.holistic, loaded->holistic, 2);
}

TEST(ModelFormat, FullSizeModelForThisBuildsLayoutsRoundTrips) {
  TrackClassifierModel model{
      trained(segment_layout(), 200, 30, 3), trained(holistic_layout(), 200, 30, 4), {}};
  const auto bytes = serialize(model);
  EXPECT_GT(bytes.size(), descriptors::kDimensions * 110 * kDefaultClassCount * 4);
  auto loaded = deserialize(bytes);  // this build's layouts
  ASSERT_TRUE(loaded.has_value()) << loaded.error().message;
  EXPECT_EQ(serialize(*loaded), bytes);
  expect_same_outputs(model.segment, loaded->segment, 3);
}

TEST(ModelFormat, TruncationAtEveryLengthIsRefused) {
  const auto bytes = serialize(small_model());
  for (std::size_t n = 0; n < bytes.size(); ++n) {
    auto r = deserialize(std::span(bytes).first(n), small_layouts());
    ASSERT_FALSE(r.has_value()) << "truncated to " << n;
    ASSERT_NE(r.error().message.find("bytes"), std::string::npos) << r.error().message;
  }
  auto padded = bytes;
  padded.push_back(0);
  EXPECT_FALSE(deserialize(padded, small_layouts()).has_value());
}

TEST(ModelFormat, EveryFlippedByteIsRefusedWithAMessage) {
  const auto bytes = serialize(small_model());
  for (std::size_t i = 0; i < bytes.size(); ++i) {
    auto b = bytes;
    b[i] ^= 0x5A;
    auto r = deserialize(b, small_layouts());
    ASSERT_FALSE(r.has_value()) << "byte " << i;
    ASSERT_FALSE(r.error().message.empty());
    if (i >= kHeader && i < bytes.size() - 8) {
      ASSERT_NE(r.error().message.find("checksum"), std::string::npos) << r.error().message;
    }
  }
}

TEST(ModelFormat, CorruptPayloadWithAValidChecksumNeverCrashes) {
  // A writer bug rather than a disk error: the checksum is right, the content is not. Loading
  // either succeeds (a changed number) or fails with a message, and never reads out of bounds.
  const auto bytes = serialize(small_model());
  std::mt19937 rng(5);
  std::uniform_int_distribution<std::size_t> at(kHeader, bytes.size() - 9);
  std::size_t refused = 0;
  for (int t = 0; t < 2000; ++t) {
    auto b = bytes;
    b[at(rng)] = static_cast<std::uint8_t>(rng());
    rechecksum(b);
    auto r = deserialize(b, small_layouts());
    if (!r.has_value()) {
      ++refused;
      ASSERT_FALSE(r.error().message.empty());
    }
  }
  EXPECT_GT(refused, 0u);
  auto huge_count = bytes;  // the class count field set to 2^32 - 1
  std::memset(huge_count.data() + kHeader, 0xFF, 4);
  rechecksum(huge_count);
  EXPECT_FALSE(deserialize(huge_count, small_layouts()).has_value());
}

// Issue 31: a model with a valid checksum but huge values made `stac process` write inf and NaN
// log odds (invalid JSON); such a model is refused when it is read.
TEST(ModelFormat, HugeResponsesOrFilterWeightsAreRefused) {
  TrackClassifierModel huge = small_model();
  huge.segment.table()[0] = 1e30f;
  auto r = deserialize(serialize(huge), small_layouts());
  ASSERT_FALSE(r.has_value());
  EXPECT_NE(r.error().message.find("1e6"), std::string::npos) << r.error().message;
  TrackClassifierModel weights = small_model();
  weights.adbf.gamma[0] = 1e20f;
  r = deserialize(serialize(weights), small_layouts());
  ASSERT_FALSE(r.has_value());
  EXPECT_NE(r.error().message.find("filter parameter"), std::string::npos) << r.error().message;
}

TEST(ModelFormat, WrongMagicOrVersionIsRefusedSayingWhat) {
  auto b = serialize(small_model());
  b[0] = 'X';
  auto r = deserialize(b, small_layouts());
  ASSERT_FALSE(r.has_value());
  EXPECT_NE(r.error().message.find("magic"), std::string::npos) << r.error().message;
  b = serialize(small_model());
  b[8] = static_cast<std::uint8_t>(kModelFormatVersion + 1);
  r = deserialize(b, small_layouts());
  ASSERT_FALSE(r.has_value());
  EXPECT_NE(r.error().message.find("version 2"), std::string::npos) << r.error().message;
  EXPECT_NE(r.error().message.find("retrain"), std::string::npos) << r.error().message;
}

// A model of `names` on the small layouts, trained on separable data of that many classes.
TrackClassifierModel small_model_of(const ClassNames& names) {
  const ExpectedLayouts l = small_layouts();
  const auto seg = testing::separable(400, layout_dimensions(l.segment), 5, names.size());
  const auto hol = testing::separable(400, layout_dimensions(l.holistic), 6, names.size());
  TrackClassifierModel m{testing::trained(seg, l.segment, {.rounds = 40, .seed = 5}),
                         testing::trained(hol, l.holistic, {.rounds = 40, .seed = 6}),
                         {},
                         names};
  for (std::size_t k = 0; k < names.size(); ++k) m.adbf.gamma[k] = 0.5f + static_cast<float>(k);
  return m;
}

TEST(ModelFormat, ModelWithUserClassesRoundTripsWithItsNamesAndCount) {
  const ClassNames names = {"car", "pedestrian", "bicyclist", "pole", "traffic_sign"};
  const TrackClassifierModel model = small_model_of(names);
  ASSERT_EQ(model.segment.classes(), 5u);
  const auto bytes = serialize(model);
  auto loaded = deserialize(bytes, small_layouts());
  ASSERT_TRUE(loaded.has_value()) << loaded.error().message;
  EXPECT_EQ(loaded->classes, names);
  EXPECT_EQ(loaded->segment.classes(), 5u);
  EXPECT_EQ(loaded->holistic.classes(), 5u);
  EXPECT_EQ(loaded->adbf.gamma[4], 4.5f);
  EXPECT_EQ(serialize(*loaded), bytes);
  expect_same_outputs(model.segment, loaded->segment, 7);
  // Element 0 tells the class (synthetic.hpp): the 5th class is predicted as itself.
  std::vector<float> x(loaded->segment.dimensions(), 5.0f);
  x[0] = 2.0f * 4 + 0.5f;
  LogOdds h{};
  ASSERT_TRUE(loaded->segment.classify(x, h));
  EXPECT_EQ(predict(h, 5), 4);
  EXPECT_STREQ(class_name(loaded->classes, predict(h, 5)), "traffic_sign");
}

TEST(ModelFormat, ClassNamesComeFromTheModel) {
  auto b = serialize(small_model());
  b[kHeader + 8] = 'b';  // "car" -> "bar" (u32 count, u32 length, then the name)
  rechecksum(b);
  auto r = deserialize(b, small_layouts());
  ASSERT_TRUE(r.has_value()) << r.error().message;
  EXPECT_EQ(r->classes, (ClassNames{"bar", "pedestrian", "bicyclist"}));
}

TEST(ModelFormat, BadClassCountOrNamesAreRefusedSayingHowToRemakeTheModel) {
  const auto refused = [](std::vector<std::uint8_t> b, const std::string& what) {
    rechecksum(b);
    auto r = deserialize(b, small_layouts());
    ASSERT_FALSE(r.has_value()) << what;
    EXPECT_NE(r.error().message.find(what), std::string::npos) << r.error().message;
    EXPECT_NE(r.error().message.find("stac train"), std::string::npos) << r.error().message;
  };
  const auto bytes = serialize(small_model());
  for (const int count : {0, 9, 200}) {
    auto b = bytes;
    b[kHeader] = static_cast<std::uint8_t>(count);
    refused(b, std::to_string(count) + " classes");
  }
  auto b = bytes;
  b[kHeader + 8] = '\t';  // "car" -> "\tar"
  refused(b, "not printable");
  b = bytes;
  std::memcpy(&b[kHeader + 8], "bic", 3);  // "car" -> "bic", then "bicyclist": still unique
  rechecksum(b);
  EXPECT_TRUE(deserialize(b, small_layouts()).has_value());
  // Names a model cannot have: built with them, refused on loading.
  for (const auto& [names, what] : std::vector<std::pair<ClassNames, std::string>>{
           {{"car", "car", "bicyclist"}, "repeats"},
           {{"car", "", "bicyclist"}, "empty"},
           {{"car", "background", "bicyclist"}, "reserved"},
           {{"car", "a b", "bicyclist"}, "space"},
           {{"car", std::string(40, 'x'), "bicyclist"}, "longer than"}}) {
    TrackClassifierModel m = small_model();
    m.classes = names;
    refused(serialize(m), what);
  }
}

TEST(ModelFormat, ModelForAnotherDescriptorLayoutIsRefused) {
  const auto bytes = serialize(small_model());
  ExpectedLayouts other = small_layouts();
  other.segment[1].name = "spin_v2";
  auto r = deserialize(bytes, other);
  ASSERT_FALSE(r.has_value());
  EXPECT_NE(r.error().message.find("segment classifier"), std::string::npos);
  EXPECT_NE(r.error().message.find("'spin'"), std::string::npos) << r.error().message;
  EXPECT_NE(r.error().message.find("retrain"), std::string::npos);
  other = small_layouts();
  other.holistic.push_back({"max_accel", 1});
  r = deserialize(bytes, other);
  ASSERT_FALSE(r.has_value());
  EXPECT_NE(r.error().message.find("holistic classifier"), std::string::npos) << r.error().message;
  // And the small model is not one for this build's 931-element descriptors.
  r = deserialize(bytes);
  ASSERT_FALSE(r.has_value());
  EXPECT_NE(r.error().message.find("931"), std::string::npos) << r.error().message;
}

}  // namespace
}  // namespace stac::classification
