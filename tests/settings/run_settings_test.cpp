#include "settings/run_settings.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "test_paths.hpp"

namespace stac::settings {
namespace {

const std::filesystem::path kShipped =
    std::filesystem::path(::stac::testing::source_dir()) / "config" / "stac.yaml";

constexpr const char* kRunKeys[] = {"deadline_ms: 100",
                                    "latency_histogram_max_ms: 1000",
                                    "result_slots: 4",
                                    "lock_memory: false",
                                    "cpu_wake_latency_us: 0",
                                    "classify_budget_ms: 12.5",
                                    "receiver_priority: 0",
                                    "receiver_cpu: -1",
                                    "perception_priority: 10",
                                    "perception_cpu: 1",
                                    "publisher_priority: 0",
                                    "publisher_cpu: -1",
                                    "pose_priority: 0",
                                    "pose_cpu: -1",
                                    "ins: tcp",
                                    "ins_address: 127.0.0.1",
                                    "can: false",
                                    "velodyne_timeout_s: 0.2"};

// A file with only a run: section: every key above, `key` replaced by `replacement` ("" drops it).
std::filesystem::path run_section(const std::string& name, const std::string& key,
                                  const std::string& replacement) {
  const auto path =
      std::filesystem::temp_directory_path() / ("stac_run_settings_" + name + ".yaml");
  std::ofstream out(path);
  out << "run:\n";
  for (const std::string line : kRunKeys) {
    if (line.rfind(key + ":", 0) == 0) {
      if (!replacement.empty()) out << "  " << replacement << "\n";
    } else {
      out << "  " << line << "\n";
    }
  }
  return path;
}

TEST(RunSettings, ShippedSectionLoadsWithoutRealTimeRequests) {
  auto s = load_run_settings(kShipped);
  ASSERT_TRUE(s) << s.error().message;
  EXPECT_EQ(s->deadline.budget_ns, 100'000'000);
  EXPECT_EQ(s->deadline.histogram_bins, 10'000u);  // 0.1 ms bins over 1 s
  EXPECT_EQ(s->result_slots, 4u);
  EXPECT_EQ(s->classify_budget_ns, 8'000'000);
  EXPECT_EQ(s->cpu_wake_latency_us, -1);  // no PM QoS request unless asked
  EXPECT_EQ(s->ins, InsTransport::kTcp);
  EXPECT_EQ(s->perception.fifo_priority, 0);
  EXPECT_EQ(s->perception.cpu, -1);
}

TEST(RunSettings, EveryKeyIsReadIntoItsField) {
  auto s = load_run_settings(run_section("all", "none", ""));
  ASSERT_TRUE(s) << s.error().message;
  EXPECT_FALSE(s->lock_memory);
  EXPECT_EQ(s->cpu_wake_latency_us, 0);
  EXPECT_EQ(s->classify_budget_ns, 12'500'000);
  EXPECT_EQ(s->perception.fifo_priority, 10);
  EXPECT_EQ(s->perception.cpu, 1);
  EXPECT_EQ(s->ins_address, "127.0.0.1");
  EXPECT_EQ(s->velodyne_timeout_ns, 200'000'000);
}

TEST(RunSettings, MissingOrInvalidKeysAreNamed) {
  for (const std::string key : {"deadline_ms", "result_slots", "cpu_wake_latency_us",
                                "classify_budget_ms", "pose_cpu", "ins", "velodyne_timeout_s"}) {
    auto missing = load_run_settings(run_section("missing_" + key, key, ""));
    ASSERT_FALSE(missing) << key;
    EXPECT_NE(missing.error().message.find("missing required key 'run." + key + "'"),
              std::string::npos)
        << missing.error().message;
  }
  const std::pair<std::string, std::string> invalid[] = {
      {"deadline_ms", "deadline_ms: 0"},
      {"latency_histogram_max_ms", "latency_histogram_max_ms: 50"},
      {"result_slots", "result_slots: 1"},
      {"classify_budget_ms", "classify_budget_ms: -1"},
      {"classify_budget_ms", "classify_budget_ms: 101"},  // over deadline_ms
      {"cpu_wake_latency_us", "cpu_wake_latency_us: -2"},
      {"perception_priority", "perception_priority: 100"},
      {"receiver_cpu", "receiver_cpu: -2"},
      {"ins", "ins: serial"},
      {"ins_address", "ins_address: pos.local"},
      {"velodyne_timeout_s", "velodyne_timeout_s: -1"}};
  for (const auto& [key, line] : invalid) {
    auto r = load_run_settings(run_section("invalid_" + key, key, line));
    ASSERT_FALSE(r) << line;
    EXPECT_NE(r.error().message.find("'run." + key + "'"), std::string::npos) << r.error().message;
  }
}

}  // namespace
}  // namespace stac::settings
