// Both paths of each scheduling step, honestly: what this process is allowed gets applied and
// verified; in a child that gave up its privileges (nobody, RLIMIT_RTPRIO and RLIMIT_MEMLOCK 0)
// the same requests are refused with a message naming the thread and what to change.
#include "rt/scheduling.hpp"

#include <gtest/gtest.h>
#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cstdio>
#include <thread>
#include <type_traits>
#include <utility>

namespace stac::rt {
namespace {

// Move-only; a move never throws (the request goes with the descriptor).
static_assert(std::is_nothrow_move_constructible_v<CpuLatencyRequest> &&
              std::is_nothrow_move_assignable_v<CpuLatencyRequest> &&
              !std::is_copy_constructible_v<CpuLatencyRequest>);

int first_allowed_cpu() {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof(set), &set) != 0) return -1;
  for (int c = 0; c < CPU_SETSIZE; ++c) {
    if (CPU_ISSET(c, &set)) return c;
  }
  return -1;
}

TEST(Scheduling, ValidateNamesTheThreadAndTheBadValue) {
  EXPECT_TRUE(validate({.fifo_priority = 99, .cpu = -1}, "perception"));
  auto bad = validate({.fifo_priority = 100, .cpu = -1}, "perception");
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("perception"), std::string::npos);
  EXPECT_NE(bad.error().message.find("100"), std::string::npos);
  EXPECT_FALSE(validate({.fifo_priority = 0, .cpu = -2}, "receiver"));
}

TEST(Scheduling, NothingAskedIsNothingDone) {
  EXPECT_TRUE(apply_schedule("test", {}));
}

TEST(Scheduling, PinningToAnAllowedCpuIsAppliedInThatThread) {
  const int cpu = first_allowed_cpu();
  ASSERT_GE(cpu, 0);
  bool ok = false;
  int now_on = -2;
  std::thread t([&] {
    ok = static_cast<bool>(apply_schedule("pinned", {.fifo_priority = 0, .cpu = cpu}));
    cpu_set_t set;
    CPU_ZERO(&set);
    pthread_getaffinity_np(pthread_self(), sizeof(set), &set);
    now_on = CPU_COUNT(&set) == 1 && CPU_ISSET(cpu, &set) ? cpu : -1;
  });
  t.join();
  EXPECT_TRUE(ok);
  EXPECT_EQ(now_on, cpu);
}

TEST(Scheduling, PinningToACpuOutsideTheCpusetIsRefusedWithItsName) {
  auto r = apply_schedule("receiver", {.fifo_priority = 0, .cpu = CPU_SETSIZE - 1});
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("receiver thread: pinning to cpu"), std::string::npos)
      << r.error().message;
}

// Whatever this process may do, the result must say so truthfully: applied means the thread
// really runs SCHED_FIFO at that priority; refused means it still runs SCHED_OTHER.
TEST(Scheduling, FifoPriorityIsEitherAppliedOrRefusedTruthfully) {
  bool applied = false;
  int policy = -1, priority = -1;
  std::string message;
  std::thread t([&] {
    auto r = apply_schedule("perception", {.fifo_priority = 10, .cpu = -1});
    applied = static_cast<bool>(r);
    if (!r) message = r.error().message;
    sched_param p{};
    pthread_getschedparam(pthread_self(), &policy, &p);
    priority = p.sched_priority;
  });
  t.join();
  if (applied) {
    EXPECT_EQ(policy, SCHED_FIFO);
    EXPECT_EQ(priority, 10);
  } else {
    EXPECT_EQ(policy, SCHED_OTHER);
    EXPECT_NE(message.find("SCHED_FIFO priority 10 refused"), std::string::npos) << message;
    std::printf("this process may not use SCHED_FIFO: %s\n", message.c_str());
  }
}

TEST(Scheduling, LockMemoryIsEitherAppliedOrRefusedWithWhatToChange) {
  auto r = lock_memory();
  if (r) {
    munlockall();
  } else {
    EXPECT_NE(r.error().message.find("mlockall"), std::string::npos);
    EXPECT_NE(r.error().message.find("RLIMIT_MEMLOCK"), std::string::npos);
  }
}

// The request's encoding, on a regular file standing in for the device: one binary int32.
TEST(Scheduling, CpuLatencyRequestWritesTheValueAsABinaryInt32) {
  char path[] = "/tmp/stac_cpu_latency_XXXXXX";
  const int fd = mkstemp(path);
  ASSERT_GE(fd, 0);
  close(fd);
  {
    auto r = CpuLatencyRequest::hold(25, path);
    ASSERT_TRUE(r) << r.error().message;
    auto v = CpuLatencyRequest::current(path);
    ASSERT_TRUE(v) << v.error().message;
    EXPECT_EQ(*v, 25);
  }
  EXPECT_FALSE(CpuLatencyRequest::hold(-1, path));
  std::remove(path);
  auto missing = CpuLatencyRequest::hold(0, "/nonexistent/cpu_dma_latency");
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().message.find("/nonexistent/cpu_dma_latency"), std::string::npos);
  EXPECT_NE(missing.error().message.find("root"), std::string::npos);
}

// The kernel's device: held, the aggregate request is at most ours; released, it is back.
TEST(Scheduling, CpuLatencyRequestIsEitherHeldOrRefusedTruthfully) {
  auto before = CpuLatencyRequest::current();
  if (!before) GTEST_SKIP() << "no PM QoS device here: " << before.error().message;
  {
    auto r = CpuLatencyRequest::hold(3);
    if (!r) {
      EXPECT_NE(r.error().message.find("cannot open"), std::string::npos) << r.error().message;
      std::printf("this process may not hold a CPU latency request: %s\n",
                  r.error().message.c_str());
      return;
    }
    auto held = CpuLatencyRequest::current();
    ASSERT_TRUE(held);
    EXPECT_LE(*held, 3);
    CpuLatencyRequest moved = std::move(*r);  // the request moves with the descriptor
    held = CpuLatencyRequest::current();
    ASSERT_TRUE(held);
    EXPECT_LE(*held, 3);
  }
  auto after = CpuLatencyRequest::current();
  ASSERT_TRUE(after);
  EXPECT_EQ(*after, *before);  // closed: the request is gone
}

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
constexpr bool kSanitized = true;
#else
constexpr bool kSanitized = false;
#endif

// The refused path for certain: a child without the privileges asks for both.
void refused_without_privileges() {
  rlimit zero{0, 0};
  setrlimit(RLIMIT_RTPRIO, &zero);
  setrlimit(RLIMIT_MEMLOCK, &zero);
  if (geteuid() == 0 && setuid(65534) != 0) std::_Exit(2);  // nobody: no capabilities left
  auto m = lock_memory();
  auto s = apply_schedule("perception", {.fifo_priority = 10, .cpu = -1});
  if (CpuLatencyRequest::hold(0)) std::_Exit(4);  // the device is root's: nobody may not
  const bool named =
      !s && s.error().message.find("perception thread: SCHED_FIFO") != std::string::npos;
  int policy = -1;
  sched_param p{};
  pthread_getschedparam(pthread_self(), &policy, &p);
  if (m && !kSanitized) std::_Exit(3);  // the sanitizers make mlockall a no-op that succeeds
  std::_Exit(named && policy == SCHED_OTHER ? 0 : 1);
}

TEST(SchedulingDeathTest, WithoutPrivilegesBothRequestsAreRefusedAndTheThreadRunsOn) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(refused_without_privileges(), ::testing::ExitedWithCode(0), "");
}

}  // namespace
}  // namespace stac::rt
