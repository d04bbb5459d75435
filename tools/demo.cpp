// stac demo: the main job on a built-in default, no sensor needed. A simulated urban drive
// (`stac sim`) is written to a pcap with its truth, replayed over loopback (`stac replay`: the
// HDL-64E's UDP packets and the Applanix TCP stream at the recorded pace) into the live component
// (`stac run`, Cyclone on config/dds/loopback.xml), both run as child processes exactly as a user
// would run them; this process subscribes to the DDS topics, prints a line per scan as the tracks
// arrive, and at the end a summary and pictures (pictures/demo_pictures.hpp).
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <type_traits>
#include <vector>

#include "dds/idl_types.hpp"
#include "dds/reading.hpp"
#include "formats/recorded_drive.hpp"
#include "pictures/demo_pictures.hpp"
#include "rt/unique_fd.hpp"
#include "settings/dds_settings.hpp"
#include "settings/settings.hpp"
#include "tools/commands.hpp"
#include "tools/sim.hpp"
#include "tools/support/child_process.hpp"
#include "view/view_bridge.hpp"

namespace stac::tools {

using namespace stac::settings;
using namespace stac::formats;
namespace {

struct DemoOptions {
  std::string out = "stac-demo";
  std::string config;
  double seconds = 12.0;
  std::uint64_t seed = 2026;
  int port = 0, ins_port = 0;  // 0: any free port on 127.0.0.1
  int domain = -1;             // < 0: dds.domain_id
  bool view = false;           // --view: a Foxglove WebSocket server beside the demo
  std::string view_address = "127.0.0.1";
  int view_port = 8765;
  double view_wait_s = 60;  // --view: wait this long for a viewer before the drive (0: no wait)
};

constexpr double kMatchTimeoutS = 30;  // stac run up and its writers matched
constexpr double kQuietS = 2;         // after the replay: nothing more for this long ends the drive
constexpr double kStopTimeoutS = 20;  // stac run's shutdown after SIGINT

volatile std::sig_atomic_t g_interrupted = 0;
extern "C" void on_interrupt(int) {
  g_interrupted = 1;
}

// A port on 127.0.0.1 for a child to bind: `wanted` once checked free, or (0) one the kernel gives
// out. The socket is closed again before the child binds (a short race, reported by the child).
rt::Result<std::uint16_t> loopback_port(int type, int wanted, const char* option) {
  const char* kind = type == SOCK_DGRAM ? "UDP" : "TCP";
  const rt::UniqueFd fd(::socket(AF_INET, type | SOCK_CLOEXEC, 0));
  if (!fd) return rt::make_error(std::string(kind) + " socket: " + std::strerror(errno));
  const int on = 1;
  if (type == SOCK_STREAM) (void)::setsockopt(fd.get(), SOL_SOCKET, SO_REUSEADDR, &on, sizeof(on));
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  a.sin_port = htons(static_cast<std::uint16_t>(wanted));
  socklen_t len = sizeof(a);
  if (::bind(fd.get(), reinterpret_cast<sockaddr*>(&a), sizeof(a)) != 0) {
    const int e = errno;
    return rt::make_error(std::string(kind) + " port " + std::to_string(wanted) +
                          " on 127.0.0.1 is not free (" + std::strerror(e) +
                          "): another program uses it; pass " + option +
                          " with another port, or 0 for any free one");
  }
  (void)::getsockname(fd.get(), reinterpret_cast<sockaddr*>(&a), &len);
  return ntohs(a.sin_port);
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const auto k = static_cast<std::size_t>(std::ceil(q * static_cast<double>(v.size()))) - 1;
  return v[std::min(k, v.size() - 1)];
}

// What arrives on DDS during the drive, and the line per scan.
template <class T>
class DriveWatch {
 public:
  void on_tracked(const typename T::TrackedObjects& s, dds_time_t now,
                  const dds_sample_info_t& info) {
    const double t = dds::seconds(s.stamp);
    if (scans.empty()) first_stamp_s_ = t;
    latency_ms.push_back(static_cast<double>(now - info.source_timestamp) * 1e-6);
    scans.push_back(s.scan_index);
    last_ = pictures::ScanView{};
    last_.scan_index = s.scan_index;
    std::uint32_t confirmed = 0;
    std::vector<const typename T::TrackedObject*> shown;
    for (std::uint32_t i = 0; i < s.objects._length; ++i) {
      const auto& o = s.objects._buffer[i];
      const auto& p = o.kinematics.position;
      const auto& v = o.kinematics.velocity;
      const dds::ShownClass c = dds::shown_class(o);
      last_.tracks.push_back({o.object_id, static_cast<float>(p.x), static_cast<float>(p.y),
                              static_cast<float>(o.shape.dimensions.x),
                              static_cast<float>(o.shape.dimensions.y), o.shape.yaw,
                              static_cast<float>(std::hypot(v.x, v.y)), o.state, c.name});
      if (o.state == 0) continue;  // tentative
      ++confirmed;
      paths_[o.object_id].push_back({static_cast<float>(p.x), static_cast<float>(p.y)});
      classes_[o.object_id] = c.name;
      shown.push_back(&o);
    }
    for (std::uint32_t i = 0; i < s.objects._length; ++i)
      ids.insert(s.objects._buffer[i].object_id);
    confirmed_per_scan.push_back(confirmed);
    tracks_per_scan.push_back(s.objects._length);
    // The three confirmed tracks nearest the vehicle (its last pose), nearest first.
    const auto distance = [&](const typename T::TrackedObject* o) {
      return std::hypot(o->kinematics.position.x - ego_x_, o->kinematics.position.y - ego_y_);
    };
    std::sort(shown.begin(), shown.end(),
              [&](auto* a, auto* b) { return distance(a) < distance(b); });
    char text[512];
    int at = std::snprintf(text, sizeof(text), "scan %4llu  +%5.1f s  tracks %3u (%3u confirmed)",
                           static_cast<unsigned long long>(s.scan_index), t - first_stamp_s_,
                           s.objects._length, confirmed);
    for (std::size_t i = 0;
         i < shown.size() && i < 3 && at > 0 && at < static_cast<int>(sizeof(text)); ++i) {
      const auto& o = *shown[i];
      at += std::snprintf(text + at, sizeof(text) - static_cast<std::size_t>(at),
                          "  | #%llu %s (%.1f, %.1f) %.1f m/s",
                          static_cast<unsigned long long>(o.object_id), dds::shown_class(o).name,
                          o.kinematics.position.x, o.kinematics.position.y,
                          std::hypot(o.kinematics.velocity.x, o.kinematics.velocity.y));
    }
    pending_.emplace_back(text);
  }

  // Prints the lines of the scans that arrived since the last call (not on the receive thread).
  void print_lines() {
    for (const std::string& line : pending_) std::printf("%s\n", line.c_str());
    if (!pending_.empty()) std::fflush(stdout);
    pending_.clear();
  }

  void on_health(const typename T::Health& s, dds_time_t, const dds_sample_info_t&) {
    if (s.stages._length > 0)
      end_to_end_ms.push_back(static_cast<double>(s.end_to_end_latency_us) * 1e-3);
    deadline_misses = s.deadline_misses;
    drops.clear();
    for (std::uint32_t i = 0; i < s.drops._length; ++i)
      drops.emplace_back(s.drops._buffer[i].cause, s.drops._buffer[i].count);
  }

  void on_pose(const typename T::EgoPose& s, dds_time_t, const dds_sample_info_t&) {
    ego_x_ = s.position.x;
    ego_y_ = s.position.y;
    const double* q = s.orientation;  // x, y, z, w
    ego_yaw_ =
        std::atan2(2.0 * (q[3] * q[2] + q[0] * q[1]), 1.0 - 2.0 * (q[1] * q[1] + q[2] * q[2]));
    ego_path_.push_back({static_cast<float>(ego_x_), static_cast<float>(ego_y_)});
  }

  void on_segments(const typename T::ScanSegments& s, dds_time_t, const dds_sample_info_t&) {
    segments_.clear();
    for (std::uint32_t i = 0; i < s.segments._length; ++i) {
      const auto& g = s.segments._buffer[i];
      segments_.push_back({static_cast<float>(g.centroid.x), static_cast<float>(g.centroid.y),
                           static_cast<float>(g.dimensions.x), static_cast<float>(g.dimensions.y),
                           g.yaw});
    }
  }

  // The last scan's view: its tracks, the segments and the vehicle's pose that came last.
  [[nodiscard]] pictures::DriveView view() const {
    pictures::DriveView v;
    v.last = last_;
    v.segments = segments_;
    v.ego_x = static_cast<float>(ego_x_);
    v.ego_y = static_cast<float>(ego_y_);
    v.ego_yaw = static_cast<float>(ego_yaw_);
    v.ego_path = ego_path_;
    v.paths = paths_;
    v.classes = classes_;
    return v;
  }

  std::vector<std::uint64_t> scans;
  std::vector<std::uint32_t> tracks_per_scan, confirmed_per_scan;
  std::vector<double> latency_ms, end_to_end_ms;
  std::uint64_t deadline_misses = 0;
  std::vector<std::pair<std::string, std::uint64_t>> drops;
  std::set<std::uint64_t> ids;

 private:
  double first_stamp_s_ = 0, ego_x_ = 0, ego_y_ = 0, ego_yaw_ = 0;
  pictures::ScanView last_;
  std::vector<pictures::BoxView> segments_;
  std::vector<pictures::PointM> ego_path_;
  std::map<std::uint64_t, std::vector<pictures::PointM>> paths_;
  std::map<std::uint64_t, std::string> classes_;  // each confirmed track's latest class
  std::vector<std::string> pending_;
};

// The points of complete scan `index` of the capture (the scan stac run published as that index
// when no packet was lost), in the vehicle frame (the sensor's extrinsics; not deskewed).
rt::Result<std::vector<pictures::Point3M>> last_scan_points(const std::string& config,
                                                            const std::string& pcap,
                                                            std::uint64_t index) {
  auto settings = load_pipeline_settings(config);
  if (!settings) return rt::Unexpected<rt::Error>{settings.error()};
  const Eigen::Isometry3f vehicle_T_sensor = settings->ego.deskew.vehicle_T_sensor.cast<float>();
  auto drive = formats::RecordedDrive::open(pcap, *settings, {"", "", false});
  if (!drive) return rt::Unexpected<rt::Error>{drive.error()};
  std::vector<pictures::Point3M> points;
  auto read = drive->for_each_scan([&](velodyne::Scan& scan, std::int64_t) {
    if (drive->scans() - 1 < index) return true;
    points.reserve(scan.points.size());
    for (const velodyne::Point& p : scan.points) {
      const Eigen::Vector3f v = vehicle_T_sensor * Eigen::Vector3f(p.x, p.y, p.z);
      points.push_back({v.x(), v.y(), v.z()});
    }
    return false;
  });
  if (!read) return rt::Unexpected<rt::Error>{read.error()};
  if (drive->scans() == 0) return rt::make_error(drive->nothing_decoded());
  if (points.empty())
    return rt::make_error(pcap + " holds no complete scan " + std::to_string(index));
  return points;
}

// The drive seen live: stac run and stac replay as children, this process reading DDS.
struct DemoPorts {
  std::uint16_t udp = 0, tcp = 0;  // Velodyne UDP, INS TCP (127.0.0.1)
};

template <class T>
int watch_drive(const DemoOptions& o, const std::filesystem::path& dir, const std::string& config,
                const std::string& loopback_xml, const dds::PublisherConfig& dds_config,
                const std::string& pcap, DemoPorts ports) {
  // Every sample is taken on Cyclone's receive thread as it arrives (the latency measured is the
  // one of a consumer doing so) and recorded under `mutex`; this thread prints and waits.
  DriveWatch<T> w;
  std::mutex mutex;
  std::uint64_t arrived = 0;  // samples of any topic, under `mutex`
  const auto record = [&](auto member) {
    return [&, member](const auto& s, dds_time_t t, const dds_sample_info_t& i) {
      const std::lock_guard<std::mutex> lock(mutex);
      (w.*member)(s, t, i);
      // Health without stages comes each second while no scan is published: not a scan's.
      if constexpr (std::is_same_v<std::decay_t<decltype(s)>, typename T::Health>) {
        if (s.stages._length == 0) return;
      }
      ++arrived;
    };
  };
  auto readers =
      dds::TopicReaders::create(dds_config);  // after what its callbacks use: deleted first
  if (!readers) return fail(readers.error().message);
  dds::TopicReaders& r = **readers;
  auto tracked = r.listen<typename T::TrackedObjects>(dds::Topic::kTrackedObjects, 64,
                                                      record(&DriveWatch<T>::on_tracked));
  auto health =
      r.listen<typename T::Health>(dds::Topic::kHealth, 64, record(&DriveWatch<T>::on_health));
  auto pose =
      r.listen<typename T::EgoPose>(dds::Topic::kEgoPose, 64, record(&DriveWatch<T>::on_pose));
  auto segments = r.listen<typename T::ScanSegments>(dds::Topic::kSegments, 4,
                                                     record(&DriveWatch<T>::on_segments));
  for (const auto* e : {&tracked, &health, &pose, &segments})
    if (!*e) return fail(e->error().message);

  const std::string domain = std::to_string(dds_config.domain_id);
  auto run = ChildProcess::start(
      {"run", "--config", config, "--dds-config", loopback_xml, "--domain", domain, "--bind",
       "127.0.0.1", "--port", std::to_string(ports.udp), "--ins", "tcp", "--ins-address",
       "127.0.0.1", "--ins-port", std::to_string(ports.tcp), "--summary-json",
       (dir / "run_summary.json").string()},
      dir / "run.log");
  if (!run) return fail(run.error().message);
  std::fprintf(stderr,
               "stac demo: 2/4 stac run on 127.0.0.1 (Velodyne UDP %u, INS TCP %u, DDS domain %u, "
               "loopback only; log %s)\n",
               ports.udp, ports.tcp, dds_config.domain_id, run->log_path().c_str());
  const auto run_failed = [&](const std::string& what) {
    return fail(what + "; stac run said:\n" + run->log_tail(8));
  };
  for (const dds_time_t end = dds_time() + DDS_SECS(static_cast<long>(kMatchTimeoutS));
       !(dds::TopicReaders::matched(*tracked) > 0 && dds::TopicReaders::matched(*health) > 0);) {
    if (run->poll()) return run_failed("stac run ended at start-up");
    if (g_interrupted) return fail("interrupted");
    if (dds_time() > end) return run_failed("stac run's DDS writers did not match within 30 s");
    dds_sleepfor(DDS_MSECS(20));
  }

  auto replay = ChildProcess::start(
      {"replay", "--in", pcap, "--to", "127.0.0.1", "--port", std::to_string(ports.udp),
       "--tcp-port", "5602:" + std::to_string(ports.tcp), "--wait-tcp"},
      dir / "replay.log");
  if (!replay) return fail(replay.error().message);
  std::fprintf(
      stderr,
      "stac demo: 3/4 replaying the drive at its recorded pace; tracks as they arrive on DDS "
      "(another terminal: DDS_TEST_TAG=%s stac echo tracked_objects --domain %u)\n",
      std::getenv("DDS_TEST_TAG"), dds_config.domain_id);

  // Until the replay has ended and nothing more arrived for kQuietS (or a child fails, or Ctrl-C).
  const dds_time_t deadline = dds_time() + DDS_SECS(static_cast<long>(3 * o.seconds + 60));
  dds_time_t last_sample = dds_time();
  std::uint64_t seen = 0;
  std::optional<int> replay_code;
  const auto print_lines = [&] {
    const std::lock_guard<std::mutex> lock(mutex);
    w.print_lines();
    return arrived;
  };
  for (;;) {
    const std::uint64_t n = print_lines();
    const dds_time_t now = dds_time();
    if (n != seen) seen = n, last_sample = now;
    if (!replay_code) replay_code = replay->poll();
    if (replay_code && *replay_code != 0)
      return fail("stac replay failed:\n" + replay->log_tail(8));
    if (replay_code && now - last_sample > DDS_SECS(static_cast<long>(kQuietS))) break;
    if (run->poll()) return run_failed("stac run ended during the drive");
    if (g_interrupted) break;
    if (now > deadline) return run_failed("the drive did not end in time (replay or DDS stuck)");
    dds_sleepfor(DDS_MSECS(20));
  }
  const int run_code = run->stop(SIGINT, kStopTimeoutS);
  (void)replay->stop(SIGINT, kStopTimeoutS);
  dds_sleepfor(DDS_MSECS(200));  // what stac run wrote just before it stopped
  readers->reset();              // no callback runs after this
  w.print_lines();
  const std::string run_log = run->log();
  if (run_code != 0)
    return run_failed("stac run did not stop cleanly (exit " + std::to_string(run_code) + ")");

  // 4. The summary (as data: --summary-json) and the pictures.
  nlohmann::json summary;
  {
    std::ifstream in(dir / "run_summary.json");
    summary = nlohmann::json::parse(in, nullptr, false);
  }
  if (summary.is_discarded() || !summary.is_object())
    return run_failed("stac run wrote no summary to " + (dir / "run_summary.json").string());
  const auto summary_count = [&](const char* group, const char* key) {
    const nlohmann::json& g = summary.value(group, nlohmann::json::object());
    return g.value(key, std::uint64_t{0});
  };
  const std::uint64_t published = summary_count("scans", "published");
  std::set<std::uint64_t> arrived_indices;  // of 0..published-1
  for (std::uint64_t i : w.scans)
    if (i < published) arrived_indices.insert(i);
  const std::uint64_t missing = published - arrived_indices.size();
  std::fprintf(stderr, "stac demo: 4/4 the drive is over; stac run's own summary:\n%s",
               run_log.substr(std::min(run_log.size(), run_log.find("stac run: stopped"))).c_str());
  const auto u = [](std::uint64_t v) { return static_cast<unsigned long long>(v); };
  std::vector<double> per_scan(w.tracks_per_scan.begin(), w.tracks_per_scan.end());
  std::vector<double> confirmed(w.confirmed_per_scan.begin(), w.confirmed_per_scan.end());
  std::string drops;
  for (const auto& [cause, count] : w.drops)
    if (count > 0 && cause != "classification.late")
      drops += " " + cause + "=" + std::to_string(count);
  // Published tracks classified before their scan's publication, and those left for after it.
  const std::uint64_t current = summary_count("classes", "current");
  const std::uint64_t late = summary_count("classes", "late");
  std::printf(
      "\nSTAC demo: %.0f s simulated urban drive (seed %llu) -> loopback UDP + INS -> stac run -> "
      "DDS\n"
      "  scans       %zu received on tracked_objects of %llu published by stac run (%llu missing)\n"
      "  tracks      %zu ids; per scan median %.0f (%.0f confirmed), max %.0f\n"
      "  deadline    %llu misses (run.deadline_ms)\n"
      "  drops      %s\n"
      "  classes     %llu published tracks classified before publication, %llu one scan late "
      "(run.classify_budget_ms)\n"
      "  end to end  last firing -> published: median %.1f ms, p99 %.1f ms (%zu scans, health)\n"
      "  DDS         publish -> receive (tracked_objects): median %.2f ms, p99 %.2f ms, max %.2f "
      "ms\n",
      o.seconds, u(o.seed), w.scans.size(), u(published), u(missing), w.ids.size(),
      percentile(per_scan, 0.5), percentile(confirmed, 0.5), percentile(per_scan, 1.0),
      u(w.deadline_misses), drops.empty() ? " none" : drops.c_str(), u(current), u(late),
      percentile(w.end_to_end_ms, 0.5), percentile(w.end_to_end_ms, 0.99), w.end_to_end_ms.size(),
      percentile(w.latency_ms, 0.5), percentile(w.latency_ms, 0.99), percentile(w.latency_ms, 1.0));
  pictures::DriveView view = w.view();
  if (auto p = last_scan_points(config, pcap, view.last.scan_index); p) {
    view.points = std::move(*p);
  } else {
    std::fprintf(stderr, "stac demo: warning: no points in the picture: %s\n",
                 p.error().message.c_str());
  }
  for (auto [name, picture] : {std::pair{"demo_last_scan.png", pictures::DrivePicture::kLastScan},
                               {"demo_tracks.png", pictures::DrivePicture::kWholeDrive}}) {
    if (auto d = pictures::draw_drive(view, picture, dir / name); !d)
      return fail(d.error().message);
    std::printf("  picture     %s\n", (dir / name).c_str());
  }
  std::fflush(stdout);
  if (g_interrupted) return fail("interrupted");
  if (w.scans.empty()) return fail("no scan arrived on DDS");
  if (missing > 0) return fail(std::to_string(missing) + " published scans did not arrive on DDS");
  return 0;
}

int run_demo(const DemoOptions& o) {
  const std::filesystem::path config = std::filesystem::absolute(config_path(o.config));
  auto dds_config = load_dds_settings(config);
  if (!dds_config) return fail(dds_config.error().message);
  std::error_code ec;
  std::filesystem::create_directories(o.out, ec);
  if (ec) return fail(o.out + ": cannot create the output folder: " + ec.message());
  const std::filesystem::path dir = std::filesystem::absolute(o.out);

  // Loopback only, whatever the config's dds.config_file, and a discovery tag of this demo's own
  // (unless one is set) so that demos and tests running at the same time never see each other.
  // The loopback XML beside the config (config/dds/ or /etc/stac/dds/), else the default config's.
  std::filesystem::path loopback_xml = config.parent_path() / "dds" / "loopback.xml";
  if (!std::filesystem::exists(loopback_xml, ec))
    loopback_xml = default_config_path().parent_path() / "dds" / "loopback.xml";
  if (!std::filesystem::exists(loopback_xml, ec))
    return fail(loopback_xml.string() +
                ": the demo's loopback-only Cyclone DDS configuration is missing");
  dds_config->config_uri = "file://" + loopback_xml.string();
  if (o.domain >= 0) dds_config->domain_id = static_cast<std::uint32_t>(o.domain);
  if (std::getenv("DDS_TEST_TAG") == nullptr || *std::getenv("DDS_TEST_TAG") == '\0')
    ::setenv("DDS_TEST_TAG", ("stac-demo-" + std::to_string(::getpid())).c_str(), 1);

  struct sigaction sa {};
  sa.sa_handler = on_interrupt;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);

  // The ports first: a busy one stops the demo before the drive is simulated.
  auto udp = loopback_port(SOCK_DGRAM, o.port, "--port");
  if (!udp) return fail(udp.error().message);
  auto tcp = loopback_port(SOCK_STREAM, o.ins_port, "--ins-port");
  if (!tcp) return fail(tcp.error().message);

  // With --view, the Foxglove server on the demo's DDS domain first: a viewer can connect while
  // the drive is simulated, and is waited for before the drive is replayed.
  std::unique_ptr<view::ViewBridge> viewer;
  if (o.view) {
    view::ServerOptions server;
    server.address = o.view_address;
    server.port = static_cast<std::uint16_t>(o.view_port);
    auto bridge = view::ViewBridge::start(*dds_config, server);
    if (!bridge) return fail("--view: " + bridge.error().message);
    viewer = std::move(*bridge);
    std::fprintf(
        stderr,
        "stac demo: view: in Foxglove or Lichtblick: Open connection -> Foxglove WebSocket "
        "-> %s\n",
        viewer->url().c_str());
  }

  // 1. The drive: pcap (HDL-64E UDP + the Applanix TCP stream) and its truth.
  std::fprintf(stderr, "stac demo: 1/4 simulating a %.0f s urban drive (seed %llu)\n", o.seconds,
               static_cast<unsigned long long>(o.seed));
  sim::DriveOptions sim;
  sim.scenario = "urban";
  sim.seed = o.seed;
  sim.duration_s = o.seconds;
  sim.out = (dir / "drive.pcap").string();
  sim.truth = (dir / "drive.truth.jsonl").string();
  sim.config = config.string();
  if (const int code = run_sim(sim); code != 0) return code;

  if (viewer && o.view_wait_s > 0) {
    std::fprintf(stderr, "stac demo: view: waiting up to %.0f s for a viewer (--view-wait)\n",
                 o.view_wait_s);
    const dds_time_t end = dds_time() + static_cast<dds_duration_t>(o.view_wait_s * 1e9);
    while (!viewer->any_subscribed() && dds_time() < end && g_interrupted == 0)
      dds_sleepfor(DDS_MSECS(50));
    std::fprintf(stderr, "stac demo: view: %s\n",
                 viewer->any_subscribed() ? "a viewer is subscribed" : "no viewer: going on");
  }

  const int code = dds_config->ros2_names
                       ? watch_drive<dds::IdlTypes<true>>(o, dir, config.string(), loopback_xml,
                                                          *dds_config, sim.out, {*udp, *tcp})
                       : watch_drive<dds::IdlTypes<false>>(o, dir, config.string(), loopback_xml,
                                                           *dds_config, sim.out, {*udp, *tcp});
  if (viewer) std::printf("  view        %s", viewer->summary().c_str());
  return code;
}

}  // namespace

void add_demo_command(CLI::App& app) {
  auto o = std::make_shared<DemoOptions>();
  CLI::App* cmd = app.add_subcommand("demo",
                                     "The full pipeline on a built-in simulated drive, live over "
                                     "loopback to DDS (no sensor needed)");
  cmd->description(
      "The full pipeline on a built-in default, no sensor needed: simulates an urban drive\n"
      "(OUT/drive.pcap + OUT/drive.truth.jsonl), replays it over loopback (HDL-64E UDP and the\n"
      "Applanix TCP stream, at the recorded pace) into `stac run` (Cyclone DDS on loopback only),\n"
      "prints a line per scan as the tracks arrive on DDS, then a summary (scans, tracks, "
      "deadline\n"
      "misses, drops, end-to-end and DDS latency) and draws OUT/demo_last_scan.png and\n"
      "OUT/demo_tracks.png. Logs of the children: OUT/run.log, OUT/replay.log.");
  cmd->add_option("--out", o->out, "output folder")->capture_default_str();
  cmd->add_flag("--view", o->view,
                "serve the drive live to Foxglove or Lichtblick (as `stac view`), and wait for a "
                "viewer before the drive starts");
  cmd->add_option("--view-port", o->view_port, "--view: WebSocket port (0: any free one)")
      ->capture_default_str()
      ->check(CLI::Range(0, 65535));
  cmd->add_option("--view-address", o->view_address, "--view: address to listen on")
      ->capture_default_str();
  cmd->add_option("--view-wait", o->view_wait_s,
                  "--view: seconds to wait for a viewer to subscribe (0: start at once)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 3600.0));
  cmd->add_option("--seconds", o->seconds, "length of the drive")
      ->check(CLI::Range(1.0, 600.0))
      ->capture_default_str();
  cmd->add_option("--seed", o->seed, "the drive's random seed")->capture_default_str();
  cmd->add_option("--port", o->port, "Velodyne UDP port on 127.0.0.1 (0: any free one)")
      ->check(CLI::Range(0, 65535))
      ->capture_default_str();
  cmd->add_option("--ins-port", o->ins_port, "INS TCP port on 127.0.0.1 (0: any free one)")
      ->check(CLI::Range(0, 65535))
      ->capture_default_str();
  cmd->add_option("--domain", o->domain, "DDS domain (default: dds.domain_id)")
      ->check(CLI::Range(0, 230));
  cmd->add_option("--config", o->config, stac::settings::kConfigOptionHelp);
  cmd->callback([o] {
    if (const int code = run_demo(*o); code != 0) throw CLI::RuntimeError(code);
  });
}

}  // namespace stac::tools
