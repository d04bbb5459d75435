// The live component in one process (runtime::Component): a simulated drive's Velodyne packets
// sent over loopback UDP by a replay thread, the component's five threads, DDS readers in this
// process. .ci/sanitizers runs it under ThreadSanitizer.
#include "runtime/component.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <filesystem>
#include <thread>

#include "dds/dds_test_support.hpp"
#include "dds/idl_types.hpp"
#include "replay/udp_replay.hpp"
#include "shared_data.hpp"
#include "sim/drive_writer.hpp"
#include "stac_cli.hpp"
#include "test_paths.hpp"

namespace stac::runtime {
namespace {

using Types = dds::IdlTypes<false>;
constexpr const char* kYaml = "velodyne/calib/rosdrivers_64e_s2.1-sztaki.yaml";

// The shipped configuration, on loopback: any free port, no INS (a parked sensor), its own domain.
ComponentSettings loopback_settings(std::uint32_t domain, const std::string& model) {
  auto s = load_component_settings(std::filesystem::path(::stac::testing::source_dir()) /
                                   "config/stac.yaml");
  EXPECT_TRUE(s.has_value()) << s.error().message;
  s->pipeline.velodyne.calibration = stac::testing::shared_data(kYaml);
  s->pipeline.velodyne.bind_address = "127.0.0.1";
  s->pipeline.velodyne.port = 0;
  s->run.ins = settings::InsTransport::kNone;
  s->run.can = false;
  s->can.reset();
  s->run.lock_memory = false;
  s->dds.domain_id = domain;
  s->dds.config_uri = stac::testing::loopback_uri();
  s->model = model;
  s->name = "component test";
  return *s;
}

TEST(Component, RunsAReplayedDriveInOneProcessAndPublishesEveryScan) {
  STAC_REQUIRE_SHARED_DATA(kYaml);
  const auto dir = stac::testing::fresh_dir("stac_component");
  const std::string pcap = (dir / "drive.pcap").string();
  sim::DriveOptions drive;
  drive.scenario = "urban";
  drive.seed = 4;
  drive.duration_s = 2.0;
  drive.out = pcap;
  drive.truth = (dir / "truth.jsonl").string();
  drive.calib = stac::testing::shared_data(kYaml).string();
  const auto sim = sim::write_drive(drive);
  ASSERT_TRUE(sim) << sim.error().message;

  constexpr std::uint32_t kDomain = 151;
  auto component = Component::create(loopback_settings(kDomain, ""));
  ASSERT_TRUE(component.has_value()) << component.error().message;
  // Every sample kept (the topic's own reader QoS keeps the last one only).
  const dds_entity_t participant = dds_create_participant(kDomain, nullptr, nullptr);
  ASSERT_GT(participant, 0);
  const dds_entity_t topic = dds_create_topic(participant, Types::tracked_objects(),
                                              "stac/tracked_objects", nullptr, nullptr);
  auto qos = dds::reader_qos(dds::Topic::kTrackedObjects);
  dds_qset_history(qos.get(), DDS_HISTORY_KEEP_ALL, 0);
  const dds_entity_t reader = dds_create_reader(participant, topic, qos.get(), nullptr);
  ASSERT_GT(reader, 0);
  dds_subscription_matched_status_t matched{};
  for (int i = 0; i < 1000 && matched.current_count == 0; ++i) {
    dds_sleepfor(DDS_MSECS(10));
    ASSERT_EQ(dds_get_subscription_matched_status(reader, &matched), 0);
  }
  ASSERT_GT(matched.current_count, 0u) << "the component's writer never matched";
  std::thread run([&] { (*component)->run(); });

  replay::ReplayConfig rc;
  rc.port = (*component)->lidar_port();
  auto replay = replay::UdpReplay::open(pcap, rc);
  ASSERT_TRUE(replay.has_value()) << replay.error().message;
  std::atomic<bool> never{false};
  auto sent = replay->run(never);
  ASSERT_TRUE(sent.has_value()) << sent.error().message;
  EXPECT_EQ(sent->packets, replay->plan().packets);

  // Every published scan arrives; then the component stops as a signal would stop it.
  std::uint64_t samples = 0;
  for (int quiet = 0; quiet < 300; ++quiet) {  // until nothing came for 3 s
    dds_sample_info_t info{};
    void* sample[1] = {nullptr};
    while (dds_take(reader, sample, &info, 1, 1) > 0) {
      samples += info.valid_data ? 1 : 0;
      dds_return_loan(reader, sample, 1);
      quiet = 0;
    }
    dds_sleepfor(DDS_MSECS(10));
  }
  (*component)->stop();
  run.join();
  const Summary& s = (*component)->summary();
  EXPECT_TRUE(s.stop_requested);
  // A 2 s drive is about 20 scans: each processed, or dropped and counted (a slow build, such as
  // one with ThreadSanitizer, cannot keep up with the sensor's pace).
  EXPECT_GT(s.scans, 0u);
  EXPECT_GE(s.scans + s.incomplete + s.scan_slots_full, 15u);
  EXPECT_EQ(s.published, s.scans);
  EXPECT_EQ(s.publish_errors, 0u);
  // The port was any free one: a datagram from elsewhere (such as a Cyclone peer still writing to
  // a participant that had this port and exited) is received and refused as wrong size, not
  // taken for a Velodyne packet.
  EXPECT_EQ(s.received - s.wrong_size, sent->packets);
  EXPECT_EQ(s.invalid_block, 0u);
  EXPECT_EQ(samples, s.published);
  EXPECT_EQ(s.deadline_scans, s.published);
  ASSERT_EQ(s.latencies.size(), 9u);
  dds_delete(participant);
  EXPECT_STREQ(s.latencies.back().name, "end-to-end");
}

TEST(Component, StopsAtOnceWithoutDataAndRefusesAReloadWithoutAModel) {
  STAC_REQUIRE_SHARED_DATA(kYaml);
  auto component = Component::create(loopback_settings(152, "none"));
  ASSERT_TRUE(component.has_value()) << component.error().message;
  std::thread run([&] { (*component)->run(); });
  (*component)->reload_model();
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  (*component)->stop();
  run.join();
  const Summary& s = (*component)->summary();
  EXPECT_EQ(s.scans, 0u);
  EXPECT_EQ(s.published, 0u);
  EXPECT_EQ(s.model_refused, 1u);
  EXPECT_LT(s.elapsed_s, 5.0) << "the threads sleep on the data and wake to stop";
}

TEST(Component, CreateNamesWhatToFix) {
  auto settings = loopback_settings(153, "");
  settings.pipeline.velodyne.calibration.clear();
  auto c = Component::create(settings);
  ASSERT_FALSE(c.has_value());
  EXPECT_NE(c.error().message.find("velodyne.calibration"), std::string::npos) << c.error().message;
  settings = loopback_settings(153, "/nonexistent/model.stacmodel");
  c = Component::create(settings);
  ASSERT_FALSE(c.has_value());
  EXPECT_NE(c.error().message.find("/nonexistent/model.stacmodel"), std::string::npos)
      << c.error().message;
}

}  // namespace
}  // namespace stac::runtime
