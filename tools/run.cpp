// stac run: the live component (docs/run.md). Threads:
//   receiver   UdpReceiver (Velodyne) -> ScanStream slots
//   pose       Applanix (TCP client or UDP) and SocketCAN (or the can thread's ring) ->
//              EgoEstimator -> PoseHistory
//   can        gs_usb only: GsUsbDevice (blocking libusb reads) -> odometry ring -> pose
//   perception ScanStream -> ScanPipeline -> result slots (full: the newest result is dropped)
//   publisher  result slots -> DDS tracked_objects, segments, ego_pose, point_cloud, health;
//   deadline monitor
// Everything is allocated before the threads start. SIGINT/SIGTERM (or --seconds/--scans) stop
// the receivers; perception and the publisher drain what was received, then a summary is printed.
#include <pthread.h>

#include <csignal>
#include <cstdio>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "dds/idl_types.hpp"
#include "dds/scan_publishing.hpp"
#include "drivers/applanix/tcp_client.hpp"
#include "drivers/applanix/udp_listener.hpp"
#include "drivers/can/dbc.hpp"
#include "drivers/can/odometry_input.hpp"
#include "drivers/io/udp_receiver.hpp"
#include "drivers/velodyne/calibration.hpp"
#include "drivers/velodyne/scan_stream.hpp"
#include "ego/ego_estimator.hpp"
#include "formats/model_file.hpp"
#include "pipeline/scan_pipeline.hpp"
#include "rt/clock.hpp"
#include "rt/deadline_monitor.hpp"
#include "rt/scheduling.hpp"
#include "rt/slot_exchange.hpp"
#include "rt/spsc_ring.hpp"
#include "rt/watchdog.hpp"
#include "runtime/can_input.hpp"
#include "settings/dds_settings.hpp"
#include "settings/run_settings.hpp"
#include "settings/settings.hpp"
#include "tools/commands.hpp"
#include "tools/support/cli_checks.hpp"

namespace stac::tools {
namespace {

struct RunOptions {
  std::string config, calib, ins, ins_address, bind, model, dds_config;
  double seconds = 0;
  std::uint64_t scans = 0;
  int domain = -1, port = -1, ins_port = -1, point_cloud_stride = -1;
};

volatile std::sig_atomic_t g_signal = 0;
void on_signal(int) {
  g_signal = 1;
}
volatile std::sig_atomic_t g_reload = 0;  // SIGHUP: read the model file again
void on_reload(int) {
  g_reload = 1;
}

enum Input : std::size_t { kLidar, kIns, kCan };
// While no scan is published, a health sample (without stages) every second.
constexpr std::int64_t kIdleHealthNs = 1'000'000'000;
// After a stop request the receiver reads what its socket holds for at most this long.
constexpr std::int64_t kStopDrainNs = 300'000'000;
constexpr const char* kInputNames[] = {"lidar", "ins", "can"};

// Health stages: where the time of one scan went, from its last firing to its publication.
enum HealthStage : std::size_t {
  kWait,
  kDeskew,
  kSegment,
  kTrack,
  kClassify,
  kClassifyDeferred,
  kHandover,
  kPublish,
  kHealthStages
};
constexpr const char* kStageNames[] = {
    "wait", "deskew", "segment", "track", "classify", "classify_deferred", "handover", "publish"};

// One perception result in a slot of the perception -> publisher exchange.
struct Frame {
  pipeline::ScanResult result;
  std::int64_t last_firing_ns = 0;  // receive clock (CLOCK_REALTIME, kernel stamps)
  std::int64_t started_ns = 0;      // perception took the scan
  std::int64_t finished_ns = 0;     // perception pushed the result
  std::uint64_t incomplete = 0;     // cumulative, as seen by perception at this scan
  std::uint64_t packets_lost = 0;
  std::uint64_t segment_overflow = 0;
  std::uint64_t without_pose = 0;  // scans not deskewed (no pose at their time)
  std::uint64_t classes_late = 0;  // published tracks classified after publication (budget)
};

// Counters shared between the threads (each written by one thread).
struct Shared {
  std::atomic<bool> stopping{false};  // main: stop requested; the receiver drains its socket first
  std::atomic<bool> receiver_done{false}, perception_done{false};
  std::atomic<std::uint64_t> packets{0}, kernel_drops{0}, receive_errors{0};
  // The receiver's packets dropped by the decoder, by cause (AssemblerCounters).
  std::atomic<std::uint64_t> wrong_size{0}, invalid_block{0}, duplicates{0}, late_firings{0};
  // The INS input's (ParserCounters, TcpClientCounters): checksum, framing (length, terminator,
  // oversize, truncated), layout, bytes skipped, and the TCP connection.
  std::atomic<std::uint64_t> ins_bad_checksum{0}, ins_bad_framing{0}, ins_malformed{0},
      ins_garbage_bytes{0};
  std::atomic<std::uint64_t> ins_connect_failures{0}, ins_disconnects{0};
  std::atomic<std::uint64_t> scans{0}, incomplete{0}, published{0}, publish_errors{0};
  // Published tracks classified before / after their scan's publication (run.classify_budget_ms).
  std::atomic<std::uint64_t> classes_current{0}, classes_late{0};
  std::atomic<std::uint8_t> ego_source{0};  // 0 none, 1 INS, 2 CAN dead reckoning
  CanCounterCells can;                      // written by the thread that reads CAN
  // A model handed to the perception thread (SIGHUP): main fills `incoming` and sets
  // `model_ready`; perception swaps it in between scans and clears it. Main then drops the old
  // model (never freed on the perception thread).
  std::atomic<bool> model_ready{false};
  std::shared_ptr<const classification::TrackClassifierModel> incoming;
  std::atomic<std::uint64_t> model_hash{0};
  std::atomic<std::uint32_t> model_reloads{0};
  std::atomic<std::uint64_t> model_refused{0};  // reloads refused (bad file, other classes)
  std::uint64_t incoming_hash = 0;              // main's, with `incoming`
};

void idle() {
  std::this_thread::sleep_for(std::chrono::microseconds(200));
}

void start_thread(const char* name, const rt::ThreadSchedule& s) {
  rt::name_thread(name);
  if (auto r = rt::apply_schedule(name, s); !r)
    std::fprintf(stderr, "stac run: warning: %s\n", r.error().message.c_str());
}

std::uint8_t sensor_status(const rt::InputStatus& s) {
  switch (s.state) {
    case rt::InputState::kOk:
      return 0;
    case rt::InputState::kStalled:
      return 1;
    case rt::InputState::kLost:
      return 2;
    case rt::InputState::kNotConfigured:
      return 3;
  }
  return 2;
}

std::uint32_t to_us(std::int64_t ns) {
  return static_cast<std::uint32_t>(std::clamp<std::int64_t>(ns / 1000, 0, UINT32_MAX));
}

// Odometry updates in flight from the can thread to the pose thread, which drains them every
// 5 ms or sooner: 1024 are 50 ms of a 1 Mbit/s bus full of the shortest frames (about 20,000/s),
// ten drain periods. Full: the newest update is dropped and counted (can.overflow).
constexpr std::size_t kOdometryRing = 1024;

// The pose thread's inputs (and the can thread's), opened at start-up.
struct PoseInputs {
  std::optional<applanix::TcpClient> tcp;
  std::optional<applanix::UdpListener> udp;
  // can.transport: socketcan, polled by the pose thread between its INS reads.
  std::optional<can::OdometryInput<can::SocketCanReader>> socketcan;
  // can.transport: gs_usb, read by the can thread into `odometry`, which the pose thread drains.
  std::optional<can::OdometryInput<can::GsUsbDevice>> gs_usb;
  std::optional<rt::SpscRing<can::OdometryUpdate>> odometry;
  std::atomic<bool> can_done{false};  // the can thread ended (stopped, or the adapter is gone)
  [[nodiscard]] bool ins() const { return tcp || udp; }
  [[nodiscard]] bool can() const { return socketcan || gs_usb; }
  [[nodiscard]] can::CanInputCounters can_counters() const {  // once the readers ended
    return socketcan ? socketcan->counters()
           : gs_usb  ? gs_usb->counters()
                     : can::CanInputCounters{};
  }
  void stop() {
    if (tcp) tcp->stop();
    if (udp) udp->stop();
    if (socketcan) socketcan->stop();
    if (gs_usb) gs_usb->stop();
  }
};

void pose_loop(PoseInputs& in, ego::EgoEstimator& estimator, const ego::PoseHistory& history,
               rt::Watchdog& watchdog, CanReport& can_report, Shared& shared) {
  applanix::StreamParser parser;
  std::vector<std::uint8_t> bytes(16384);
  std::uint64_t session = 0;
  bool can_closed = false;
  applanix::Parsed m;
  const int timeout_ms = in.can() ? 5 : 50;  // the INS and CAN handled in turn when CAN is read
  const auto add_odometry = [&](const can::OdometryUpdate& u) { estimator.add_odometry(u); };
  for (;;) {
    bool stopped = false;
    auto take = [&](const applanix::StreamParser& p) {
      const std::uint64_t fixes = estimator.counters().ins_fixes;
      estimator.add_ins(m, p);
      // Only a fix that became a pose shows the INS alive (not a rejected or unusable one).
      if (estimator.counters().ins_fixes != fixes) watchdog.beat(kIns, rt::monotonic_ns());
    };
    auto publish_counters = [&](const applanix::ParserCounters& pc) {
      const auto set = [](std::atomic<std::uint64_t>& a, std::uint64_t v) {
        a.store(v, std::memory_order_relaxed);
      };
      set(shared.ins_bad_checksum, pc.bad_checksum);
      set(shared.ins_bad_framing, pc.bad_length + pc.bad_terminator + pc.oversize + pc.truncated);
      set(shared.ins_malformed, pc.malformed);
      set(shared.ins_garbage_bytes, pc.garbage_bytes);
      if (in.tcp) {
        set(shared.ins_connect_failures, in.tcp->counters().connect_failures);
        set(shared.ins_disconnects, in.tcp->counters().disconnects + in.tcp->counters().stalls +
                                        in.tcp->counters().no_message);
      }
    };
    if (in.tcp) {
      const int n = in.tcp->receive(bytes, timeout_ms);
      if (n == applanix::TcpClient::kStopped) stopped = true;
      if (in.tcp->session() != session) {
        session = in.tcp->session();
        parser.end_of_stream();
      }
      if (n > 0) {
        parser.feed({bytes.data(), static_cast<std::size_t>(n)});
        while (parser.next(m)) {
          in.tcp->note_message();  // the stream holds the INS's messages
          take(parser);
        }
      }
      publish_counters(parser.counters());
    } else if (in.udp) {
      const int n = in.udp->receive(timeout_ms);
      if (n == io::UdpReceiver::kStopped) stopped = true;
      while (n > 0 && in.udp->next(m)) take(in.udp->parser());
      publish_counters(in.udp->parser().counters());
    }
    if (in.socketcan && !can_closed) {
      const can::InputEvent e =
          read_can(*in.socketcan, in.ins() ? 0 : timeout_ms, add_odometry, can_report);
      if (e == can::InputEvent::kStopped) stopped = true;
      if (e == can::InputEvent::kGone) {  // marked lost; the INS goes on
        can_closed = true;
        if (!in.ins()) return;
      }
    }
    if (in.odometry) {  // gs_usb: what the can thread read
      const bool can_done = in.can_done.load(std::memory_order_acquire);
      for (can::OdometryUpdate u; in.odometry->try_pop(u);) add_odometry(u);
      if (!in.ins()) {  // nothing else to wait on
        if (can_done) return;
        std::this_thread::sleep_for(std::chrono::milliseconds(timeout_ms));
      }
    }
    const ego::EgoSource s = estimator.source(history.newest_stamp_ns());
    shared.ego_source.store(s == ego::EgoSource::kIns             ? 1
                            : s == ego::EgoSource::kDeadReckoning ? 2
                                                                  : 0,
                            std::memory_order_relaxed);
    if (stopped) return;
  }
}

// The CAN input as the start-up line and the summary name it.
std::string can_description(const can::CanConfig& c) {
  if (c.transport == can::Transport::kSocketCan) return c.socketcan.interface;
  return "gs_usb channel " + std::to_string(c.gs_usb.channel) + " at " +
         std::to_string(c.gs_usb.bitrate_bps) + " bit/s" +
         (c.gs_usb.listen_only ? " (listen-only)" : "");
}

// Opens the configured CAN transport with the DBC signal map's decoder. SocketCAN gets the mapped
// ids as its kernel filter; a gs_usb adapter delivers the whole bus and the decoder drops the rest.
rt::Result<bool> open_can(can::CanConfig& c, PoseInputs& inputs) {
  auto db = can::load_dbc(c.dbc);
  if (!db) return rt::Unexpected<rt::Error>{db.error()};
  auto decoder = can::OdometryDecoder::create(*db, c.signals);
  if (!decoder) return rt::Unexpected<rt::Error>{decoder.error()};
  if (c.transport == can::Transport::kSocketCan) {
    c.socketcan.filters = decoder->filters();
    auto reader = can::SocketCanReader::open(c.socketcan);
    if (!reader) return rt::Unexpected<rt::Error>{reader.error()};
    inputs.socketcan.emplace(std::move(*reader), std::move(*decoder));
  } else {
    auto device = can::GsUsbDevice::open(c.gs_usb);
    if (!device) return rt::Unexpected<rt::Error>{device.error()};
    inputs.gs_usb.emplace(std::move(*device), std::move(*decoder));
    inputs.odometry.emplace(kOdometryRing);
  }
  return true;
}

int run_live(const RunOptions& o) {
  const std::filesystem::path config = config_path(o.config);
  auto settings = load_pipeline_settings(config);
  if (!settings) return fail(settings.error().message);
  VelodyneSettings& vs = settings->velodyne;
  EgoSettings& es = settings->ego;
  auto dds_config = load_dds_settings(config);
  if (!dds_config) return fail(dds_config.error().message);
  auto rs = load_run_settings(config);
  if (!rs) return fail(rs.error().message);
  std::optional<can::CanConfig> can_config;
  if (rs->can) {
    auto c = load_can_settings(config);
    if (!c) return fail(c.error().message);
    can_config = *c;
  }
  // Command-line overrides.
  if (!o.calib.empty()) vs.calibration = o.calib;
  if (o.port >= 0) vs.port = static_cast<std::uint16_t>(o.port);
  if (!o.bind.empty()) vs.bind_address = o.bind;
  if (o.domain >= 0) dds_config->domain_id = static_cast<std::uint32_t>(o.domain);
  if (o.point_cloud_stride >= 0)
    dds_config->point_cloud_stride = static_cast<std::uint32_t>(o.point_cloud_stride);
  if (!o.dds_config.empty())
    dds_config->config_uri = "file://" + std::filesystem::absolute(o.dds_config).string();
  if (!o.ins.empty()) {
    auto t = parse_ins_transport(o.ins);
    if (!t) return fail("--ins: " + t.error().message);
    rs->ins = *t;
  }
  if (!o.ins_address.empty()) rs->ins_address = o.ins_address;
  if (o.ins_port >= 0) es.ins_port = static_cast<std::uint16_t>(o.ins_port);
  if (vs.calibration.empty())
    return fail("'velodyne.calibration': stac run needs the unit's calibration file");
  auto calibration = velodyne::load_calibration(vs.calibration);
  if (!calibration) return fail(calibration.error().message);

  // Start-up: every allocation of the run happens from here to the threads' start.
  if (rs->lock_memory) {
    if (auto r = rt::lock_memory(); !r)
      std::fprintf(stderr, "stac run: warning: %s\n", r.error().message.c_str());
  }
  std::optional<rt::CpuLatencyRequest> cpu_latency;  // held until the run returns
  if (rs->cpu_wake_latency_us >= 0) {
    if (auto r = rt::CpuLatencyRequest::hold(rs->cpu_wake_latency_us); r) {
      cpu_latency.emplace(std::move(*r));
    } else {
      std::fprintf(stderr, "stac run: warning: %s\n", r.error().message.c_str());
    }
  }
  auto model = job_model(o.model, settings->classification.model);
  if (!model) return fail(model.error().message);
  // The file SIGHUP reads again: the one the model came from.
  const std::filesystem::path model_path = !o.model.empty() && o.model != "none"
                                               ? std::filesystem::path(o.model)
                                               : settings->classification.model;
  std::shared_ptr<const classification::TrackClassifierModel> current_model = *model;
  const pipeline::PipelineConfig pc{.deskew = es.deskew,
                                    .segmenter = settings->segmenter,
                                    .tracker = settings->tracker,
                                    .classifier = settings->classification.classifier,
                                    .model = *model,
                                    .describe = false,
                                    .split_classification = true,
                                    .publish_tentative = dds_config->tentative_tracks,
                                    .trailer = velodyne::traits(vs.assembler.decoder.model).trailer,
                                    .cloud_stride = dds_config->point_cloud_stride,
                                    .cloud_max_points = dds::kMaxCloudPoints,
                                    .clock = pipeline::StageClock::kMonotonic};
  if (auto r = ScanPublishing::check_capacities(pc); !r) return fail(r.error().message);
  auto publisher = dds::Publisher::create(*dds_config);
  if (!publisher) return fail(publisher.error().message);
  auto receiver = io::UdpReceiver::open({.bind_address = vs.bind_address,
                                         .port = vs.port,
                                         .receive_buffer_bytes = vs.receive_buffer_bytes,
                                         .sender_address = vs.sender_address,
                                         .batch = 32,
                                         .max_payload = 2048});
  if (!receiver) return fail(receiver.error().message);

  PoseInputs inputs;
  if (rs->ins == InsTransport::kTcp) {
    auto c = applanix::TcpClient::open({.address = rs->ins_address, .port = es.ins_port});
    if (!c) return fail(c.error().message);
    inputs.tcp.emplace(std::move(*c));
  } else if (rs->ins == InsTransport::kUdp) {
    auto l = applanix::UdpListener::open({.bind_address = "0.0.0.0",
                                          .port = es.ins_port,
                                          .receive_buffer_bytes = 1 << 20,
                                          .sender_address = "",
                                          .batch = 32,
                                          .max_payload = 8192});
    if (!l) return fail(l.error().message);
    inputs.udp.emplace(std::move(*l));
  }
  if (can_config) {
    if (auto r = open_can(*can_config, inputs); !r) return fail(r.error().message);
  }
  const bool have_pose_thread = inputs.ins() || inputs.can();
  ego::LocalFrame frame(es.origin);
  if (can_config) es.estimator.odometry = can_config->dead_reckoning;
  ego::PoseHistory history(es.history);
  ego::EgoEstimator estimator(es.estimator, frame, history);

  velodyne::ScanStream stream(*calibration, vs.assembler, static_cast<std::size_t>(vs.scan_slots));
  pipeline::ScanPipeline pipeline(pc);
  rt::SlotExchange<Frame> results(rs->result_slots, [&] { return Frame{pipeline.make_result()}; });
  ScanPublishing scan_publishing(**publisher, dds_config->tentative_tracks,
                                 ScanPublishing::classes_of(pc));
  rt::DeadlineMonitor monitor(rs->deadline, kHealthStages);
  rt::Watchdog watchdog;
  watchdog.start(
      {rs->velodyne_timeout_ns, inputs.ins() ? es.estimator.ins_timeout_ns : std::int64_t{0},
       can_config ? can_config->dead_reckoning.stale_timeout_ns : std::int64_t{0}, std::int64_t{0}},
      rt::monotonic_ns());
  Shared shared;
  if (current_model != nullptr) shared.model_hash = classification::model_hash(*current_model);
  CanReport can_report{watchdog, kCan, shared.can};
  const ego::PoseHistory* poses = inputs.ins() ? &history : nullptr;

  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  struct sigaction reload {};
  reload.sa_handler = on_reload;
  sigaction(SIGHUP, &reload, nullptr);
  // The worker threads start with SIGINT and SIGTERM blocked, so only the main thread takes them
  // (no receive call is interrupted); it unblocks them once the threads run.
  sigset_t stop_signals;
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGINT);
  sigaddset(&stop_signals, SIGTERM);
  sigaddset(&stop_signals, SIGHUP);
  pthread_sigmask(SIG_BLOCK, &stop_signals, nullptr);
  std::fprintf(stderr,
               "stac run: Velodyne UDP %s:%u, INS %s, CAN %s, DDS domain %u; Ctrl-C stops\n",
               vs.bind_address.c_str(), receiver->port(),
               rs->ins == InsTransport::kTcp
                   ? (rs->ins_address + ":" + std::to_string(es.ins_port) + " (tcp)").c_str()
               : rs->ins == InsTransport::kUdp ? ("udp port " + std::to_string(es.ins_port)).c_str()
                                               : "none (parked sensor)",
               can_config ? can_description(*can_config).c_str() : "none", dds_config->domain_id);

  std::thread receiver_thread([&] {
    start_thread("receiver", rs->receiver);
    std::array<io::Datagram, 32> batch{};
    std::int64_t stop_seen_ns = 0;
    for (;;) {
      // After a stop request: what the socket already holds is still read, then the thread ends;
      // under a flood that never lets the socket run empty, for at most kStopDrainNs.
      const bool stopping = shared.stopping.load(std::memory_order_acquire);
      if (stopping && stop_seen_ns == 0) stop_seen_ns = rt::monotonic_ns();
      const int n = receiver->receive(batch, stopping ? 0 : 100);
      if (n == io::UdpReceiver::kStopped || (stopping && n == 0)) break;
      if (stopping && rt::monotonic_ns() - stop_seen_ns > kStopDrainNs) break;
      if (n == io::UdpReceiver::kError) {
        shared.receive_errors.fetch_add(1, std::memory_order_relaxed);
        idle();
        continue;
      }
      const velodyne::AssemblerCounters& ac = stream.assembler().counters();
      const auto rejected = [&] { return ac.wrong_size + ac.invalid_block + ac.duplicates; };
      const std::uint64_t rejected_before = rejected();
      for (int i = 0; i < n; ++i) {
        const io::Datagram& d = batch[static_cast<std::size_t>(i)];
        (void)stream.add_packet(d.payload, d.stamp_ns);
      }
      if (n > 0) {
        // Only a packet the decoder took shows the sensor alive (not garbage on its port).
        if (rejected() - rejected_before < static_cast<std::uint64_t>(n))
          watchdog.beat(kLidar, rt::monotonic_ns());
        shared.packets.fetch_add(static_cast<std::uint64_t>(n), std::memory_order_relaxed);
        shared.wrong_size.store(ac.wrong_size, std::memory_order_relaxed);
        shared.invalid_block.store(ac.invalid_block, std::memory_order_relaxed);
        shared.duplicates.store(ac.duplicates, std::memory_order_relaxed);
        shared.late_firings.store(ac.late_firings, std::memory_order_relaxed);
      }
      shared.kernel_drops.store(receiver->counters().kernel_drops, std::memory_order_relaxed);
    }
    shared.receiver_done.store(true, std::memory_order_release);
  });
  std::thread can_thread;
  if (inputs.gs_usb) {
    can_thread = std::thread([&] {
      start_thread("can", rs->pose);  // the pose thread's priority and CPU
      (void)read_can_until_end(*inputs.gs_usb, *inputs.odometry, can_report);
      inputs.can_done.store(true, std::memory_order_release);
    });
  }
  std::thread pose_thread;
  if (have_pose_thread) {
    pose_thread = std::thread([&] {
      start_thread("pose", rs->pose);
      pose_loop(inputs, estimator, history, watchdog, can_report, shared);
    });
  }
  std::thread perception_thread([&] {
    start_thread("perception", rs->perception);
    std::uint64_t incomplete = 0, packets_lost = 0, overflow = 0, classes_late = 0,
                  classes_current = 0;
    for (;;) {
      if (shared.model_ready.load(std::memory_order_acquire)) {  // between scans
        pipeline.classifier()->set_model(shared.incoming);
        shared.model_hash.store(shared.incoming_hash, std::memory_order_relaxed);
        shared.model_reloads.fetch_add(1, std::memory_order_relaxed);
        shared.model_ready.store(false, std::memory_order_release);
      }
      velodyne::Scan* scan = stream.take();
      if (scan == nullptr) {
        if (!shared.receiver_done.load(std::memory_order_acquire)) {
          idle();
          continue;
        }
        if ((scan = stream.take()) == nullptr) break;
      }
      packets_lost += scan->header.packets_lost;
      if (!scan->header.complete()) {  // the first scan after start-up or a gap, or points dropped
        shared.incomplete.store(++incomplete, std::memory_order_relaxed);
        stream.release();
        continue;
      }
      Frame& f = results.current();
      f.started_ns = rt::realtime_ns();
      f.last_firing_ns = scan->header.end_stamp_ns;
      // Published tracks are classified until the scan is classify_budget old; the rest after.
      pipeline.process(*scan, poses, f.result, f.last_firing_ns + rs->classify_budget_ns);
      classes_late += f.result.classes_late;
      classes_current += f.result.classes_current;
      const segmentation::SegmentCounters& c = f.result.segments.counters;
      overflow += c.ignored_over_capacity + c.dropped_cell_overflow + c.dropped_segment_overflow;
      f.incomplete = incomplete;
      f.packets_lost = packets_lost;
      f.segment_overflow = overflow;
      f.without_pose = pipeline.scans_without_pose();
      f.classes_late = classes_late;
      shared.classes_late.store(classes_late, std::memory_order_relaxed);
      shared.classes_current.store(classes_current, std::memory_order_relaxed);
      f.finished_ns = rt::realtime_ns();
      shared.scans.fetch_add(1, std::memory_order_relaxed);
      (void)results.publish();      // full: dropped and counted by the exchange; perception goes on
      pipeline.finish_scan(*scan);  // the other tracks and the accumulated clouds: off the latency
      stream.release();
    }
    shared.perception_done.store(true, std::memory_order_release);
  });
  std::thread publisher_thread([&] {
    start_thread("publisher", rs->publisher);
    std::array<std::int64_t, kHealthStages> stage_ns{};
    std::array<dds::StageLatencyIn, kHealthStages> stages{};
    std::array<dds::DropCountIn, 28> drops{};
    static_assert(std::tuple_size_v<decltype(drops)> <= dds::kMaxDrops, "idl/stac.idl's bound");
    std::array<dds::SensorStatusIn, 3> sensors{};
    bool reported = false;
    // The counters of the last published scan's frame (health without a scan repeats them).
    struct FrameDrops {
      std::uint64_t incomplete = 0, packets_lost = 0, segment_overflow = 0, without_pose = 0;
      std::uint64_t pool_overflow = 0, dropped_detections = 0, classes_late = 0;
    } frame_drops;
    const auto get = [](const std::atomic<std::uint64_t>& a) {
      return a.load(std::memory_order_relaxed);
    };
    // Health now: drops by cause and the inputs' status, with this scan's stages (none when no
    // scan is published: the samples of a silent or dead sensor).
    const auto health_sample = [&](std::int64_t stamp_ns, std::uint64_t index,
                                   std::span<const dds::StageLatencyIn> scan_stages,
                                   std::int64_t end_to_end) {
      const std::int64_t now = rt::monotonic_ns();
      watchdog.update(now);
      const can::CanInputCounters cc = shared.can.load();
      const FrameDrops& fd = frame_drops;
      drops = {dds::DropCountIn{"velodyne.kernel", get(shared.kernel_drops)},
               {"velodyne.wrong_size", get(shared.wrong_size)},
               {"velodyne.invalid_block", get(shared.invalid_block)},
               {"velodyne.duplicates", get(shared.duplicates)},
               {"velodyne.late_firings", get(shared.late_firings)},
               {"velodyne.scan_slots_full", stream.scans_dropped()},
               {"velodyne.incomplete_scan", fd.incomplete},
               {"velodyne.packets_lost", fd.packets_lost},
               {"results.slots_full", results.dropped()},
               {"segmentation.overflow", fd.segment_overflow},
               {"tracking.pool_full", fd.pool_overflow},
               {"tracking.detections", fd.dropped_detections},
               {"dds.errors", get(shared.publish_errors)},
               {"pose.rejected", history.rejected()},
               {"ins.bad_checksum", get(shared.ins_bad_checksum)},
               {"ins.bad_framing", get(shared.ins_bad_framing)},
               {"ins.malformed", get(shared.ins_malformed)},
               {"ins.garbage_bytes", get(shared.ins_garbage_bytes)},
               {"ins.connect_failures", get(shared.ins_connect_failures)},
               {"ins.disconnects", get(shared.ins_disconnects)},
               {"ego.scans_without_pose", fd.without_pose},
               {"classification.late", fd.classes_late},
               {"can.not_mapped", cc.not_mapped},
               {"can.overflow", cc.kernel_drops + cc.overflows + get(shared.can.ring_full)},
               {"can.fd", cc.can_fd},
               {"can.malformed", cc.malformed},
               {"can.other_channel", cc.other_channel},
               {"model.reload_refused", get(shared.model_refused)}};
      for (std::size_t i = 0; i < sensors.size(); ++i) {
        const rt::InputStatus st = watchdog.status(i, now);
        sensors[i] = {kInputNames[i], sensor_status(st),
                      static_cast<float>(static_cast<double>(st.age_ns) * 1e-9)};
      }
      return dds::HealthIn{.scan = {stamp_ns, index},
                           .stages = scan_stages,
                           .end_to_end_latency_us = to_us(end_to_end),
                           .deadline_misses = monitor.misses(),
                           .drops = drops,
                           .sensors = sensors,
                           .model_hash = shared.model_hash.load(std::memory_order_relaxed),
                           .model_reloads = shared.model_reloads.load(std::memory_order_relaxed)};
    };
    std::int64_t last_health_ns = rt::monotonic_ns();
    for (;;) {
      Frame* f = results.take();
      if (f == nullptr) {
        if (!shared.perception_done.load(std::memory_order_acquire)) {
          // No scan for kIdleHealthNs: a health sample without stages, so that subscribers see
          // a stale or dead sensor (and garbage on its port counted) while nothing is published.
          if (rt::monotonic_ns() - last_health_ns >= kIdleHealthNs) {
            const std::uint64_t published = get(shared.published);
            const dds::HealthIn h =
                health_sample(rt::realtime_ns(), published == 0 ? 0 : published - 1, {}, 0);
            if (auto r = (*publisher)->publish_health(h); !r)
              shared.publish_errors.fetch_add(1, std::memory_order_relaxed);
            last_health_ns = rt::monotonic_ns();
          }
          idle();
          continue;
        }
        if ((f = results.take()) == nullptr) break;
      }
      const std::int64_t t0 = rt::realtime_ns();
      const std::uint64_t index = shared.published.load(std::memory_order_relaxed);
      auto status = scan_publishing.publish(f->result, index,
                                            shared.ego_source.load(std::memory_order_relaxed));
      const std::int64_t t1 = rt::realtime_ns();
      const std::int64_t end_to_end = t1 - f->last_firing_ns;
      stage_ns = {f->started_ns - f->last_firing_ns,
                  f->result.stage_ns[pipeline::kDeskew],
                  f->result.stage_ns[pipeline::kSegment],
                  f->result.stage_ns[pipeline::kTrack],
                  f->result.stage_ns[pipeline::kClassify],
                  f->result.stage_ns[pipeline::kClassifyDeferred],
                  t0 - f->finished_ns,
                  t1 - t0};
      (void)monitor.record(stage_ns, end_to_end);
      for (std::size_t i = 0; i < kHealthStages; ++i)
        stages[i] = {kStageNames[i], to_us(stage_ns[i])};
      const tracking::TrackerCounters& tc = f->result.tracked.counters;
      frame_drops = {f->incomplete,    f->packets_lost,       f->segment_overflow, f->without_pose,
                     tc.pool_overflow, tc.dropped_detections, f->classes_late};
      const dds::HealthIn health = health_sample(f->result.stamp_ns, index, stages, end_to_end);
      if (auto h = (*publisher)->publish_health(health); !h && status) status = h;
      last_health_ns = rt::monotonic_ns();
      // The viewers' cloud last, outside the scan's end-to-end latency (it is the largest sample).
      if (auto c = scan_publishing.publish_cloud(f->result, index); !c && status) status = c;
      pipeline.want_cloud(scan_publishing.cloud_reader());  // as publish_cloud found it
      results.release();
      if (status) {
        shared.published.fetch_add(1, std::memory_order_relaxed);
      } else {
        shared.publish_errors.fetch_add(1, std::memory_order_relaxed);
        if (!reported) std::fprintf(stderr, "stac run: DDS: %s\n", status.error().message.c_str());
        reported = true;
      }
    }
  });

  pthread_sigmask(SIG_UNBLOCK, &stop_signals, nullptr);
  // The main thread waits for a stop: a signal, --seconds, or --scans published; and swaps in
  // the model file again on SIGHUP.
  const std::int64_t start = rt::monotonic_ns();
  std::shared_ptr<const classification::TrackClassifierModel> next_model;
  while (g_signal == 0) {
    if (next_model != nullptr && !shared.model_ready.load(std::memory_order_acquire)) {
      current_model = std::move(next_model);  // swapped in: the old one is freed here
      next_model = nullptr;
      std::fprintf(stderr, "stac run: model %s (%016llx) in use\n", model_path.c_str(),
                   static_cast<unsigned long long>(shared.incoming_hash));
    }
    if (g_reload != 0 && next_model == nullptr) {
      g_reload = 0;
      std::string refused;
      auto m = model_path.empty() ? rt::Result<classification::TrackClassifierModel>(
                                        rt::make_error("no model file is configured"))
                                  : read_model_file(model_path);
      if (!m) {
        refused = m.error().message;
      } else if (pipeline.classifier() == nullptr || current_model == nullptr) {
        refused = "started without a model: restart with --model to classify";
      } else if (const std::string bad = pipeline.classifier()->check_swap(*m); !bad.empty()) {
        refused = model_path.string() + ": " + bad;
      }
      if (!refused.empty()) {
        shared.model_refused.fetch_add(1, std::memory_order_relaxed);
        std::fprintf(stderr, "stac run: SIGHUP: the model is kept: %s\n", refused.c_str());
      } else {
        next_model = std::make_shared<const classification::TrackClassifierModel>(std::move(*m));
        shared.incoming_hash = classification::model_hash(*next_model);
        shared.incoming = next_model;
        shared.model_ready.store(true, std::memory_order_release);
      }
    }
    if (o.seconds > 0 && static_cast<double>(rt::monotonic_ns() - start) * 1e-9 >= o.seconds) break;
    if (o.scans > 0 && shared.published.load(std::memory_order_relaxed) >= o.scans) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  shared.stopping.store(true, std::memory_order_release);
  inputs.stop();
  receiver_thread.join();
  if (can_thread.joinable()) can_thread.join();
  if (pose_thread.joinable()) pose_thread.join();
  perception_thread.join();
  publisher_thread.join();

  // The summary.
  watchdog.update(rt::monotonic_ns());  // stalls since the last published scan count too
  const double elapsed_s = static_cast<double>(rt::monotonic_ns() - start) * 1e-9;
  const auto u = [](std::uint64_t v) { return static_cast<unsigned long long>(v); };
  const auto ms = [](std::int64_t ns) { return static_cast<double>(ns) * 1e-6; };
  const io::UdpReceiverCounters& rc = receiver->counters();
  std::fprintf(stderr, "stac run: stopped after %.1f s%s\n", elapsed_s,
               g_signal != 0 ? " (signal)" : "");
  std::fprintf(stderr,
               "  packets     %llu received, %llu dropped by the kernel, %llu truncated, %llu "
               "receive errors, %llu lost on the wire (estimated from azimuth steps)\n",
               u(rc.received), u(rc.kernel_drops), u(rc.truncated), u(shared.receive_errors.load()),
               u(stream.assembler().counters().packets_lost));
  std::fprintf(
      stderr,
      "  dropped     wrong size %llu, invalid block %llu, duplicate %llu, late firings %llu "
      "(packets the decoder refused)\n",
      u(shared.wrong_size.load()), u(shared.invalid_block.load()), u(shared.duplicates.load()),
      u(shared.late_firings.load()));
  std::fprintf(
      stderr,
      "  scans       %llu received (complete), %llu published, %llu incomplete (not processed), "
      "%llu of them with more packets lost than velodyne.min_scan_completeness %.2f allows\n",
      u(shared.scans.load()), u(shared.published.load()), u(shared.incomplete.load()),
      u(stream.assembler().counters().below_completeness), vs.assembler.min_completeness);
  std::fprintf(
      stderr,
      "  drops       scan slots full %llu, result slots full %llu, DDS errors %llu, tracking pool "
      "full %llu, detections %llu\n",
      u(stream.scans_dropped()), u(results.dropped()), u(shared.publish_errors.load()),
      u(pipeline.tracker().counters().pool_overflow),
      u(pipeline.tracker().counters().dropped_detections));
  if (current_model != nullptr) {
    std::fprintf(stderr, "  model       %016llx, %u swapped in (SIGHUP), %llu refused\n",
                 u(shared.model_hash.load()), shared.model_reloads.load(),
                 u(shared.model_refused.load()));
  }
  if (pipeline.classifier() != nullptr) {
    std::fprintf(stderr,
                 "  classes     %llu published tracks classified before publication, %llu after "
                 "it (run.classify_budget_ms %.1f: their class one scan late)\n",
                 u(shared.classes_current.load()), u(shared.classes_late.load()),
                 ms(rs->classify_budget_ns));
  }
  std::fprintf(
      stderr, "  ego         %llu INS fixes, %llu dead-reckoned poses, %llu scans without a pose\n",
      u(estimator.counters().ins_fixes), u(estimator.counters().dead_reckoned),
      u(pipeline.scans_without_pose()));
  if (have_pose_thread && rs->ins != InsTransport::kNone) {
    std::fprintf(stderr,
                 "  ins         %llu poses rejected, %llu fixes with impossible values, %llu time "
                 "jumps, %llu jumps back (a new timeline); input: bad "
                 "checksum %llu, bad framing %llu, malformed %llu, %llu bytes skipped; connect "
                 "failures %llu, disconnects %llu\n",
                 u(history.rejected()), u(estimator.counters().impossible),
                 u(estimator.counters().time_jumps), u(estimator.counters().backward_jumps),
                 u(shared.ins_bad_checksum.load()), u(shared.ins_bad_framing.load()),
                 u(shared.ins_malformed.load()), u(shared.ins_garbage_bytes.load()),
                 u(shared.ins_connect_failures.load()), u(shared.ins_disconnects.load()));
  }
  if (can_config) {
    const can::CanInputCounters cc = inputs.can_counters();
    std::fprintf(stderr,
                 "  can         %s: %llu frames, %llu with odometry, %llu not in the signal map; "
                 "drops: kernel %llu, adapter overflows %llu, ring full %llu, CAN FD %llu, "
                 "malformed %llu, other channel %llu; read errors %llu\n",
                 can_description(*can_config).c_str(), u(cc.frames), u(cc.updates),
                 u(cc.not_mapped), u(cc.kernel_drops), u(cc.overflows),
                 u(shared.can.ring_full.load()), u(cc.can_fd), u(cc.malformed), u(cc.other_channel),
                 u(cc.read_errors));
  }
  std::fprintf(stderr, "  inputs     ");
  for (std::size_t i = 0; i < 3; ++i) {
    std::fprintf(stderr, " %s %s (%llu stalls)", kInputNames[i],
                 rt::to_string(watchdog.status(i, rt::monotonic_ns()).state),
                 u(watchdog.stalls(i)));
  }
  std::fprintf(stderr, "\n  deadline    %.1f ms: %llu misses of %llu published scans\n",
               ms(monitor.budget_ns()), u(monitor.misses()), u(monitor.end_to_end().count()));
  std::fprintf(stderr, "  %-12s %9s %9s %9s   (ms, wall clock; histogram bins of 0.1 ms)\n",
               "latency", "p50", "p99", "max");
  const auto row = [&](const char* name, const rt::LatencyHistogram& h) {
    std::fprintf(stderr, "  %-12s %9.3f %9.3f %9.3f\n", name, ms(h.percentile(0.5)),
                 ms(h.percentile(0.99)), ms(h.max_ns()));
  };
  for (std::size_t i = 0; i < kHealthStages; ++i) row(kStageNames[i], monitor.stage(i));
  row("end-to-end", monitor.end_to_end());
  return 0;
}

}  // namespace

void add_run_command(CLI::App& app) {
  auto o = std::make_shared<RunOptions>();
  CLI::App* cmd =
      app.add_subcommand("run", "The live component: sensor UDP -> perception -> DDS topics");
  cmd->description(
      "Receives the HDL-64E's UDP packets, the Applanix INS (TCP or UDP) and optionally the\n"
      "vehicle CAN bus (SocketCAN or a gs_usb adapter: can.transport), runs every complete scan\n"
      "through deskew -> segment -> track -> classify on its own thread and publishes\n"
      "tracked_objects, segments, ego_pose and health on DDS, watching the deadline\n"
      "(run.deadline_ms) and the inputs. The published tracks are classified before publication\n"
      "while the scan is younger than run.classify_budget_ms; the rest after it. Stops on\n"
      "Ctrl-C/SIGTERM, --seconds or --scans and prints a summary: scans, drops by cause, classes\n"
      "classified before and after publication, deadline misses, latencies (docs/run.md).\n"
      "SIGHUP reads the model file again and swaps it in between scans (same classes; health's\n"
      "model_hash says which model is in use; a bad file is refused and the model kept).");
  cmd->add_option("--config", o->config,
                  "configuration file (default: $STAC_CONFIG or config/stac.yaml)");
  cmd->add_option("--seconds", o->seconds, "stop after this many seconds")
      ->check(finite_range(0.001, 1e9));
  cmd->add_option("--scans", o->scans, "stop after this many scans are published")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--domain", o->domain, "DDS domain (default: dds.domain_id)")
      ->check(CLI::Range(0, 230));
  cmd->add_option("--point-cloud-stride", o->point_cloud_stride,
                  "publish point_cloud: every segment return and every Nth other one; 0: none "
                  "(default: dds.point_cloud_stride)")
      ->check(CLI::Range(0, 1000));
  cmd->add_option("--dds-config", o->dds_config, "Cyclone DDS XML (default: dds.config_file)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--port", o->port, "Velodyne UDP port (default: velodyne.port; 0: any free port)")
      ->check(CLI::Range(0, 65535));
  cmd->add_option("--bind", o->bind,
                  "Velodyne UDP address to bind (default: velodyne.bind_address)");
  cmd->add_option("--calib", o->calib, "calibration file (default: velodyne.calibration)");
  cmd->add_option(
      "--model", o->model,
      "track classifier model (`stac train`) or 'none' (default: classification.model)");
  cmd->add_option("--ins", o->ins, "INS transport: tcp, udp or none (default: run.ins)");
  cmd->add_option("--ins-address", o->ins_address,
                  "INS TCP server IPv4 address (default: run.ins_address)");
  cmd->add_option("--ins-port", o->ins_port, "INS port (default: es.ins_port)")
      ->check(CLI::Range(1, 65535));
  cmd->callback([o] {
    if (const int code = run_live(*o); code != 0) throw CLI::RuntimeError(code);
  });
}

}  // namespace stac::tools
