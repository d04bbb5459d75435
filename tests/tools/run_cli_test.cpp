// `stac run` as a user runs it, over loopback only: `stac sim` -> `stac replay` (UDP to 127.0.0.1
// and the INS as a TCP server on 127.0.0.1) -> `stac run` (Cyclone on config/dds/loopback.xml,
// a domain of its own) -> DDS readers in this test.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "dds/dds_test_support.hpp"
#include "dds/idl_types.hpp"
#include "drivers/can/gs_usb_device.hpp"
#include "formats/model_file.hpp"
#include "shared_data.hpp"
#include "stac_cli.hpp"
#include "test_paths.hpp"
#include "tools/support/child_process.hpp"

namespace stac::tools {
namespace {

using Types = dds::IdlTypes<false>;
constexpr const char* kYaml = "velodyne/calib/rosdrivers_64e_s2.1-sztaki.yaml";

std::filesystem::path fresh_dir(const std::string& name) {
  return stac::testing::fresh_dir("stac_run_" + name);
}

// A port the kernel just gave out on 127.0.0.1 (closed again for the child to bind).
std::uint16_t free_port(int type) {
  const int fd = socket(AF_INET, type, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t len = sizeof(a);
  if (bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof(a)) != 0 ||
      getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len) != 0) {
    close(fd);
    return 0;
  }
  close(fd);
  return ntohs(a.sin_port);
}

// `stac ARGS` in the background (tools::ChildProcess, as `stac demo` runs its children), its
// stdout and stderr into `log`; killed and reaped if the test ends first.
class Child {
 public:
  Child(const std::string& args, const std::filesystem::path& log) {
    std::vector<std::string> words;
    std::istringstream in(args);
    for (std::string w; in >> w;) words.push_back(w);
    auto child = tools::ChildProcess::start_program(::stac::testing::stac_cli(), words, log);
    if (child) child_.emplace(std::move(*child));
  }
  [[nodiscard]] bool started() const { return child_.has_value(); }
  // Sends `sig` and waits (60 s at most, then SIGKILL): the exit code, -1 when killed.
  int stop(int sig) { return child_ ? child_->stop(sig, 60) : -1; }
  bool signal(int sig) { return child_ && child_->signal(sig); }
  // Waits for it to end (10 minutes at most): the exit code, -1 when it did not end.
  int wait() { return child_ ? child_->wait_for(600).value_or(-1) : -1; }
  // Its exit code if it has ended, nullopt while it runs (never blocks).
  std::optional<int> poll() { return child_ ? child_->poll() : std::optional<int>(-1); }
  // Its resident memory now (kB, /proc/PID/status VmRSS; 0 when unknown).
  [[nodiscard]] std::uint64_t rss_kb() const {
    std::ifstream status("/proc/" + std::to_string(child_ ? child_->pid() : 0) + "/status");
    for (std::string line; std::getline(status, line);)
      if (line.rfind("VmRSS:", 0) == 0) return std::stoull(line.substr(6));
    return 0;
  }
  [[nodiscard]] std::string output() const { return child_ ? child_->log() : ""; }

 private:
  std::optional<tools::ChildProcess> child_;
};

// A keep-all reader of one topic in this process.
class Reader {
 public:
  Reader(dds_entity_t participant, const dds_topic_descriptor_t* type, const char* name,
         dds::Topic t) {
    topic_ = dds_create_topic(participant, type, name, nullptr, nullptr);
    dds::QosPtr qos = dds::reader_qos(t);
    dds_qset_history(qos.get(), DDS_HISTORY_KEEP_ALL, 0);
    reader_ = dds_create_reader(participant, topic_, qos.get(), nullptr);
  }
  [[nodiscard]] bool ok() const { return topic_ > 0 && reader_ > 0; }
  [[nodiscard]] bool matched() const {
    dds_subscription_matched_status_t s{};
    return dds_get_subscription_matched_status(reader_, &s) == 0 && s.current_count > 0;
  }
  // Calls f(sample) for every sample available now; returns how many.
  template <class T, class F>
  int drain(F&& f) {
    int n = 0;
    for (;;) {
      void* samples[1] = {nullptr};
      dds_sample_info_t info{};
      const dds_return_t got = dds_take(reader_, samples, &info, 1, 1);
      if (got <= 0) return n;
      if (info.valid_data) {
        f(*static_cast<const T*>(samples[0]));
        ++n;
      }
      dds_return_loan(reader_, samples, got);
    }
  }

 private:
  dds_entity_t topic_ = 0, reader_ = 0;
};

// A DDS domain on the loopback-only configuration (loopback_uri() also sets DDS_TEST_TAG, which
// the children inherit) and a participant in it, deleted at the end of the test.
struct LoopbackDomain {
  explicit LoopbackDomain(std::uint32_t id)
      : domain(dds_create_domain(id, stac::testing::loopback_uri().c_str())),
        participant(dds_create_participant(id, nullptr, nullptr)) {}
  LoopbackDomain(const LoopbackDomain&) = delete;
  LoopbackDomain& operator=(const LoopbackDomain&) = delete;
  ~LoopbackDomain() {
    dds_delete(participant);
    dds_delete(domain);
  }
  [[nodiscard]] bool ok() const { return domain > 0 && participant > 0; }
  dds_entity_t domain, participant;
};

struct HealthSeen {
  std::uint64_t scan_index = 0, deadline_misses = 0;
  std::uint32_t end_to_end_us = 0;
  std::map<std::string, std::uint32_t> stages;
  std::map<std::string, std::uint64_t> drops;
  std::map<std::string, unsigned> sensors;
};

std::uint64_t summary_number(const std::string& out, const std::string& pattern) {
  std::smatch m;
  if (!std::regex_search(out, m, std::regex(pattern))) return ~0ull;
  return std::stoull(m[1].str());
}

TEST(RunCli, ReplayedDriveGivesOneTrackedObjectsSamplePerScanAndHealthThatAgreesWithTheSummary) {
  STAC_REQUIRE_SHARED_DATA(kYaml);
  const auto dir = fresh_dir("e2e");
  const std::string pcap = (dir / "run.pcap").string();
  const auto sim = stac::testing::stac("sim --scenario urban --seed 3 --duration 3 --calib " +
                                       stac::testing::shared_data(kYaml).string() + " --out " +
                                       pcap + " --truth " + (dir / "truth.jsonl").string());
  ASSERT_EQ(sim.code, 0) << sim.output;

  constexpr std::uint32_t kDomain = 141;
  const LoopbackDomain dds_domain(kDomain);  // sets DDS_TEST_TAG for the children too
  ASSERT_TRUE(dds_domain.ok());
  const dds_entity_t participant = dds_domain.participant;
  Reader tracked(participant, Types::tracked_objects(), "stac/tracked_objects",
                 dds::Topic::kTrackedObjects);
  Reader health(participant, Types::health(), "stac/health", dds::Topic::kHealth);
  Reader cloud(participant, Types::point_cloud(), "stac/point_cloud", dds::Topic::kPointCloud);
  ASSERT_TRUE(tracked.ok() && health.ok() && cloud.ok());

  const std::uint16_t udp = free_port(SOCK_DGRAM), tcp = free_port(SOCK_STREAM);
  ASSERT_TRUE(udp != 0 && tcp != 0);
  Child run("run --point-cloud-stride 8 --domain " + std::to_string(kDomain) +
                " --bind 127.0.0.1 --port " + std::to_string(udp) +
                " --ins tcp --ins-address 127.0.0.1 --ins-port " + std::to_string(tcp) +
                " --summary-json " + (dir / "summary.json").string(),
            dir / "run.log");
  ASSERT_TRUE(run.started());
  for (int i = 0; i < 2000 && !(tracked.matched() && health.matched() && cloud.matched()); ++i)
    dds_sleepfor(DDS_MSECS(10));
  ASSERT_TRUE(tracked.matched() && health.matched() && cloud.matched()) << run.output();

  const auto replay =
      stac::testing::stac("replay --in " + pcap + " --to 127.0.0.1 --port " + std::to_string(udp) +
                          " --tcp-port 5602:" + std::to_string(tcp) + " --wait-tcp");
  ASSERT_EQ(replay.code, 0) << replay.output;

  // Everything published arrives; stop once nothing came for 2 s.
  std::vector<std::uint64_t> indices;
  std::vector<HealthSeen> healths;
  struct CloudSeen {
    std::uint64_t scan_index = 0;
    std::uint32_t points = 0, objects = 0, classified = 0, unclassified = 0;
    double origin_z = 0;
    float resolution = 0;
  };
  std::vector<CloudSeen> clouds;
  std::size_t healths_before = 0;
  std::uint64_t confirmed_current = 0, confirmed_late = 0;  // by class_age, confirmed objects
  for (int quiet = 0; quiet < 200;) {
    const int n = tracked.drain<Types::TrackedObjects>([&](const Types::TrackedObjects& s) {
      indices.push_back(s.scan_index);
      for (std::uint32_t i = 0; i < s.objects._length; ++i) {
        const auto& o = s.objects._buffer[i];
        if (o.state != 1 || o.classification._buffer[0].label == 0) continue;  // unclassified
        (o.class_age == 0 ? confirmed_current : confirmed_late) += 1;
      }
    }) + health.drain<Types::Health>([&](const Types::Health& s) {
      HealthSeen h{s.scan_index, s.deadline_misses, s.end_to_end_latency_us, {}, {}, {}};
      for (std::uint32_t i = 0; i < s.stages._length; ++i)
        h.stages[s.stages._buffer[i].stage] = s.stages._buffer[i].latency_us;
      for (std::uint32_t i = 0; i < s.drops._length; ++i)
        h.drops[s.drops._buffer[i].cause] = s.drops._buffer[i].count;
      for (std::uint32_t i = 0; i < s.sensors._length; ++i)
        h.sensors[s.sensors._buffer[i].name] = s.sensors._buffer[i].status;
      healths.push_back(std::move(h));
    }) + cloud.drain<Types::LabeledPointCloud>([&](const Types::LabeledPointCloud& s) {
      CloudSeen c{s.scan_index, s.points._length, 0, 0, 0, s.origin.z, s.resolution};
      for (std::uint32_t i = 0; i < s.points._length; ++i) {
        const std::uint8_t label = s.points._buffer[i].label;
        c.objects += label != 0 ? 1 : 0;
        c.classified += label >= 1 && label <= 4 ? 1 : 0;
        c.unclassified += label == 5 ? 1 : 0;
      }
      clouds.push_back(c);
    });
    // Health without a scan comes every 100 ms while nothing is published: not a scan's.
    bool scan_sample = static_cast<std::size_t>(n) > healths.size() - healths_before;
    for (std::size_t i = healths_before; i < healths.size(); ++i)
      scan_sample |= !healths[i].stages.empty();
    quiet = scan_sample ? 0 : quiet + 1;
    healths_before = healths.size();
    dds_sleepfor(DDS_MSECS(10));
  }
  ASSERT_EQ(run.stop(SIGINT), 0) << run.output();
  const std::string out = run.output();

  // The summary: every scan received was published or counted as dropped, after a signal.
  EXPECT_NE(out.find("(signal)"), std::string::npos) << out;
  const std::uint64_t received = summary_number(out, R"((\d+) received \(complete\))");
  const std::uint64_t published = summary_number(out, R"((\d+) published,)");
  const std::uint64_t misses = summary_number(out, R"((\d+) misses of)");
  const std::uint64_t results_full = summary_number(out, R"(result slots full (\d+))");
  EXPECT_EQ(received, published + results_full) << out;
  {  // --summary-json: the same counts as data (what stac demo reads)
    std::ifstream in(dir / "summary.json");
    const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
    ASSERT_TRUE(j.is_object()) << "no JSON summary";
    EXPECT_TRUE(j["stop_requested"].get<bool>());
    EXPECT_EQ(j["scans"]["received"].get<std::uint64_t>(), received);
    EXPECT_EQ(j["scans"]["published"].get<std::uint64_t>(), published);
    EXPECT_EQ(j["scans"]["result_slots_full"].get<std::uint64_t>(), results_full);
    EXPECT_EQ(j["deadline"]["misses"].get<std::uint64_t>(), misses);
    EXPECT_GT(j["ego"]["ins_fixes"].get<std::uint64_t>(), 0u);
    EXPECT_FALSE(j["latencies"].empty());
  }
  // 3 s at 10 Hz: ~28 scans, unless packets were lost, which must then be counted. On a busy
  // machine a scan may arrive incomplete (a late packet) or find the slots full: counted too.
  const std::uint64_t incomplete = summary_number(out, R"((\d+) incomplete \(not processed\))");
  const std::uint64_t scan_slots_full = summary_number(out, R"(scan slots full (\d+))");
  ASSERT_TRUE(incomplete != ~0ull && scan_slots_full != ~0ull) << out;
  EXPECT_TRUE(received + incomplete + scan_slots_full >= 20u ||
              summary_number(out, R"((\d+) dropped by the kernel)") > 0)
      << out;
  EXPECT_GT(summary_number(out, R"((\d+) INS fixes)"), 0u) << out;
  for (const char* word :
       {"end-to-end", "p50", "p99", "max", "deskew", "segment", "track", "publish"}) {
    EXPECT_NE(out.find(word), std::string::npos) << word << " missing from:\n" << out;
  }

  // DDS: one tracked_objects sample per published scan, in order, none lost; health for each,
  // and, while no scan was published for a second (before the replay), health without stages.
  ASSERT_EQ(indices.size(), published) << out;
  for (std::size_t i = 0; i < indices.size(); ++i) EXPECT_EQ(indices[i], i);
  std::erase_if(healths, [&](const HealthSeen& h) {
    if (!h.stages.empty()) return false;
    EXPECT_EQ(h.end_to_end_us, 0u);
    EXPECT_LT(h.scan_index, std::max<std::uint64_t>(published, 1));
    EXPECT_EQ(h.drops.size(), 30u);
    return true;
  });
  ASSERT_EQ(healths.size(), published);
  const HealthSeen& last = healths.back();
  EXPECT_EQ(last.scan_index, published - 1);
  EXPECT_EQ(last.deadline_misses, misses);
  // Each miss is a scan that came out over the 100 ms budget, and each such scan is a miss: the
  // health samples' counter steps by one exactly where their end-to-end latency passes it. Whether
  // a scan misses depends on how busy the machine is, so the test does not ask for none (CI runs
  // the tests two at a time on two cores); docs/benchmarks.md records the misses of idle runs.
  // (Latencies are whole microseconds, truncated: 100000 us may be either side of the budget.)
  EXPECT_LE(misses, published);
  for (std::size_t i = 0; i < healths.size(); ++i) {
    const std::uint64_t before = i == 0 ? 0 : healths[i - 1].deadline_misses;
    const std::uint64_t step = healths[i].deadline_misses - before;
    const std::uint32_t us = healths[i].end_to_end_us;
    if (us > 100'000u)
      EXPECT_EQ(step, 1u) << "scan " << healths[i].scan_index << ": " << us << " us";
    else if (us < 100'000u)
      EXPECT_EQ(step, 0u) << "scan " << healths[i].scan_index << ": " << us << " us";
    else
      EXPECT_LE(step, 1u);
  }
  EXPECT_GT(last.end_to_end_us, 0u);
  for (const char* stage : {"wait", "deskew", "segment", "track", "handover", "publish"}) {
    EXPECT_TRUE(last.stages.count(stage)) << stage;
  }
  EXPECT_GT(last.stages.at("segment"), 0u);
  // Slots run full only when perception or the publisher falls behind (a sanitizer build): then
  // the drops are counted, in health as in the summary.
  EXPECT_EQ(last.drops.at("results.slots_full"), results_full);
  EXPECT_EQ(last.drops.at("velodyne.scan_slots_full"), scan_slots_full);
  EXPECT_EQ(last.drops.at("dds.errors"), 0u);
  EXPECT_TRUE(last.drops.count("velodyne.kernel") && last.drops.count("tracking.pool_full"));
  EXPECT_EQ(last.drops.at("ego.scans_without_pose"),
            summary_number(out, R"((\d+) scans without a pose)"));
  // Published tracks classified before their scan's publication, and those the budget
  // (run.classify_budget_ms) left for after it, in health as in the summary.
  // (Under a sanitizer, perception runs 5-10 times slower and falls behind the sensor: every
  // scan is older than the budget when its turn comes, and every class is counted late.)
  const std::uint64_t classified_before =
      summary_number(out, R"((\d+) published tracks classified before publication)");
  EXPECT_EQ(last.drops.at("classification.late"),
            summary_number(out, R"((\d+) after it \(run.classify_budget_ms)"));
  EXPECT_GT(classified_before +
                (stac::testing::kSanitizerBuild ? last.drops.at("classification.late") : 0u),
            0u);
  // On DDS, a confirmed track (updated with a segment this scan) has class_age 0 when classified
  // before publication, and more when the budget left it: as many as were counted late (fewer
  // when results were dropped with full slots: their late classes were counted, never sent).
  EXPECT_GT(confirmed_current + (stac::testing::kSanitizerBuild ? confirmed_late : 0), 0u);
  if (results_full == 0) {
    EXPECT_EQ(confirmed_late, last.drops.at("classification.late"));
  } else {
    EXPECT_LE(confirmed_late, last.drops.at("classification.late"));
  }
  EXPECT_LE(last.sensors.at("lidar"), 1u);  // ok, or stale if the last scan waited past the timeout
  EXPECT_EQ(last.sensors.at("can"), 3u);    // not configured
  // CAN's drop causes are there, at 0 without CAN.
  for (const char* cause : {"can.not_mapped", "can.overflow", "can.fd", "can.malformed",
                            "can.other_channel", "can.lost"}) {
    ASSERT_TRUE(last.drops.count(cause)) << cause;
    EXPECT_EQ(last.drops.at(cause), 0u) << cause;
  }
  EXPECT_TRUE(last.sensors.count("ins"));

  // point_cloud (best effort: on loopback nearly every scan's arrives): each holds the scan's
  // object returns, labelled, and a share of the others, from the sensor's position.
  EXPECT_GE(clouds.size(), published / 2) << out;
  std::uint64_t classified = 0;
  for (const CloudSeen& c : clouds) {
    EXPECT_LT(c.scan_index, published);
    EXPECT_GT(c.objects, 0u);
    EXPECT_LT(c.objects, c.points);  // ground and dropped returns too (every 8th)
    EXPECT_EQ(c.objects, c.classified + c.unclassified);
    EXPECT_FLOAT_EQ(c.resolution, 0.01f);
    EXPECT_GT(c.origin_z, 1.0);  // the sensor, about 1.9 m above the road
    classified += c.classified;
  }
  EXPECT_GT(classified, 0u);  // the shipped model classifies tracks: their returns carry classes
}

// Garbage on the sensor's port: every datagram is counted by cause, in health (published each
// second while no scan comes) and in the summary, and it does not make the lidar look alive.
TEST(RunCli, GarbageOnTheSensorPortIsCountedInHealthAndTheLidarStaysStale) {
  constexpr std::uint32_t kDomain = 145;
  const auto dir = fresh_dir("garbage");
  const LoopbackDomain dds_domain(kDomain);
  ASSERT_TRUE(dds_domain.ok());
  const dds_entity_t participant = dds_domain.participant;
  Reader health(participant, Types::health(), "stac/health", dds::Topic::kHealth);
  ASSERT_TRUE(health.ok());
  const std::uint16_t udp = free_port(SOCK_DGRAM);
  ASSERT_NE(udp, 0);
  Child run("run --domain " + std::to_string(kDomain) + " --bind 127.0.0.1 --port " +
                std::to_string(udp) + " --ins none",
            dir / "run.log");
  ASSERT_TRUE(run.started());
  for (int i = 0; i < 2000 && !health.matched(); ++i) dds_sleepfor(DDS_MSECS(10));
  ASSERT_TRUE(health.matched()) << run.output();

  const int fd = socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(udp);
  to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  std::vector<std::uint8_t> junk(1206, 0x5A);  // the size of a data packet, no 0xEEFF block
  constexpr int kEach = 40;
  for (int i = 0; i < kEach; ++i) {
    ASSERT_EQ(sendto(fd, junk.data(), 100, 0, reinterpret_cast<sockaddr*>(&to), sizeof(to)), 100);
    ASSERT_EQ(sendto(fd, junk.data(), junk.size(), 0, reinterpret_cast<sockaddr*>(&to), sizeof(to)),
              1206);
    dds_sleepfor(DDS_MSECS(20));  // the whole second: a lidar that beats on anything looks alive
  }
  close(fd);
  // Every datagram is counted once: by the receiver's cause, or as a kernel drop when the
  // receiver fell behind (a loaded machine, a sanitizer build).
  const auto counted = [](std::map<std::string, std::uint64_t>& drops) {
    return drops["velodyne.wrong_size"] + drops["velodyne.invalid_block"] +
           drops["velodyne.kernel"];
  };
  std::optional<HealthSeen> seen;
  for (int i = 0; i < 400 && !(seen && counted(seen->drops) == 2 * kEach); ++i) {
    (void)health.drain<Types::Health>([&](const Types::Health& s) {
      HealthSeen h{s.scan_index, s.deadline_misses, s.end_to_end_latency_us, {}, {}, {}};
      EXPECT_EQ(s.stages._length, 0u);  // no scan: health without stages
      for (std::uint32_t k = 0; k < s.drops._length; ++k)
        h.drops[s.drops._buffer[k].cause] = s.drops._buffer[k].count;
      for (std::uint32_t k = 0; k < s.sensors._length; ++k)
        h.sensors[s.sensors._buffer[k].name] = s.sensors._buffer[k].status;
      seen = std::move(h);
    });
    dds_sleepfor(DDS_MSECS(10));
  }
  ASSERT_TRUE(seen) << run.output();
  const std::uint64_t wrong_size = seen->drops["velodyne.wrong_size"];
  const std::uint64_t invalid_block = seen->drops["velodyne.invalid_block"];
  EXPECT_EQ(counted(seen->drops), 2u * kEach) << run.output();
  EXPECT_LE(wrong_size, static_cast<std::uint64_t>(kEach));
  EXPECT_LE(invalid_block, static_cast<std::uint64_t>(kEach));
  EXPECT_GT(wrong_size, 0u);
  EXPECT_GT(invalid_block, 0u);
  EXPECT_NE(seen->sensors.at("lidar"), 0u);  // not ok: nothing it sent was a packet
  EXPECT_FALSE(seen->drops.count("")) << "a drop without its cause";
  EXPECT_EQ(run.stop(SIGINT), 0) << run.output();
  const std::string out = run.output();
  EXPECT_NE(out.find("dropped     wrong size " + std::to_string(wrong_size) + ", invalid block " +
                     std::to_string(invalid_block)),
            std::string::npos)
      << out;
}

// `stac run RUN_ARGS` with the lidar on a free UDP port and the INS over UDP on another, fed a
// capture's lidar packets and INS datagrams, each to its port, at the recorded pace (the INS
// half a second ahead, so that a scan's pose has always arrived: a pose is only extrapolated
// 50 ms past the newest, ego.max_extrapolation_s); stopped with SIGTERM. Its output, or why not.
std::string replayed_run(const std::filesystem::path& dir, const std::string& pcap,
                         const std::string& run_args, const std::string& log) {
  (void)stac::testing::loopback_uri();
  const std::uint16_t lidar = free_port(SOCK_DGRAM), ins = free_port(SOCK_DGRAM);
  if (lidar == 0 || ins == 0 || lidar == ins) return "no free ports";
  Child run(run_args + " --bind 127.0.0.1 --port " + std::to_string(lidar) +
                " --ins udp --ins-port " + std::to_string(ins),
            dir / log);
  if (!run.started()) return "stac run did not start";
  for (int i = 0; i < 1000 && run.output().find("Ctrl-C stops") == std::string::npos; ++i)
    dds_sleepfor(DDS_MSECS(10));
  Child ins_replay("replay --in " + pcap + " --to 127.0.0.1 --port " + std::to_string(ins) +
                       " --filter-port 5602",
                   dir / ("ins_" + log));
  dds_sleepfor(DDS_MSECS(500));
  const auto replay = stac::testing::stac("replay --in " + pcap + " --to 127.0.0.1 --port " +
                                          std::to_string(lidar) + " --filter-port 2368");
  const int ins_code = ins_replay.wait();
  const int run_code = run.stop(SIGTERM);
  if (replay.code != 0) return "replay failed: " + replay.output;
  if (ins_code != 0) return "INS replay failed: " + ins_replay.output();
  if (run_code != 0) return "stac run exited " + std::to_string(run_code) + ": " + run.output();
  return run.output();
}

TEST(RunCli, InsOverUdpDeskewsTheScansAndSigtermStopsAfterPublishingWhatWasReceived) {
  STAC_REQUIRE_SHARED_DATA(kYaml);
  const auto dir = fresh_dir("ins_udp");
  const std::string pcap = (dir / "run.pcap").string();
  const auto sim =
      stac::testing::stac("sim --scenario parking-lot --seed 6 --duration 2 --ins-udp --calib " +
                          stac::testing::shared_data(kYaml).string() + " --out " + pcap +
                          " --truth " + (dir / "truth.jsonl").string());
  ASSERT_EQ(sim.code, 0) << sim.output;
  const std::string out = replayed_run(dir, pcap, "run --domain 144", "run.log");
  EXPECT_NE(out.find("(signal)"), std::string::npos) << out;
  const std::uint64_t received = summary_number(out, R"((\d+) received \(complete\))");
  EXPECT_EQ(received, summary_number(out, R"((\d+) published,)") +
                          summary_number(out, R"(result slots full (\d+))"))
      << out;
  // 2 s at 10 Hz: ~18 complete scans, unless packets were lost, which must then be counted.
  EXPECT_TRUE(received >= 12u || summary_number(out, R"((\d+) dropped by the kernel)") > 0) << out;
  EXPECT_GT(summary_number(out, R"((\d+) INS fixes)"), 300u) << out;  // 200 Hz for about 2 s
  EXPECT_LE(summary_number(out, R"((\d+) scans without a pose)"), 2u)
      << out;  // before the first fixes only
  EXPECT_EQ(summary_number(out, R"((\d+) receive errors)"), 0u) << out;
}

// Issue 33: an HDL-32E, a VLP-16 and a VLP-32C live, as the 64E above (UDP replay at the
// recorded pace, INS over UDP, DDS on loopback): every scan complete and published with --sensor
// (the VLP-16 with VeloView's real calibration, the others with velodyne.model_calibrations');
// with the configuration's HDL-64E instead, every packet is counted as another model's.
TEST(RunCli, TheVelodyneFamilyIsDecodedLiveAndAnotherModelsPacketsAreCounted) {
  constexpr const char* kVlp16 = "velodyne/calib/veloview_VLP-16.xml";
  STAC_REQUIRE_SHARED_DATA(kVlp16);
  STAC_REQUIRE_SHARED_DATA(kYaml);
  struct Model {
    const char* name;
    std::string calib;
    std::uint64_t packets_per_s;  // 2 s of them, at least 90% named another model's
  };
  const Model models[] = {
      {"VLP-16", " --calib " + stac::testing::shared_data(kVlp16).string(), 753},
      {"HDL-32E", "", 1808},
      {"VLP-32C", "", 1507}};
  for (const Model& m : models) {
    const auto dir = fresh_dir(std::string("family_") + m.name);
    const std::string pcap = (dir / "run.pcap").string();
    const auto sim = stac::testing::stac(std::string("sim --model ") + m.name +
                                         " --scenario parking-lot --seed 6 --duration 2 "
                                         "--ins-udp --out " +
                                         pcap + " --truth " + (dir / "truth.jsonl").string());
    ASSERT_EQ(sim.code, 0) << sim.output;
    for (const bool named : {true, false}) {
      const std::string out = replayed_run(
          dir, pcap,
          "run --domain 149" + (named ? std::string(" --sensor ") + m.name + m.calib : ""),
          named ? "run.log" : "run_64e.log");
      const std::uint64_t received = summary_number(out, R"((\d+) received \(complete\))");
      const std::uint64_t kernel = summary_number(out, R"((\d+) dropped by the kernel)");
      if (named) {
        // 2 s at 10 Hz: ~18 complete scans, unless packets were lost, which must be counted.
        EXPECT_TRUE(received >= 12u || kernel > 0) << m.name << "\n" << out;
        EXPECT_EQ(received, summary_number(out, R"((\d+) published,)") +
                                summary_number(out, R"(result slots full (\d+))"))
            << out;
        EXPECT_EQ(summary_number(out, R"(invalid block (\d+))"), 0u) << out;
        EXPECT_EQ(out.find("name another model"), std::string::npos) << out;
      } else {
        EXPECT_GT(summary_number(out, R"((\d+) packets name another model than velodyne.model)"),
                  2 * m.packets_per_s * 9 / 10)
            << m.name << "\n"
            << out;
      }
    }
  }
}

TEST(ProcessDds, EveryScanOfTheTracksFileIsPublishedInOrderWithItsTracks) {
  STAC_REQUIRE_SHARED_DATA(kYaml);
  const auto dir = fresh_dir("process_dds");
  const std::string pcap = (dir / "run.pcap").string(), tracks = (dir / "tracks.jsonl").string();
  const auto sim =
      stac::testing::stac("sim --scenario parking-lot --seed 4 --duration 1.5 --calib " +
                          stac::testing::shared_data(kYaml).string() + " --out " + pcap +
                          " --truth " + (dir / "truth.jsonl").string());
  ASSERT_EQ(sim.code, 0) << sim.output;
  constexpr std::uint32_t kDomain = 143;
  const LoopbackDomain dds_domain(kDomain);
  ASSERT_TRUE(dds_domain.ok());
  const dds_entity_t participant = dds_domain.participant;
  Reader tracked(participant, Types::tracked_objects(), "stac/tracked_objects",
                 dds::Topic::kTrackedObjects);
  ASSERT_TRUE(tracked.ok());
  Child process("process " + pcap + " --tracks " + tracks + " --dds --domain " +
                    std::to_string(kDomain) + " --dds-wait 20",
                dir / "process.log");
  ASSERT_TRUE(process.started());
  ASSERT_EQ(process.wait(), 0) << process.output();
  std::vector<std::pair<std::uint64_t, std::uint32_t>> seen;  // scan index, objects
  for (int quiet = 0; quiet < 100;) {
    const int n = tracked.drain<Types::TrackedObjects>([&](const Types::TrackedObjects& s) {
      seen.emplace_back(s.scan_index, s.objects._length);
    });
    quiet = n > 0 ? 0 : quiet + 1;
    dds_sleepfor(DDS_MSECS(10));
  }
  std::ifstream in(tracks);
  std::vector<std::size_t> tracks_per_line;
  std::size_t all_tracks = 0, tentative_tracks = 0;
  for (std::string line; std::getline(in, line);) {
    // dds.tentative_tracks is false: confirmed and coasting tracks are published.
    std::size_t n = 0, tentative = 0;
    for (std::size_t at = line.find("\"state\""); at != std::string::npos;
         at = line.find("\"state\"", at + 1))
      ++n;
    for (std::size_t at = line.find("\"state\":\"tentative\""); at != std::string::npos;
         at = line.find("\"state\":\"tentative\"", at + 1))
      ++tentative;
    tracks_per_line.push_back(n - tentative);
    all_tracks += n;
    tentative_tracks += tentative;
  }
  ASSERT_GE(tracks_per_line.size(), 12u);
  ASSERT_EQ(seen.size(), tracks_per_line.size()) << process.output();
  for (std::size_t i = 0; i < seen.size(); ++i) {
    EXPECT_EQ(seen[i].first, i);
    EXPECT_EQ(seen[i].second, tracks_per_line[i]) << "scan " << i;
  }
  EXPECT_NE(process.output().find("scans published on tracked_objects"), std::string::npos);
  EXPECT_GT(tentative_tracks, 0u);  // there were some to leave out
  EXPECT_GT(all_tracks, tentative_tracks);
}

// Issue 29: a model retrained by `stac induct` goes into a running `stac run` without a restart.
// Without a sensor the perception loop still turns and health comes every 100 ms, with the hash
// of the model in use.
TEST(RunCli, SighupSwapsInTheModelFileAndHealthSaysWhichModelIsInUse) {
  const auto dir = fresh_dir("reload");
  const auto file = dir / "model.stacmodel";
  auto a = formats::read_model_file(std::filesystem::path(::stac::testing::source_dir()) /
                                    "config/models/stac_default.stacmodel");
  ASSERT_TRUE(a.has_value()) << a.error().message;
  classification::TrackClassifierModel b = *a;
  b.adbf.alpha[0] += 0.25f;  // another model of the same classes
  ASSERT_TRUE(formats::write_model_file(file, *a));
  const std::uint64_t hash_a = classification::model_hash(*a),
                      hash_b = classification::model_hash(b);
  ASSERT_NE(hash_a, hash_b);

  constexpr std::uint32_t kDomain = 149;
  const LoopbackDomain dds_domain(kDomain);
  ASSERT_TRUE(dds_domain.ok());
  const dds_entity_t participant = dds_domain.participant;
  Reader health(participant, Types::health(), "stac/health", dds::Topic::kHealth);
  ASSERT_TRUE(health.ok());
  Child run("run --model " + file.string() + " --domain " + std::to_string(kDomain) +
                " --bind 127.0.0.1 --port 0 --ins none",
            dir / "run.log");
  ASSERT_TRUE(run.started());
  struct Seen {
    std::uint64_t hash = 0;
    std::uint32_t reloads = 0;
    std::uint64_t refused = ~0ull;
  };
  // Waits (20 s at most) for a health sample that `done` accepts; the last one seen.
  const auto wait_for = [&](const auto& done) {
    Seen last;
    for (int i = 0; i < 2000; ++i) {
      bool ok = false;
      health.drain<Types::Health>([&](const Types::Health& s) {
        last = {s.model_hash, s.model_reloads, ~0ull};
        for (std::uint32_t d = 0; d < s.drops._length; ++d)
          if (std::string(s.drops._buffer[d].cause) == "model.reload_refused")
            last.refused = s.drops._buffer[d].count;
        ok = ok || done(last);
      });
      if (ok) return last;
      dds_sleepfor(DDS_MSECS(10));
    }
    return last;
  };
  Seen s = wait_for([](const Seen&) { return true; });
  EXPECT_EQ(s.hash, hash_a) << run.output();
  EXPECT_EQ(s.reloads, 0u);
  EXPECT_EQ(s.refused, 0u);

  ASSERT_TRUE(formats::write_model_file(file, b));
  ASSERT_TRUE(run.signal(SIGHUP));
  s = wait_for([&](const Seen& x) { return x.hash == hash_b; });
  EXPECT_EQ(s.hash, hash_b) << run.output();
  EXPECT_EQ(s.reloads, 1u);

  // A damaged file is refused, counted, and the model kept.
  std::ofstream(file, std::ios::trunc) << "not a model";
  ASSERT_TRUE(run.signal(SIGHUP));
  s = wait_for([](const Seen& x) { return x.refused == 1; });
  EXPECT_EQ(s.refused, 1u) << run.output();
  EXPECT_EQ(s.hash, hash_b);
  EXPECT_EQ(s.reloads, 1u);

  ASSERT_EQ(run.stop(SIGINT), 0) << run.output();
  const std::string out = run.output();
  EXPECT_NE(out.find("SIGHUP: the model is kept"), std::string::npos) << out;
  EXPECT_NE(out.find("1 swapped in (SIGHUP), 1 refused"), std::string::npos) << out;
}

TEST(RunCli, WithoutSensorItStopsByItselfAndReportsTheLidarStalled) {
  const auto dir = fresh_dir("idle");
  (void)stac::testing::loopback_uri();
  Child run("run --seconds 1 --domain 142 --bind 127.0.0.1 --port 0 --ins none", dir / "run.log");
  ASSERT_TRUE(run.started());
  ASSERT_EQ(run.wait(), 0) << run.output();
  const std::string out = run.output();
  EXPECT_EQ(out.find("(signal)"), std::string::npos) << out;
  EXPECT_NE(out.find("0 received (complete), 0 published"), std::string::npos) << out;
  EXPECT_NE(out.find("lidar stalled"), std::string::npos) << out;
  EXPECT_NE(out.find("ins not configured"), std::string::npos) << out;
}

// The shipped config with the CAN bus read (run.can: true) through `transport` on `interface`,
// and any `more` edits.
std::filesystem::path can_config(const std::filesystem::path& dir, const std::string& transport,
                                 const std::string& interface,
                                 std::vector<std::pair<std::string, std::string>> more = {}) {
  more.insert(more.begin(), {{"can", "true"}, {"transport", transport}, {"interface", interface}});
  std::string error;
  const auto file = stac::testing::shipped_config_with(dir, more, &error);
  EXPECT_FALSE(file.empty()) << error;
  return file;
}

std::string run_briefly(const std::filesystem::path& config, int domain) {
  (void)stac::testing::loopback_uri();
  return "run --config " + config.string() + " --model none --ins none --bind 127.0.0.1 --port 0 " +
         "--seconds 1 --domain " + std::to_string(domain);
}

// No adapter on this machine: start-up stops with the driver's message, exit code 1, before any
// thread starts, as it does for a missing SocketCAN interface (below).
TEST(RunCli, GsUsbWithoutAnAdapterStopsStartUpNamingTheAdapterLsusbAndUdev) {
  STAC_REQUIRE_SHARED_DATA(kYaml);
  const auto probe = can::GsUsbDevice::open({});
  if (probe)
    GTEST_SKIP() << "SKIPPED: a gs_usb adapter is attached; this test checks start-up without one";
  const auto dir = fresh_dir("gs_usb_absent");
  const auto r = stac::testing::stac(run_briefly(can_config(dir, "gs_usb", "can0"), 147));
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("stac: " + probe.error().message + "\n"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("gs_usb (1d50:606f): no gs_usb/candleLight adapter found"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("lsusb -d 1d50:606f"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("udev rule granting access (deploy/60-stac-gs-usb.rules"),
            std::string::npos)
      << r.output;
  EXPECT_EQ(r.output.find("reads socketcan only"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("Ctrl-C stops"), std::string::npos) << r.output;  // nothing started
}

TEST(RunCli, SocketCanWithoutItsInterfaceStopsStartUpNamingIt) {
  STAC_REQUIRE_SHARED_DATA(kYaml);
  const auto dir = fresh_dir("socketcan_absent");
  const auto r = stac::testing::stac(run_briefly(can_config(dir, "socketcan", "stacnocan0"), 148));
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("stac: SocketCAN: no network interface 'stacnocan0'"), std::string::npos)
      << r.output;
  EXPECT_EQ(r.output.find("Ctrl-C stops"), std::string::npos) << r.output;
}

TEST(RunCli, BadOptionsAreNamed) {
  const auto r =
      stac::testing::stac("run --ins carrier-pigeon --seconds 1 --port 0 --bind 127.0.0.1");
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.output.find("--ins"), std::string::npos) << r.output;
}

// Issue 31, faults in the loop: one `stac run`, and a simulated drive replayed into it once per
// fault, the fault from capture second 2 to 3 (`stac replay --faults`). For each: the run never
// stops; the cause shows on health in the first scan after the fault begins; its count stops
// growing and complete scans with tracks are published again within a scan of its end; no object
// is published from garbage (every position finite, within the sensor's range). Reordering by one
// datagram and a jump of the sensor's own clock are absorbed: nothing to count, output normal.
// Times are when samples arrive here, from when the replay's first datagram was due (both on
// CLOCK_REALTIME): "within a scan" allows one more scan (100 ms) for publishing and delivery on a
// loaded test machine.
// A 5 s simulated urban drive, DIR/drive.pcap (the faults and 3x-rate tests).
stac::testing::CliResult simulate_drive(const std::filesystem::path& dir, int seed) {
  return stac::testing::stac("sim --scenario urban --seed " + std::to_string(seed) +
                             " --duration 5 --out " + (dir / "drive.pcap").string() + " --truth " +
                             (dir / "drive.jsonl").string());
}

// `stac run` on loopback UDP port `udp` without an INS, publishing on `domain`.
Child live_run(std::uint32_t domain, std::uint16_t udp, const std::filesystem::path& dir) {
  return Child("run --domain " + std::to_string(domain) + " --bind 127.0.0.1 --port " +
                   std::to_string(udp) + " --ins none",
               dir / "run.log");
}

// Seconds on CLOCK_REALTIME (when a sample arrives here).
double wall_s() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

// Calls `drain` until `replay` has ended and `linger_s` more passed, and expects the replay to
// exit 0. Returns when the capture's first datagram was due (CLOCK_REALTIME s), NaN with a
// failure when the replay's log does not say.
double follow_replay(Child& replay, const std::function<void()>& drain, double linger_s) {
  std::optional<double> ended;
  while (!ended || wall_s() < *ended + linger_s) {
    drain();
    if (!ended && replay.poll()) ended = wall_s();
    dds_sleepfor(DDS_MSECS(2));
  }
  EXPECT_EQ(replay.wait(), 0) << replay.output();
  std::smatch m;
  const std::string log = replay.output();
  if (!std::regex_search(log, m, std::regex("first datagram is due at ([0-9.]+) s"))) {
    ADD_FAILURE() << log;
    return std::nan("");
  }
  return std::stod(m[1].str());
}

struct FaultCase {
  std::string faults;
  std::vector<std::string> causes;  // health drops whose sum counts it (empty: none)
  bool dropout = false;             // the lidar goes stale instead
};

TEST(FaultsInTheLoop, EachFaultIsCountedByCauseWithinAScanAndOutputIsNormalAScanAfterItEnds) {
  constexpr std::uint32_t kDomain = 147;
  const auto dir = fresh_dir("faults");
  const std::string drive = (dir / "drive.pcap").string();
  const stac::testing::CliResult sim = simulate_drive(dir, 21);
  ASSERT_EQ(sim.code, 0) << sim.output;
  const LoopbackDomain dds_domain(kDomain);
  ASSERT_TRUE(dds_domain.ok());
  const dds_entity_t participant = dds_domain.participant;
  Reader tracked(participant, Types::tracked_objects(), "stac/tracked_objects",
                 dds::Topic::kTrackedObjects);
  Reader health(participant, Types::health(), "stac/health", dds::Topic::kHealth);
  ASSERT_TRUE(tracked.ok() && health.ok());
  const std::uint16_t udp = free_port(SOCK_DGRAM);
  ASSERT_NE(udp, 0);
  Child run = live_run(kDomain, udp, dir);
  ASSERT_TRUE(run.started());
  for (int i = 0; i < 2000 && !(health.matched() && tracked.matched()); ++i)
    dds_sleepfor(DDS_MSECS(10));
  ASSERT_TRUE(health.matched() && tracked.matched()) << run.output();

  const std::vector<FaultCase> cases = {
      {"garbage=0.05", {"velodyne.wrong_size", "velodyne.invalid_block"}},
      {"duplicate=0.05", {"velodyne.duplicates"}},
      {"truncate=0.05", {"velodyne.wrong_size"}},
      {"oversize=0.05", {"velodyne.wrong_size"}},
      {"loss=0.05", {"velodyne.packets_lost"}},
      // Bursts lose a fifth of a scan: it is not processed, counted as incomplete.
      {"burst=0.01:20", {"velodyne.packets_lost", "velodyne.incomplete_scan"}},
      {"reorder=0.05", {}},
      {"clock-jump=2:-5", {}},
      {"dropout=2+1", {}, true},
  };
  constexpr double kStart = 2.0, kEnd = 3.0, kScan = 0.1 + 0.1;  // a scan, and delivery
  constexpr double kStale = 0.2;  // run.velodyne_timeout: a lidar silent this long is stale
  // Health reports a count with the scan it publishes: under a sanitizer that scan may be up to
  // kSanitizerLagS behind the sensor (CI's ASan run saw the burst's count 0.2 s in not there yet).
  constexpr double kLag = stac::testing::kSanitizerLagS;
  for (std::size_t k = 0; k < cases.size(); ++k) {
    const FaultCase& c = cases[k];
    SCOPED_TRACE(c.faults);
    const std::string window = c.causes.empty() || c.dropout ? "" : ",window=2+1";
    Child replay("replay --in " + drive + " --port " + std::to_string(udp) + " --no-tcp --faults " +
                     c.faults + window + ",seed=" + std::to_string(k + 1),
                 dir / ("replay" + std::to_string(k) + ".log"));
    ASSERT_TRUE(replay.started());
    struct Sample {
      double t;  // arrival - when the capture's first datagram was due (s)
      std::uint64_t count;
      bool lidar_ok;
    };
    std::vector<Sample> samples;
    std::vector<double> scans;  // tracked_objects arrivals (s, realtime)
    std::vector<Sample> raw;    // t: arrival (s, realtime)
    bool objects_sane = true;
    std::string insane;
    const auto drain = [&] {
      (void)health.drain<Types::Health>([&](const Types::Health& s) {
        std::uint64_t n = 0;
        bool lidar_ok = false;
        for (std::uint32_t i = 0; i < s.drops._length; ++i)
          for (const std::string& cause : c.causes)
            n += cause == s.drops._buffer[i].cause ? s.drops._buffer[i].count : 0;
        for (std::uint32_t i = 0; i < s.sensors._length; ++i)
          if (std::string(s.sensors._buffer[i].name) == "lidar")
            lidar_ok = s.sensors._buffer[i].status == 0;
        raw.push_back({wall_s(), n, lidar_ok});
      });
      (void)tracked.drain<Types::TrackedObjects>([&](const Types::TrackedObjects& s) {
        scans.push_back(wall_s());
        for (std::uint32_t i = 0; i < s.objects._length; ++i) {
          const auto& p = s.objects._buffer[i].kinematics.position;
          if (!(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z) &&
                std::hypot(p.x, p.y) < 130.0)) {
            objects_sane = false;
            insane = std::to_string(p.x) + " " + std::to_string(p.y);
          }
        }
      });
    };
    drain();  // what came before this replay
    raw.clear();
    scans.clear();
    // While it runs, and half a second more: the last scans, and the lidar stale after them.
    const double t0 = follow_replay(replay, drain, 0.5);
    ASSERT_FALSE(std::isnan(t0));
    const std::string replay_log = replay.output();
    for (const Sample& r : raw) samples.push_back({r.t - t0, r.count, r.lidar_ok});
    for (double& s : scans) s -= t0;
    ASSERT_GT(samples.size(), 30u) << run.output();
    EXPECT_TRUE(objects_sane) << insane;

    // Scans with tracks after the fault's end, up to the drive's end (5 s), as before it.
    std::size_t before = 0, after = 0;
    for (const double s : scans) {
      before += s < kStart ? 1 : 0;
      after += s >= kEnd + kScan && s < 5.0 ? 1 : 0;
    }
    // (fewer under a sanitizer, whose perception runs behind and drops scans, counted)
    EXPECT_GE(before, stac::testing::kSanitizerBuild ? 10u : 15u);
    EXPECT_GE(after, stac::testing::kSanitizerBuild ? 10u : 15u)
        << "complete scans published again within a scan of the fault's end";

    if (c.dropout) {
      // Stale within a scan of the watchdog's timeout; fresh again within a scan of the end.
      for (const Sample& s : samples) {
        if (s.t >= kStart + kStale + kScan && s.t < kEnd) {
          EXPECT_FALSE(s.lidar_ok) << "at " << s.t << " s";
        }
        if (s.t >= kEnd + kScan && s.t < 5.0) {
          EXPECT_TRUE(s.lidar_ok) << "at " << s.t << " s";
        }
        if (s.t >= kScan && s.t < kStart) {
          EXPECT_TRUE(s.lidar_ok) << "at " << s.t << " s";
        }
      }
      continue;
    }
    // The earlier faults' counts, and the drive's start: its first partial scan is incomplete.
    constexpr double kSettled = 0.5;
    std::uint64_t base_count = samples.back().count;
    for (const Sample& s : samples)
      if (s.t >= kSettled) {
        base_count = s.count;
        break;
      }
    std::uint64_t at_end = ~0ull;
    bool seen_within_a_scan = c.causes.empty();
    for (const Sample& s : samples) {
      if (s.t >= kSettled && s.t < kStart) {
        EXPECT_EQ(s.count, base_count) << "before the fault, at " << s.t << " s";
      }
      if (!c.causes.empty() && s.t >= kStart + kScan + kLag && s.t < kEnd + kLag &&
          !seen_within_a_scan) {
        EXPECT_GT(s.count, base_count) << "not on health in the first scan after the fault began";
        seen_within_a_scan = true;
      }
      if (s.t >= kEnd + kScan + kLag) {
        if (at_end == ~0ull) at_end = s.count;
        EXPECT_EQ(s.count, at_end) << "still growing at " << s.t << " s";
      }
      // Stale before the drive (the last one ended) and after it, never during it.
      EXPECT_TRUE(s.lidar_ok || s.t < kScan || s.t > 5.0) << "lidar not ok at " << s.t << " s";
    }
    EXPECT_TRUE(seen_within_a_scan);
    if (c.causes.empty()) {
      EXPECT_EQ(at_end, base_count);
    }
    EXPECT_NE(replay_log.find("faults: "), std::string::npos) << replay_log;
  }
  EXPECT_EQ(run.stop(SIGINT), 0) << run.output();
}

struct InsFaultCase {
  std::string faults;
  double start, end;                // capture seconds
  std::vector<std::string> causes;  // health drops whose sum counts it (empty: none)
  bool outage = true;               // no valid fix from start to end: the INS goes stale
};

// Issue 31: faults in the INS's TCP stream (replayed, into `stac run --ins tcp`): each counted by
// cause on health within a scan, the INS stale through an outage and ok again after it, no track
// born while no pose places the scans in the world (before issue 31 such scans were tracked in
// the vehicle's frame), and complete scans with tracks published throughout.
TEST(FaultsInTheLoop, InsFaultsAreCountedTheInsIsStaleNoTrackIsMisplacedAndItRecovers) {
  constexpr std::uint32_t kDomain = 150;
  const auto dir = fresh_dir("ins_faults");
  const std::string drive = (dir / "drive.pcap").string();
  const stac::testing::CliResult sim = simulate_drive(dir, 23);
  ASSERT_EQ(sim.code, 0) << sim.output;
  const LoopbackDomain dds_domain(kDomain);
  ASSERT_TRUE(dds_domain.ok());
  Reader tracked(dds_domain.participant, Types::tracked_objects(), "stac/tracked_objects",
                 dds::Topic::kTrackedObjects);
  Reader health(dds_domain.participant, Types::health(), "stac/health", dds::Topic::kHealth);
  ASSERT_TRUE(tracked.ok() && health.ok());
  const std::uint16_t udp = free_port(SOCK_DGRAM), ins = free_port(SOCK_STREAM);
  ASSERT_TRUE(udp != 0 && ins != 0);
  Child run("run --domain " + std::to_string(kDomain) + " --bind 127.0.0.1 --port " +
                std::to_string(udp) + " --ins tcp --ins-address 127.0.0.1 --ins-port " +
                std::to_string(ins),
            dir / "run.log");
  ASSERT_TRUE(run.started());
  for (int i = 0; i < 2000 && !(health.matched() && tracked.matched()); ++i)
    dds_sleepfor(DDS_MSECS(10));
  ASSERT_TRUE(health.matched() && tracked.matched()) << run.output();

  const std::vector<InsFaultCase> cases = {
      {"ins-checksum=2+1", 2, 3, {"ins.bad_checksum"}},
      {"ins-garbage=2+1", 2, 3, {"ins.garbage_bytes", "ins.bad_framing", "ins.malformed"}},
      {"ins-dropout=2+1", 2, 3, {}},
      {"ins-disconnect=2", 2, 2, {"ins.disconnects"}, false},
  };
  // a scan, and delivery (later under a sanitizer, whose perception runs behind the sensor)
  constexpr double kScan = 0.1 + 0.1 + stac::testing::kSanitizerLagS;
  constexpr double kStale = 0.1;      // ego.ins_timeout_s
  constexpr double kReconnect = 0.1;  // the INS client's first backoff
  for (std::size_t k = 0; k < cases.size(); ++k) {
    const InsFaultCase& c = cases[k];
    SCOPED_TRACE(c.faults);
    // --wait-tcp: the drive starts once stac run's INS client is connected.
    Child replay("replay --in " + drive + " --port " + std::to_string(udp) +
                     " --tcp-port 5602:" + std::to_string(ins) + " --wait-tcp --faults " +
                     c.faults + ",seed=" + std::to_string(k + 1),
                 dir / ("replay" + std::to_string(k) + ".log"));
    ASSERT_TRUE(replay.started());
    struct Sample {
      double t;
      std::uint64_t count;
      bool ins_ok;
    };
    std::vector<Sample> samples;
    std::vector<std::pair<double, std::vector<std::uint64_t>>> scans;  // arrival, object ids
    const auto drain = [&] {
      (void)health.drain<Types::Health>([&](const Types::Health& s) {
        std::uint64_t n = 0;
        bool ok = false;
        for (std::uint32_t i = 0; i < s.drops._length; ++i)
          for (const std::string& cause : c.causes)
            n += cause == s.drops._buffer[i].cause ? s.drops._buffer[i].count : 0;
        for (std::uint32_t i = 0; i < s.sensors._length; ++i)
          if (std::string(s.sensors._buffer[i].name) == "ins")
            ok = s.sensors._buffer[i].status == 0;
        samples.push_back({wall_s(), n, ok});
      });
      (void)tracked.drain<Types::TrackedObjects>([&](const Types::TrackedObjects& s) {
        std::vector<std::uint64_t> ids;
        for (std::uint32_t i = 0; i < s.objects._length; ++i)
          ids.push_back(s.objects._buffer[i].object_id);
        scans.emplace_back(wall_s(), std::move(ids));
      });
    };
    drain();
    samples.clear();
    scans.clear();
    const double t0 = follow_replay(replay, drain, 0.3);
    ASSERT_FALSE(std::isnan(t0));
    const std::string log = replay.output();
    EXPECT_NE(log.find("ins faults: "), std::string::npos) << log;
    EXPECT_EQ(log.find("ins faults: none happened"), std::string::npos) << log;
    for (Sample& s : samples) s.t -= t0;
    for (auto& s : scans) s.first -= t0;
    ASSERT_GT(samples.size(), 30u) << run.output();

    // Before the fault: the INS ok, nothing counted.
    std::uint64_t base = ~0ull, at_end = ~0ull;
    bool seen = c.causes.empty();
    for (const Sample& s : samples) {
      if (s.t >= 0.5 && s.t < c.start) {
        EXPECT_TRUE(s.ins_ok) << "before the fault, at " << s.t << " s";
        if (base == ~0ull) base = s.count;
        EXPECT_EQ(s.count, base) << "before the fault, at " << s.t << " s";
      }
      if (!seen && s.t >= c.start + kScan && s.t < std::max(c.end, c.start + 2 * kScan)) {
        EXPECT_GT(s.count, base) << "not on health in the first scan after the fault began";
        seen = true;
      }
      if (c.outage && s.t >= c.start + kStale + kScan && s.t < c.end) {
        EXPECT_FALSE(s.ins_ok) << "at " << s.t << " s, in the outage";
      }
      if (s.t >= c.end + kReconnect + kScan && s.t < 5.0) {
        EXPECT_TRUE(s.ins_ok) << "at " << s.t << " s, after the fault";
        if (at_end == ~0ull) at_end = s.count;
        EXPECT_EQ(s.count, at_end) << "still growing at " << s.t << " s";
      }
    }
    EXPECT_TRUE(seen);

    // No track born while no pose placed the scans; scans with tracks before and after.
    std::set<std::uint64_t> known;
    std::size_t before = 0, after = 0;
    for (const auto& [t, ids] : scans) {
      if (t < c.start + kStale) {
        known.insert(ids.begin(), ids.end());
        before += t < c.start && !ids.empty() ? 1 : 0;
      } else if (c.outage && t >= c.start + kStale + kScan && t < c.end) {
        for (const std::uint64_t id : ids)
          EXPECT_TRUE(known.count(id) != 0) << "track " << id << " born at " << t << " s";
      }
      after += t >= c.end + kReconnect + kScan && t < 5.0 && !ids.empty() ? 1 : 0;
    }
    // (Under a sanitizer, on a loaded 2-core machine, perception falls behind and drops scans:
    // 4 of the 1.5 s after the INS returned had tracks in one CI run, so 3 is asked there; and 9
    // of the 2 s before the fault in another (2026-12-07), so 6 before.)
    EXPECT_GE(before, stac::testing::kSanitizerBuild ? 6u : 15u);
    EXPECT_GE(after, stac::testing::kSanitizerBuild ? 3u : 10u);
  }
  EXPECT_EQ(run.stop(SIGINT), 0) << run.output();
}

// Issue 31, a CAN bus silence: the simulated drive's CAN frames (`stac sim --can`) replayed as
// cannelloni datagrams (CAN over UDP) beside its lidar and INS into `stac run` with
// can.transport: cannelloni. `can-silence=2+1`: the CAN input is ok before, stale on health within
// can.stale_timeout_s and a scan of the silence's start, ok again within a scan of its end;
// nothing is counted lost or malformed (a silent bus is not a loss), and every scan keeps its
// pose (the INS is untouched). `ins-dropout=2+1` with CAN: the second of INS outage is bridged
// by dead reckoning from the CAN odometry, so at most the scan at the hand-over goes without a
// pose (without CAN all ten would). Both need CAN stamped in the INS's time: the drive is of
// 2026-01-01 and the frames are stamped on arrival, today.
TEST(FaultsInTheLoop, ACanSilenceIsStaleOnHealthAndCanDeadReckoningBridgesAnInsDropout) {
  STAC_REQUIRE_SHARED_DATA(kYaml);
  constexpr std::uint32_t kDomain = 178;
  const auto dir = fresh_dir("can_faults");
  const std::string drive = (dir / "drive.pcap").string(), log = (dir / "drive.log").string();
  const auto sim =
      stac::testing::stac("sim --scenario urban --seed 29 --duration 5 --out " + drive +
                          " --truth " + (dir / "drive.jsonl").string() + " --can " + log);
  ASSERT_EQ(sim.code, 0) << sim.output;
  const LoopbackDomain dds_domain(kDomain);
  ASSERT_TRUE(dds_domain.ok());
  Reader health(dds_domain.participant, Types::health(), "stac/health", dds::Topic::kHealth);
  ASSERT_TRUE(health.ok());
  const std::uint16_t udp = free_port(SOCK_DGRAM), ins = free_port(SOCK_STREAM),
                      can_port = free_port(SOCK_DGRAM);
  ASSERT_TRUE(udp != 0 && ins != 0 && can_port != 0 && can_port != udp);
  const auto config =
      can_config(dir, "cannelloni", "can0", {{"cannelloni_port", std::to_string(can_port)}});
  const std::string model = (std::filesystem::path(::stac::testing::source_dir()) /
                             "config/models/stac_default.stacmodel")
                                .string();
  Child run("run --config " + config.string() + " --model " + model + " --domain " +
                std::to_string(kDomain) + " --bind 127.0.0.1 --port " + std::to_string(udp) +
                " --ins tcp --ins-address 127.0.0.1 --ins-port " + std::to_string(ins),
            dir / "run.log");
  ASSERT_TRUE(run.started());
  for (int i = 0; i < 2000 && !health.matched(); ++i) dds_sleepfor(DDS_MSECS(10));
  ASSERT_TRUE(health.matched()) << run.output();

  constexpr double kScan = 0.1 + 0.1;  // a scan, and delivery
  constexpr double kStale = 0.2;       // can.stale_timeout_s
  for (const std::string faults : {"can-silence=2+1", "ins-dropout=2+1"}) {
    SCOPED_TRACE(faults);
    const bool silence = faults.rfind("can-", 0) == 0;
    Child replay("replay --in " + drive + " --port " + std::to_string(udp) +
                     " --tcp-port 5602:" + std::to_string(ins) + " --wait-tcp --can " + log +
                     " --can-port " + std::to_string(can_port) + " --faults " + faults,
                 dir / ("replay_" + faults.substr(0, 3) + ".log"));
    ASSERT_TRUE(replay.started());
    struct Sample {
      double t;
      bool can_ok;
      std::uint64_t lost, without_pose;
    };
    std::vector<Sample> samples;
    const auto drain = [&] {
      (void)health.drain<Types::Health>([&](const Types::Health& s) {
        Sample x{wall_s(), false, 0, 0};
        for (std::uint32_t i = 0; i < s.drops._length; ++i) {
          const std::string cause = s.drops._buffer[i].cause;
          if (cause == "can.lost" || cause == "can.malformed") x.lost += s.drops._buffer[i].count;
          if (cause == "ego.scans_without_pose") x.without_pose = s.drops._buffer[i].count;
        }
        for (std::uint32_t i = 0; i < s.sensors._length; ++i)
          if (std::string(s.sensors._buffer[i].name) == "can")
            x.can_ok = s.sensors._buffer[i].status == 0;
        samples.push_back(x);
      });
    };
    drain();
    samples.clear();
    const double t0 = follow_replay(replay, drain, 0.3);
    ASSERT_FALSE(std::isnan(t0));
    const std::string replay_log = replay.output();
    std::smatch m;
    ASSERT_TRUE(std::regex_search(replay_log, m,
                                  std::regex("CAN to [0-9.:]+: ([0-9]+) frames sent .*, ([0-9]+) "
                                             "silenced")))
        << replay_log;
    EXPECT_GT(std::stoull(m[1].str()), 300u);
    EXPECT_EQ(std::stoull(m[2].str()) > 0, silence) << replay_log;
    ASSERT_GT(samples.size(), 30u) << run.output();
    std::uint64_t lost = ~0ull, without_pose = ~0ull;
    std::size_t stale = 0;
    for (Sample& s : samples) {
      s.t -= t0;
      if (s.t < 0.5 || s.t >= 4.8) continue;
      if (lost == ~0ull) lost = s.lost;
      EXPECT_EQ(s.lost, lost) << "at " << s.t << " s";
      if (without_pose == ~0ull) without_pose = s.without_pose;
      if (silence) {
        EXPECT_EQ(s.without_pose, without_pose) << "a scan without pose at " << s.t << " s";
        if (s.t < 2.0 || s.t >= 3.0 + kScan) {
          EXPECT_TRUE(s.can_ok) << "at " << s.t << " s, outside the silence";
        } else if (s.t >= 2.0 + kStale + kScan && s.t < 3.0) {
          EXPECT_FALSE(s.can_ok) << "at " << s.t << " s, in the silence";
          ++stale;
        }
      } else {
        EXPECT_TRUE(s.can_ok) << "at " << s.t << " s";
        EXPECT_LE(s.without_pose, without_pose + 2) << "at " << s.t << " s, in the INS dropout";
      }
    }
    if (silence) {
      EXPECT_GE(stale, 3u);
    }
  }
  EXPECT_EQ(run.stop(SIGINT), 0) << run.output();
  const std::string out = run.output();
  EXPECT_NE(out.find("CAN cannelloni on udp://0.0.0.0:" + std::to_string(can_port)),
            std::string::npos)
      << out;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(out, m, std::regex("([0-9]+) dead-reckoned poses"))) << out;
  EXPECT_GT(std::stoull(m[1].str()), 50u) << "the INS dropout was bridged by CAN";
  EXPECT_NE(out.find("lost on the network 0"), std::string::npos) << out;
}

// Issue 31: the sensor's stream at 3x its rate (a 5 s drive replayed three times at --rate 3).
// Whatever the machine keeps up with, every datagram is accounted for (received or dropped by
// the kernel, counted), every complete scan not published is counted as a drop, latency stays
// bounded (queues are fixed: no sample older than a second) and memory does not grow over the
// second and third passes (all of it allocated at start-up, resident once the first pass touched
// it).
TEST(RunCli, ThreeTimesTheSensorsRateKeepsLatencyAndMemoryBoundedAndCountsWhatItDrops) {
  constexpr std::uint32_t kDomain = 148;
  const auto dir = fresh_dir("rate3");
  const std::string drive = (dir / "drive.pcap").string();
  const stac::testing::CliResult sim = simulate_drive(dir, 22);
  ASSERT_EQ(sim.code, 0) << sim.output;
  const LoopbackDomain dds_domain(kDomain);
  ASSERT_TRUE(dds_domain.ok());
  Reader health(dds_domain.participant, Types::health(), "stac/health", dds::Topic::kHealth);
  ASSERT_TRUE(health.ok());
  const std::uint16_t udp = free_port(SOCK_DGRAM);
  ASSERT_NE(udp, 0);
  Child run = live_run(kDomain, udp, dir);
  ASSERT_TRUE(run.started());
  for (int i = 0; i < 2000 && !health.matched(); ++i) dds_sleepfor(DDS_MSECS(10));
  ASSERT_TRUE(health.matched()) << run.output();

  Child replay(
      "replay --in " + drive + " --port " + std::to_string(udp) + " --no-tcp --rate 3 --loop 3",
      dir / "replay.log");
  ASSERT_TRUE(replay.started());
  std::uint32_t worst_us = 0;
  std::size_t scans = 0;
  std::uint64_t rss_before = 0;  // once the first pass is through: every buffer touched once
  while (!replay.poll()) {
    (void)health.drain<Types::Health>([&](const Types::Health& s) {
      if (s.stages._length == 0) return;  // health without a scan
      ++scans;
      worst_us = std::max(worst_us, s.end_to_end_latency_us);
    });
    if (rss_before == 0 && scans >= 45) rss_before = run.rss_kb();
    dds_sleepfor(DDS_MSECS(5));
  }
  // (Under a sanitizer fewer than 45 scans may get through all three passes; its memory is not
  // checked, below.)
  if constexpr (!stac::testing::kSanitizerBuild) {
    ASSERT_GT(rss_before, 0u) << scans << " scans";
  }
  ASSERT_EQ(replay.wait(), 0) << replay.output();
  dds_sleepfor(DDS_MSECS(500));
  const std::uint64_t rss_after = run.rss_kb();
  ASSERT_EQ(run.stop(SIGINT), 0) << run.output();
  const std::string out = run.output();
  const std::uint64_t sent = summary_number(replay.output(), "sent +([0-9]+) packets");
  const std::uint64_t received = summary_number(out, "packets +([0-9]+) received");
  const std::uint64_t kernel = summary_number(out, "received, ([0-9]+) dropped by the kernel");
  // A datagram from elsewhere on the free port (a Cyclone peer still writing to a participant
  // that had it) is received and refused as wrong size.
  const std::uint64_t foreign = summary_number(out, "dropped +wrong size ([0-9]+),");
  ASSERT_NE(foreign, ~0ull) << out;
  EXPECT_EQ(received - foreign + kernel, sent) << out;
  const std::uint64_t complete = summary_number(out, "scans +([0-9]+) received \\(complete\\)");
  const std::uint64_t published = summary_number(out, "complete\\), ([0-9]+) published");
  const std::uint64_t scan_slots = summary_number(out, "scan slots full ([0-9]+)");
  const std::uint64_t result_slots = summary_number(out, "result slots full ([0-9]+)");
  ASSERT_NE(complete, ~0ull) << out;
  // 3 passes of 5 s at 10 scans/s (under a sanitizer the receiver falls behind 3x the rate and
  // the kernel drops packets, counted above: fewer scans are complete)
  EXPECT_GT(complete, stac::testing::kSanitizerBuild ? 0u : 100u) << out;
  EXPECT_GT(published, 0u) << out;
  EXPECT_LE(published, complete);
  EXPECT_LE(complete - published, scan_slots + result_slots) << out;
  EXPECT_GT(scans, 0u);
  EXPECT_LT(worst_us, 1'000'000u) << "a scan published over a second after its last packet";
  // (AddressSanitizer keeps freed memory in quarantine, up to 256 MB, before reusing it: resident
  // memory grows under it whatever the program does; the plain build checks this.)
  if constexpr (!stac::testing::kSanitizerBuild) {
    EXPECT_LT(rss_after, rss_before + 8 * 1024)
        << "memory grew under 3x the rate: " << rss_before << " kB -> " << rss_after << " kB";
  }
}

}  // namespace
}  // namespace stac::tools
