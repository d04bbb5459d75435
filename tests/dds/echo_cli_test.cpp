// `stac echo` as a user runs it: a second process receives what this test process publishes
// over loopback (config/dds/loopback.xml, a tag unique to this process), and with no publisher
// it times out with a message saying so.
#include <gtest/gtest.h>
#include <pthread.h>
#include <sched.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "dds/publisher.hpp"
#include "dds_test_support.hpp"
#include "test_paths.hpp"

namespace stac::dds {
namespace {

using testing::run_to_end;

TEST(StacEcho, ReceivesTrackedObjectsFromAnotherProcess) {
  const std::string uri = testing::loopback_uri();  // sets DDS_TEST_TAG, inherited by the child
  const std::string cmd = std::string(::stac::testing::stac_cli()) +
                          " echo tracked_objects --count 5 --timeout 20 --domain 121 2>&1";
  FILE* child = popen(cmd.c_str(), "r");
  ASSERT_NE(child, nullptr);

  PublisherConfig c;
  c.domain_id = 121;
  c.config_uri = uri;
  auto pub = Publisher::create(c);
  ASSERT_TRUE(pub) << pub.error().message;
  ASSERT_TRUE(testing::TestReader::wait_matched((*pub)->writer(Topic::kTrackedObjects)));
  TrackedObjectIn o;
  o.object_id = 77;
  o.position = {12.5, -4.0, 0.5};
  o.classified = true;
  const std::vector<std::string> names = {"car", "pedestrian", "bicyclist", "pole"};
  o.class_names = names;  // a user-taught 4th class, most probable: shown by its name
  o.class_log_odds = {-3, -3, -3, 3, -3};
  std::vector<TrackedObjectIn> objects{o};
  for (std::uint64_t scan = 0; scan < 5; ++scan) {
    ASSERT_TRUE((*pub)->publish_tracked_objects(
        {static_cast<std::int64_t>(scan) * 100'000'000, scan}, objects));
    // Keep-last 1 replaces an unacknowledged sample (latest wins, by design): wait for the ack so
    // a loaded machine cannot turn this into a lost-sample race.
    ASSERT_EQ(dds_wait_for_acks((*pub)->writer(Topic::kTrackedObjects), DDS_SECS(10)), 0);
  }
  int code = -1;
  const std::string out = run_to_end(child, &code);
  EXPECT_EQ(code, 0) << out;
  EXPECT_NE(out.find("tracked_objects scan 0 "), std::string::npos) << out;
  EXPECT_NE(out.find("tracked_objects scan 4 "), std::string::npos) << out;
  EXPECT_NE(out.find("#77 pole x=12.50 y=-4.00"), std::string::npos) << out;
  EXPECT_NE(out.find("5 samples on stac/tracked_objects"), std::string::npos) << out;
}

// Whether this process may run a thread at SCHED_FIFO 50 (root, CAP_SYS_NICE or RLIMIT_RTPRIO).
bool may_run_fifo_50() {
  bool ok = false;
  std::thread([&] {
    const sched_param p{50};
    ok = pthread_setschedparam(pthread_self(), SCHED_FIFO, &p) == 0;
  }).join();
  return ok;
}

// config/dds/loopback-rt.xml: the same loopback path, its one receive thread at SCHED_FIFO 50.
TEST(StacEcho, RealTimeLoopbackConfigReceivesOnASchedFifoReceiveThread) {
  if (!may_run_fifo_50()) GTEST_SKIP() << "SCHED_FIFO not permitted here (Cyclone would abort)";
  (void)testing::loopback_uri();  // the tag
  const std::string xml =
      std::string(::stac::testing::source_dir()) + "/config/dds/loopback-rt.xml";
  const std::string cmd =
      std::string(::stac::testing::stac_cli()) +
      " echo tracked_objects --count 3 --timeout 20 --domain 124 --dds-config " + xml + " 2>&1";
  FILE* child = popen(cmd.c_str(), "r");
  ASSERT_NE(child, nullptr);
  PublisherConfig c;
  c.domain_id = 124;
  c.config_uri = "file://" + xml;
  auto pub = Publisher::create(c);
  ASSERT_TRUE(pub) << pub.error().message;
  // This process's Cyclone receive thread ("recv", the only one) runs SCHED_FIFO.
  int fifo_recv = 0, other_recv = 0;
  for (const auto& task : std::filesystem::directory_iterator("/proc/self/task")) {
    std::ifstream comm(task.path() / "comm");
    std::string name;
    std::getline(comm, name);
    if (name.rfind("recv", 0) != 0) continue;
    (sched_getscheduler(std::stoi(task.path().filename().string())) == SCHED_FIFO ? fifo_recv
                                                                                  : other_recv)++;
  }
  EXPECT_EQ(fifo_recv, 1);
  EXPECT_EQ(other_recv, 0);
  ASSERT_TRUE(testing::TestReader::wait_matched((*pub)->writer(Topic::kTrackedObjects)));
  TrackedObjectIn o;
  o.object_id = 9;
  std::vector<TrackedObjectIn> objects{o};
  for (std::uint64_t scan = 0; scan < 3; ++scan) {
    ASSERT_TRUE((*pub)->publish_tracked_objects(
        {static_cast<std::int64_t>(scan) * 100'000'000, scan}, objects));
    ASSERT_EQ(dds_wait_for_acks((*pub)->writer(Topic::kTrackedObjects), DDS_SECS(10)), 0);
  }
  int code = -1;
  const std::string out = run_to_end(child, &code);
  EXPECT_EQ(code, 0) << out;
  EXPECT_NE(out.find("3 samples on stac/tracked_objects"), std::string::npos) << out;
}

// examples/c_subscriber, built from idl/stac.idl alone, reads what the publisher writes.
TEST(CSubscriberExample, PrintsIdsPositionsAndClassNamesFromAnotherProcess) {
  const std::string uri = testing::loopback_uri();
  const std::string cmd =
      "CYCLONEDDS_URI=" + uri + " " + ::stac::testing::c_subscriber() + " 3 123 2>&1";
  FILE* child = popen(cmd.c_str(), "r");
  ASSERT_NE(child, nullptr);
  PublisherConfig c;
  c.domain_id = 123;
  c.config_uri = uri;
  auto pub = Publisher::create(c);
  ASSERT_TRUE(pub) << pub.error().message;
  ASSERT_TRUE(testing::TestReader::wait_matched((*pub)->writer(Topic::kTrackedObjects)));
  TrackedObjectIn a, b;
  a.object_id = 5;
  a.position = {1.25, 2.5, 0};
  const std::vector<std::string> names = {"car", "pedestrian", "bicyclist"};
  a.classified = true;
  a.class_names = names;
  a.class_log_odds = {-2, 1.5, -2, -1.5};
  b.object_id = 6;
  b.position = {-30, 40.75, 0};
  std::vector<TrackedObjectIn> objects{a, b};
  for (std::uint64_t scan = 0; scan < 3; ++scan) {
    ASSERT_TRUE((*pub)->publish_tracked_objects({0, scan}, objects));
    ASSERT_EQ(dds_wait_for_acks((*pub)->writer(Topic::kTrackedObjects), DDS_SECS(10)), 0);
  }
  int code = -1;
  const std::string out = run_to_end(child, &code);
  EXPECT_EQ(code, 0) << out;
  EXPECT_NE(out.find("scan 2: 2 objects\n  id 5 at x=1.25 y=2.50 class pedestrian\n  id 6 at "
                     "x=-30.00 y=40.75 class unknown"),
            std::string::npos)
      << out;
}

TEST(StacEcho, TimesOutWithAClearMessageWithoutAPublisher) {
  testing::loopback_uri();
  FILE* child = popen((std::string(::stac::testing::stac_cli()) +
                       " echo health --count 3 --timeout 0.5 --domain 122 2>&1")
                          .c_str(),
                      "r");
  ASSERT_NE(child, nullptr);
  int code = -1;
  const std::string out = run_to_end(child, &code);
  EXPECT_EQ(code, 1) << out;
  EXPECT_NE(out.find("timed out after 0.5 s with 0 of 3 samples on stac/health"), std::string::npos)
      << out;
}

// The cloud carries labels, not names: echo counts the points of every label up to the largest
// (a 5-class model's background is 6, unclassified 7).
TEST(StacEcho, PointCloudCountsThePointsOfEveryLabel) {
  const std::string uri = testing::loopback_uri();
  FILE* child = popen((std::string(::stac::testing::stac_cli()) +
                       " echo point_cloud --count 1 --timeout 20 --domain 124 2>&1")
                          .c_str(),
                      "r");
  ASSERT_NE(child, nullptr);
  PublisherConfig c;
  c.domain_id = 124;
  c.config_uri = uri;
  auto pub = Publisher::create(c);
  ASSERT_TRUE(pub) << pub.error().message;
  ASSERT_TRUE(testing::TestReader::wait_matched((*pub)->writer(Topic::kPointCloud)));
  const std::vector<LabeledPointIn> points = {
      {0, 0, 0, 1, 0}, {1, 0, 0, 1, 5}, {2, 0, 0, 1, 5}, {3, 0, 0, 1, 7}, {4, 0, 0, 1, 1}};
  // Best effort: published until the child has taken one.
  std::atomic<bool> done{false};
  std::thread publisher([&] {
    for (int i = 0; i < 1000 && !done; ++i) {
      (void)(*pub)->publish_point_cloud({{0, static_cast<std::uint64_t>(i)}, {}, 0.01f, points});
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  });
  int code = -1;
  const std::string out = run_to_end(child, &code);
  done = true;
  publisher.join();
  EXPECT_EQ(code, 0) << out;
  EXPECT_NE(out.find("points=5 "), std::string::npos) << out;
  EXPECT_NE(out.find(" none=1 labels=[1,0,0,0,2,0,1]"), std::string::npos) << out;
}

// Issue 31: a file that is not Cyclone XML gave only "Error".
TEST(StacEcho, ADdsConfigThatIsNotCycloneXmlIsNamed) {
  const auto file = std::filesystem::temp_directory_path() / "stac_echo_not_xml.xml";
  std::ofstream(file) << "this is not xml\n";
  FILE* child = popen((std::string(::stac::testing::stac_cli()) +
                       " echo health --timeout 0.5 --dds-config " + file.string() + " 2>&1")
                          .c_str(),
                      "r");
  ASSERT_NE(child, nullptr);
  int code = -1;
  const std::string out = run_to_end(child, &code);
  EXPECT_EQ(code, 1);
  EXPECT_NE(out.find(file.string() + " cannot be used (not Cyclone XML"), std::string::npos) << out;
}

TEST(StacEcho, UnknownTopicListsTheTopics) {
  FILE* child = popen(
      (std::string(::stac::testing::stac_cli()) + " echo tracks --timeout 0.1 2>&1").c_str(), "r");
  ASSERT_NE(child, nullptr);
  int code = -1;
  const std::string out = run_to_end(child, &code);
  EXPECT_EQ(code, 1);
  EXPECT_NE(out.find("unknown topic 'tracks' (topics: tracked_objects, segments, ego_pose, health, "
                     "point_cloud)"),
            std::string::npos)
      << out;
}

}  // namespace
}  // namespace stac::dds
