#include "rt/watchdog.hpp"

#include <gtest/gtest.h>

namespace stac::rt {
namespace {

constexpr std::int64_t kMs = 1'000'000;

TEST(Watchdog, InputSilentPastItsTimeoutIsStalledAndRecoversOnTheNextBeat) {
  Watchdog w;
  w.start({100 * kMs, 0, 0, 0}, 0);
  EXPECT_EQ(w.status(0, 50 * kMs).state,
            InputState::kOk);  // not seen yet, still within its timeout
  EXPECT_FALSE(w.status(0, 50 * kMs).seen);
  w.beat(0, 60 * kMs);
  EXPECT_EQ(w.status(0, 160 * kMs).state, InputState::kOk);  // exactly the timeout: ok
  const InputStatus late = w.status(0, 161 * kMs);
  EXPECT_EQ(late.state, InputState::kStalled);
  EXPECT_TRUE(late.seen);
  EXPECT_EQ(late.age_ns, 101 * kMs);
  w.beat(0, 200 * kMs);
  EXPECT_EQ(w.status(0, 210 * kMs).state, InputState::kOk);
}

TEST(Watchdog, NeverSeenInputStallsAfterItsTimeoutFromStart) {
  Watchdog w;
  w.start({0, 50 * kMs, 0, 0}, 1000 * kMs);
  const InputStatus s = w.status(1, 1051 * kMs);
  EXPECT_EQ(s.state, InputState::kStalled);
  EXPECT_FALSE(s.seen);
  EXPECT_EQ(s.age_ns, 51 * kMs);
}

TEST(Watchdog, InputsWithoutTimeoutAreNotConfigured) {
  Watchdog w;
  w.start({100 * kMs, 0, 0, 0}, 0);
  EXPECT_EQ(w.status(1, 1000 * kMs).state, InputState::kNotConfigured);
  EXPECT_EQ(w.status(Watchdog::kMaxInputs, 0).state, InputState::kNotConfigured);  // out of range
}

TEST(Watchdog, UpdateCountsEachTransitionIntoAStallOnce) {
  Watchdog w;
  w.start({10 * kMs, 10 * kMs, 0, 0}, 0);
  w.beat(0, 0);
  w.beat(1, 0);
  w.update(5 * kMs);
  EXPECT_EQ(w.stalls(0), 0u);
  w.update(20 * kMs);  // both stall
  w.update(30 * kMs);  // still stalled: not counted again
  EXPECT_EQ(w.stalls(0), 1u);
  EXPECT_EQ(w.stalls(1), 1u);
  w.beat(0, 35 * kMs);
  w.update(36 * kMs);  // input 0 recovered
  w.update(50 * kMs);  // and stalled again
  EXPECT_EQ(w.stalls(0), 2u);
  EXPECT_EQ(w.stalls(1), 1u);
  static_assert(noexcept(w.beat(0, 0)));
}

TEST(Watchdog, LostInputStaysLostWhateverBeatsFollowCountsOneStallAndStartClearsIt) {
  Watchdog w;
  w.start({100 * kMs, 100 * kMs, 0, 0}, 0);
  w.beat(0, 10 * kMs);
  w.beat(1, 10 * kMs);
  w.update(20 * kMs);
  w.lose(0);
  const InputStatus lost = w.status(0, 20 * kMs);  // within its timeout, but gone
  EXPECT_EQ(lost.state, InputState::kLost);
  EXPECT_TRUE(lost.seen);
  EXPECT_EQ(lost.age_ns, 10 * kMs);
  EXPECT_EQ(w.status(1, 20 * kMs).state, InputState::kOk);  // the others are untouched
  w.beat(0, 30 * kMs);                                      // a late beat does not bring it back
  EXPECT_EQ(w.status(0, 40 * kMs).state, InputState::kLost);
  w.update(40 * kMs);
  w.update(500 * kMs);  // lost and now also past its timeout: still the one transition
  EXPECT_EQ(w.stalls(0), 1u);
  EXPECT_STREQ(to_string(InputState::kLost), "lost");
  w.lose(2);  // not configured: stays so
  EXPECT_EQ(w.status(2, 40 * kMs).state, InputState::kNotConfigured);
  w.start({100 * kMs, 100 * kMs, 0, 0}, 1000 * kMs);
  EXPECT_EQ(w.status(0, 1010 * kMs).state, InputState::kOk);
  static_assert(noexcept(w.lose(0)));
}

}  // namespace
}  // namespace stac::rt
