#include "rt/fixed_vector.hpp"

#include <gtest/gtest.h>

namespace stac::rt {
namespace {

static_assert(noexcept(std::declval<FixedVector<int>&>().push_back(1)));
static_assert(noexcept(std::declval<FixedVector<int>&>().resize(1)));
static_assert(!std::is_copy_constructible_v<FixedVector<int>>);

TEST(FixedVector, PushBackRefusesBeyondCapacity) {
  FixedVector<int> v(3);
  EXPECT_TRUE(v.empty());
  EXPECT_TRUE(v.push_back(1));
  EXPECT_TRUE(v.push_back(2));
  EXPECT_TRUE(v.push_back(3));
  EXPECT_TRUE(v.full());
  EXPECT_FALSE(v.push_back(4));
  EXPECT_EQ(v.size(), 3u);
  EXPECT_EQ(v.back(), 3);
  EXPECT_EQ(v.append(), nullptr);
}

TEST(FixedVector, ResizeKeepsWhatWasWrittenThroughData) {
  FixedVector<int> v(8);
  v.data()[0] = 7;
  v.data()[1] = 9;
  ASSERT_TRUE(v.resize(2));
  EXPECT_EQ(v[0], 7);
  EXPECT_EQ(v[1], 9);
  EXPECT_FALSE(v.resize(9));
  EXPECT_EQ(v.size(), 2u);
  v.clear();
  EXPECT_TRUE(v.empty());
  EXPECT_EQ(v.capacity(), 8u);
}

TEST(FixedVector, StartsValueInitialisedAndMovesItsStorage) {
  FixedVector<double> v(4);
  ASSERT_TRUE(v.resize(4));
  for (double d : v) EXPECT_EQ(d, 0.0);
  const double* storage = v.data();
  FixedVector<double> w(std::move(v));
  EXPECT_EQ(w.data(), storage);
  EXPECT_EQ(w.size(), 4u);
  EXPECT_EQ(v.capacity(), 0u);  // NOLINT(bugprone-use-after-move): moved-from is empty
  EXPECT_FALSE(v.push_back(1.0));
}

TEST(FixedVector, IteratesOverTheSizeOnly) {
  FixedVector<int> v(10);
  for (int i = 0; i < 4; ++i) ASSERT_TRUE(v.push_back(i));
  int sum = 0;
  for (int x : v) sum += x;
  EXPECT_EQ(sum, 6);
  EXPECT_EQ(v.span().size(), 4u);
  v.pop_back();
  EXPECT_EQ(v.size(), 3u);
}

}  // namespace
}  // namespace stac::rt
