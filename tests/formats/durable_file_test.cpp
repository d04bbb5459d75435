// formats/durable_file.hpp: files a kill leaves whole (datasets, states, models, reports) and the
// answer lines people also write by hand.
#include "formats/durable_file.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "stac_cli.hpp"

namespace stac::formats {
namespace {

namespace fs = std::filesystem;

std::string read_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST(DurableFile, TextReplacesTheFileWholeAndLeavesNoTemporary) {
  const auto dir = stac::testing::fresh_dir("stac_durable_text_" + std::to_string(::getpid()));
  const fs::path report = dir / "metrics.json";
  ASSERT_TRUE(write_text_durably(report, "{\"a\": 1}\n"));
  EXPECT_EQ(read_text(report), "{\"a\": 1}\n");
  ASSERT_TRUE(write_text_durably(report, "{}\n"));  // shorter: nothing of the old one is left
  EXPECT_EQ(read_text(report), "{}\n");
  EXPECT_FALSE(fs::exists(dir / "metrics.json.tmp"));
  const auto missing = write_text_durably(dir / "no such folder" / "report.md", "x");
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().message.find("no such folder"), std::string::npos)
      << missing.error().message;
  fs::remove_all(dir);
}

TEST(DurableFile, ALastLineWithoutItsNewlineIsCompletedCutOrRefused) {
  const auto dir = stac::testing::fresh_dir("stac_durable_tail_" + std::to_string(::getpid()));
  const fs::path answers = dir / "labels.jsonl";
  const auto whole = [](const std::string& l) {
    return l.rfind("{\"ok\"", 0) == 0 && l.back() == '}';
  };
  const auto complete = [](const std::string& l) { return !l.empty() && l.back() == '}'; };
  std::ofstream(answers) << "{\"ok\": 1}\n{\"ok\": 2}";  // a person's last line, no newline
  auto r = complete_or_cut_tail(answers, whole, complete);
  ASSERT_TRUE(r);
  EXPECT_FALSE(*r);
  EXPECT_EQ(read_text(answers), "{\"ok\": 1}\n{\"ok\": 2}\n");
  std::ofstream(answers, std::ios::app) << "{\"ok\": 3";  // torn by a kill
  r = complete_or_cut_tail(answers, whole, complete);
  ASSERT_TRUE(r);
  EXPECT_TRUE(*r);
  EXPECT_EQ(read_text(answers), "{\"ok\": 1}\n{\"ok\": 2}\n");
  std::ofstream(answers, std::ios::app) << "{\"wrong\": 4}";  // complete, not a record
  r = complete_or_cut_tail(answers, whole, complete);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("labels.jsonl:3: the last line is complete but not a valid"),
            std::string::npos)
      << r.error().message;
  EXPECT_EQ(read_text(answers), "{\"ok\": 1}\n{\"ok\": 2}\n{\"wrong\": 4}");  // left as it was
  fs::remove_all(dir);
}

}  // namespace
}  // namespace stac::formats
