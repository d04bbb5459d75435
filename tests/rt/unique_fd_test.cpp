// Ownership of a descriptor, checked on the kernel's side: fcntl(F_GETFD) fails with EBADF once a
// descriptor is closed. The checks run before any other descriptor is opened, so a closed number
// cannot be handed out again in between.
#include "rt/unique_fd.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include <cerrno>
#include <type_traits>
#include <utility>

namespace stac::rt {
namespace {

static_assert(std::is_nothrow_move_constructible_v<UniqueFd>);
static_assert(std::is_nothrow_move_assignable_v<UniqueFd>);
static_assert(std::is_nothrow_destructible_v<UniqueFd>);
static_assert(!std::is_copy_constructible_v<UniqueFd> && !std::is_copy_assignable_v<UniqueFd>);
static_assert(!std::is_convertible_v<int, UniqueFd>, "taking ownership is spelled out");
static_assert(!std::is_convertible_v<UniqueFd, bool> && std::is_constructible_v<bool, UniqueFd>);
static_assert(noexcept(std::declval<UniqueFd&>().reset(3)));
static_assert(noexcept(std::declval<UniqueFd&>().release()));
static_assert(noexcept(std::declval<const UniqueFd&>().get()));

int open_eventfd() {
  const int fd = ::eventfd(0, EFD_CLOEXEC);
  EXPECT_GE(fd, 0) << "eventfd";
  return fd;
}

bool is_open(int fd) {
  return ::fcntl(fd, F_GETFD) != -1;
}

bool is_closed(int fd) {
  errno = 0;
  return ::fcntl(fd, F_GETFD) == -1 && errno == EBADF;
}

TEST(UniqueFd, HoldsNothingByDefault) {
  const UniqueFd none;
  EXPECT_EQ(none.get(), -1);
  EXPECT_FALSE(none.valid());
  EXPECT_FALSE(none);
  EXPECT_FALSE(UniqueFd(-1));
}

TEST(UniqueFd, ClosesOnDestruction) {
  const int raw = open_eventfd();
  {
    const UniqueFd fd(raw);
    EXPECT_EQ(fd.get(), raw);
    EXPECT_TRUE(fd.valid());
    EXPECT_TRUE(fd);
    EXPECT_TRUE(is_open(raw));
  }
  EXPECT_TRUE(is_closed(raw));
}

TEST(UniqueFd, MoveLeavesSourceEmpty) {
  const int raw = open_eventfd();
  UniqueFd owner;
  {
    UniqueFd a(raw);
    UniqueFd b(std::move(a));
    EXPECT_EQ(a.get(), -1);  // NOLINT(bugprone-use-after-move): the moved-from state is the point
    EXPECT_FALSE(a);
    EXPECT_EQ(b.get(), raw);
    owner = std::move(b);
    EXPECT_EQ(b.get(), -1);  // NOLINT(bugprone-use-after-move)
  }
  EXPECT_TRUE(is_open(raw));  // neither moved-from owner closed it when it died
  EXPECT_EQ(owner.get(), raw);
  owner.reset();
  EXPECT_TRUE(is_closed(raw));
}

TEST(UniqueFd, MoveAssignmentClosesTheDescriptorItReplaces) {
  const int kept = open_eventfd();
  const int replaced = open_eventfd();
  UniqueFd from(kept);
  UniqueFd to(replaced);
  to = std::move(from);
  EXPECT_TRUE(is_closed(replaced));
  EXPECT_TRUE(is_open(kept));
  EXPECT_EQ(to.get(), kept);
}

TEST(UniqueFd, SelfMoveAssignmentKeepsTheDescriptor) {
  const int raw = open_eventfd();
  UniqueFd fd(raw);
  UniqueFd& same = fd;
  fd = std::move(same);
  EXPECT_EQ(fd.get(), raw);
  EXPECT_TRUE(is_open(raw));
}

TEST(UniqueFd, ResetClosesTheOldDescriptor) {
  const int first = open_eventfd();
  const int second = open_eventfd();
  UniqueFd fd(first);
  fd.reset(second);
  EXPECT_TRUE(is_closed(first));
  EXPECT_TRUE(is_open(second));
  EXPECT_EQ(fd.get(), second);
  fd.reset();
  EXPECT_TRUE(is_closed(second));
  EXPECT_EQ(fd.get(), -1);
  EXPECT_FALSE(fd);
}

TEST(UniqueFd, ResetToTheHeldDescriptorKeepsItOpen) {
  const int raw = open_eventfd();
  UniqueFd fd(raw);
  fd.reset(raw);
  EXPECT_TRUE(is_open(raw));
  EXPECT_EQ(fd.get(), raw);
}

TEST(UniqueFd, ReleaseGivesUpOwnership) {
  const int raw = open_eventfd();
  {
    UniqueFd fd(raw);
    EXPECT_EQ(fd.release(), raw);
    EXPECT_EQ(fd.get(), -1);
    EXPECT_FALSE(fd);
  }
  EXPECT_TRUE(is_open(raw));
  ::close(raw);
}

// An owner dying on an error path must not overwrite the errno of the call that failed. Here the
// close itself fails (the number was closed behind the owner's back: EBADF), and errno stays.
TEST(UniqueFd, ClosingKeepsErrno) {
  const int raw = open_eventfd();
  ::close(raw);
  errno = ENOSPC;
  { const UniqueFd stale(raw); }
  EXPECT_EQ(errno, ENOSPC);
}

}  // namespace
}  // namespace stac::rt
