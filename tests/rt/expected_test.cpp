#include "rt/expected.hpp"

#include <gtest/gtest.h>

namespace stac::rt {
namespace {

Result<int> parse_positive(int v) {
  if (v <= 0) return make_error("value " + std::to_string(v) + " must be positive");
  return v;
}

TEST(Expected, HoldsAValueOrAnError) {
  auto ok = parse_positive(3);
  ASSERT_TRUE(ok);
  EXPECT_EQ(*ok, 3);
  auto bad = parse_positive(-1);
  ASSERT_FALSE(bad);
  EXPECT_EQ(bad.error().message, "value -1 must be positive");
}

TEST(Expected, MovesItsValueOut) {
  Expected<std::string, Error> e(std::string(100, 'a'));
  std::string s = std::move(e).value();
  EXPECT_EQ(s.size(), 100u);
}

}  // namespace
}  // namespace stac::rt
