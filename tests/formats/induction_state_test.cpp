// stac induct's state file (formats/induction_state.hpp): a damaged count with a valid checksum
// is refused before anything is allocated for its records (issue 47).
#include "formats/induction_state.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <span>
#include <string>
#include <vector>

#include "perception/classification/grid_classifier.hpp"
#include "rt/testing/alloc_counter.hpp"
#include "stac_cli.hpp"

namespace stac::formats {
namespace {

std::vector<std::uint8_t> read_bytes(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST(InductionStateFile, ACountPastTheBytesLeftIsRefusedBeforeAnyAllocationForIt) {
  const auto dir = stac::testing::fresh_dir("stac_state_count_" + std::to_string(::getpid()));
  InductionState s;
  s.classes = {"car", "pedestrian"};
  s.sources.push_back({"x", SourceRole::kUnlabeled});
  ASSERT_TRUE(write_induction_state(dir, s));
  ASSERT_TRUE(read_induction_state(dir));
  std::vector<std::uint8_t> bytes = read_bytes(dir / "state.bin");

  // The sources' count (1) is followed by the one path's length (1) and its byte 'x'.
  std::vector<std::uint8_t> pattern(13, 0);
  pattern[0] = 1;
  pattern[8] = 1;
  pattern[12] = 'x';
  const auto at = std::search(bytes.begin(), bytes.end(), pattern.begin(), pattern.end());
  ASSERT_NE(at, bytes.end());
  const std::uint64_t huge = 20'000'000;  // under the format's own cap, far past the bytes left
  std::memcpy(&*at, &huge, sizeof(huge));
  const std::uint64_t sum =
      classification::fnv1a64(std::span(bytes).first(bytes.size() - sizeof(std::uint64_t)));
  std::memcpy(bytes.data() + bytes.size() - sizeof(sum), &sum, sizeof(sum));  // valid again
  {
    std::ofstream out(dir / "state.bin", std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(bytes.data()),
              static_cast<std::streamsize>(bytes.size()));
  }

  rt::testing::AllocationCounter counter;
  const auto damaged = read_induction_state(dir);
  counter.stop();
  ASSERT_FALSE(damaged);
  EXPECT_NE(damaged.error().message.find("truncated or inconsistent"), std::string::npos)
      << damaged.error().message;
  EXPECT_LT(counter.bytes(), 1u << 20) << "allocated for records the file cannot hold";
  std::filesystem::remove_all(dir);
}

// A source keeps the checksum of the dataset read at its path (version 3): the same contents bind,
// other contents at the same path are refused naming the path, a source never read learns it.
TEST(InductionStateFile, ASourceKeepsItsDatasetsChecksumAndRefusesOtherContents) {
  const auto dir = stac::testing::fresh_dir("stac_state_checksum_" + std::to_string(::getpid()));
  InductionState s;
  s.classes = {"car"};
  s.sources.push_back({"drive_a", SourceRole::kUnlabeled});
  s.sources.push_back({"drive_b", SourceRole::kLabels});
  ASSERT_TRUE(bind_source_dataset(s.sources, "drive_a", 0x1234));
  ASSERT_TRUE(write_induction_state(dir, s));
  auto back = read_induction_state(dir);
  ASSERT_TRUE(back) << back.error().message;
  ASSERT_EQ(back->sources.size(), 2u);
  EXPECT_EQ(back->sources[0].dataset_checksum, 0x1234u);
  EXPECT_EQ(back->sources[1].dataset_checksum, 0u);
  EXPECT_TRUE(bind_source_dataset(back->sources, "drive_a", 0x1234));
  const auto other = bind_source_dataset(back->sources, "drive_a", 0x9999);
  ASSERT_FALSE(other);
  EXPECT_NE(other.error().message.find("drive_a: not the dataset this state read there"),
            std::string::npos)
      << other.error().message;
  EXPECT_NE(other.error().message.find("0000000000009999"), std::string::npos);
  EXPECT_NE(other.error().message.find("0000000000001234"), std::string::npos);
  EXPECT_TRUE(bind_source_dataset(back->sources, "drive_b", 0x5555));
  EXPECT_EQ(back->sources[1].dataset_checksum, 0x5555u);
  EXPECT_TRUE(bind_source_dataset(back->sources, "not_a_source", 0x1));  // nothing to check against
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace stac::formats
