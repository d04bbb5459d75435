#include "runtime/component.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <pthread.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <thread>

#include "dds/domain.hpp"
#include "dds/idl_types.hpp"
#include "drivers/can/dbc.hpp"
#include "drivers/can/gs_usb_device.hpp"
#include "drivers/can/odometry.hpp"
#include "drivers/can/socketcan.hpp"
#include "drivers/velodyne/calibration.hpp"
#include "formats/model_file.hpp"
#include "rt/clock.hpp"
#include "rt/scheduling.hpp"
#include "runtime/live.hpp"
#include "settings/dds_settings.hpp"

namespace stac::runtime {
namespace {

// The main thread looks at the limits this often while nothing wakes it.
constexpr std::int64_t kControlNs = 20'000'000;

void start_thread(const Component::Live& live, const char* name, const rt::ThreadSchedule& s) {
  rt::name_thread(name);
  if (auto r = rt::apply_schedule(name, s); !r)
    std::fprintf(stderr, "%s: warning: %s\n", live.settings.name.c_str(),
                 r.error().message.c_str());
}

// Reads the model file again and hands it to perception through `next`, which holds it until
// perception took it; a refused file is counted and said on stderr, and `next` stays empty.
void reload(Component::Live& l, std::shared_ptr<const classification::TrackClassifierModel>& next) {
  std::string refused;
  auto m = l.model_path.empty() ? rt::Result<classification::TrackClassifierModel>(
                                      rt::make_error("no model file is configured"))
                                : formats::read_model_file(l.model_path);
  if (!m) {
    refused = m.error().message;
  } else if (l.pipeline->classifier() == nullptr || l.model == nullptr) {
    refused = "started without a model: restart with --model to classify";
  } else if (const std::string bad = l.pipeline->classifier()->check_swap(*m); !bad.empty()) {
    refused = l.model_path.string() + ": " + bad;
  }
  if (!refused.empty()) {
    l.counts.add(Count::kModelRefused);
    std::fprintf(stderr, "%s: SIGHUP: the model is kept: %s\n", l.settings.name.c_str(),
                 refused.c_str());
    return;
  }
  next = std::make_shared<const classification::TrackClassifierModel>(std::move(*m));
  l.model_handover.incoming_hash = classification::model_hash(*next);
  l.model_handover.incoming = next;
  l.model_handover.ready.store(true, std::memory_order_release);
}

void fill_summary(Component::Live& l, std::int64_t start_ns) {
  Summary& s = l.summary;
  const auto ms = [](std::int64_t ns) { return static_cast<double>(ns) * 1e-6; };
  const auto n = [&](Count c) { return l.counts.get(c); };
  l.watchdog.update(rt::monotonic_ns());  // stalls since the last published scan count too
  s.elapsed_s = static_cast<double>(rt::monotonic_ns() - start_ns) * 1e-9;
  s.stop_requested = l.stop_requested.load();
  const io::UdpReceiverCounters& rc = l.receiver->counters();
  const velodyne::AssemblerCounters& ac = l.stream->assembler().counters();
  s.received = rc.received;
  s.kernel_drops = rc.kernel_drops;
  s.truncated = rc.truncated;
  s.receive_errors = n(Count::kReceiveErrors);
  s.packets_lost = ac.packets_lost;
  s.wrong_size = n(Count::kWrongSize);
  s.invalid_block = n(Count::kInvalidBlock);
  s.duplicates = n(Count::kDuplicates);
  s.late_firings = n(Count::kLateFirings);
  s.other_model = n(Count::kOtherModel);
  s.scans = n(Count::kScans);
  s.published = n(Count::kPublished);
  s.incomplete = n(Count::kIncomplete);
  s.below_completeness = ac.below_completeness;
  s.min_completeness = l.settings.pipeline.velodyne.assembler.min_completeness;
  s.scan_slots_full = l.stream->scans_dropped();
  s.result_slots_full = l.results->dropped();
  s.publish_errors = n(Count::kPublishErrors);
  s.pool_overflow = l.pipeline->tracker().counters().pool_overflow;
  s.dropped_detections = l.pipeline->tracker().counters().dropped_detections;
  s.has_model = l.model != nullptr;
  s.model_hash = l.model_handover.hash.load();
  s.model_reloads = l.model_handover.reloads.load();
  s.model_refused = n(Count::kModelRefused);
  s.has_classifier = l.pipeline->classifier() != nullptr;
  s.classes_current = n(Count::kClassesCurrent);
  s.classes_late = n(Count::kClassesLate);
  s.classify_budget_ms = ms(l.settings.run.classify_budget_ns);
  const ego::EgoCounters& ec = l.estimator->counters();
  s.ins_fixes = ec.ins_fixes;
  s.dead_reckoned = ec.dead_reckoned;
  s.without_pose = l.pipeline->scans_without_pose();
  s.has_ins = l.inputs.ins();
  s.poses_rejected = l.history->rejected();
  s.ins_impossible = ec.impossible;
  s.time_jumps = ec.time_jumps;
  s.backward_jumps = ec.backward_jumps;
  s.ins_bad_checksum = n(Count::kInsBadChecksum);
  s.ins_bad_framing = n(Count::kInsBadFraming);
  s.ins_malformed = n(Count::kInsMalformed);
  s.ins_garbage_bytes = n(Count::kInsGarbageBytes);
  s.ins_connect_failures = n(Count::kInsConnectFailures);
  s.ins_disconnects = n(Count::kInsDisconnects);
  s.has_can = l.settings.can.has_value();
  if (s.has_can) {
    s.can_description = can_description(*l.settings.can);
    s.can = l.inputs.can_counters();
    s.can_ring_full = l.can_cells.ring_full.load();
  }
  for (std::size_t i = 0; i < s.inputs.size(); ++i) {
    s.inputs[i] = {kInputNames[i], rt::to_string(l.watchdog.status(i, rt::monotonic_ns()).state),
                   l.watchdog.stalls(i)};
  }
  const rt::DeadlineMonitor& m = *l.monitor;
  s.deadline_ms = ms(m.budget_ns());
  s.deadline_misses = m.misses();
  s.deadline_scans = m.end_to_end().count();
  s.latencies.clear();
  const auto row = [&](const char* name, const rt::LatencyHistogram& h) {
    s.latencies.push_back({name, ms(h.percentile(0.5)), ms(h.percentile(0.99)), ms(h.max_ns())});
  };
  for (std::size_t i = 0; i < kHealthStages; ++i) row(kStageNames[i], m.stage(i));
  row("end-to-end", m.end_to_end());
}

}  // namespace

rt::Result<ComponentSettings> load_component_settings(const std::filesystem::path& config) {
  ComponentSettings s;
  auto pipeline = settings::load_pipeline_settings(config);
  if (!pipeline) return rt::Unexpected<rt::Error>{pipeline.error()};
  s.pipeline = std::move(*pipeline);
  auto dds = settings::load_dds_settings(config);
  if (!dds) return rt::Unexpected<rt::Error>{dds.error()};
  s.dds = std::move(*dds);
  auto run = settings::load_run_settings(config);
  if (!run) return rt::Unexpected<rt::Error>{run.error()};
  s.run = std::move(*run);
  if (s.run.can) {
    auto c = settings::load_can_settings(config);
    if (!c) return rt::Unexpected<rt::Error>{c.error()};
    s.can = std::move(*c);
  }
  return s;
}

namespace {

// The unit's calibration file (the live component needs one: it does not wait for the stream's).
rt::Result<velodyne::Calibration> unit_calibration(const ComponentSettings& s) {
  const std::filesystem::path& file = s.pipeline.velodyne.calibration;
  if (file.empty()) {
    return rt::make_error("'velodyne.calibration': " + s.name +
                          " needs the unit's calibration file");
  }
  const settings::VelodyneSettings& vs = s.pipeline.velodyne;
  if (vs.model_auto) {
    return rt::make_error("'velodyne.model: auto' follows a capture's packets; " + s.name +
                          " decodes a live sensor from the first packet on and needs its model "
                          "named (" +
                          std::string(velodyne::model_names()) + ")");
  }
  auto c = velodyne::load_calibration(file);
  if (!c) return c;
  if (auto fits = velodyne::check_calibration_for(*c, vs.assembler.decoder.model); !fits)
    return rt::Unexpected<rt::Error>{fits.error()};
  return velodyne::lasers_of(*c, vs.assembler.decoder.model);
}

}  // namespace

namespace {

// Whether this machine has the IPv4 address the Velodyne receiver binds (0.0.0.0: every one): a
// UDP socket bound to it on port 0, so a running service's port is left alone.
rt::Status check_bind_address(const std::string& address) {
  sockaddr_in at{};
  at.sin_family = AF_INET;
  if (inet_pton(AF_INET, address.c_str(), &at.sin_addr) != 1)
    return rt::make_error("not a dotted IPv4 address");
  const int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return rt::make_error(std::string("no UDP socket: ") + std::strerror(errno));
  const int bound = ::bind(fd, reinterpret_cast<const sockaddr*>(&at), sizeof(at));
  const int error = errno;
  ::close(fd);
  if (bound != 0) return rt::make_error(std::strerror(error));
  return {};
}

}  // namespace

rt::Result<std::string> check_component_files(const ComponentSettings& s,
                                              const std::filesystem::path& config) {
  const settings::VelodyneSettings& vs = s.pipeline.velodyne;
  if (auto b = check_bind_address(vs.bind_address); !b) {
    return rt::make_error(config.string() + ": 'velodyne.bind_address' is '" + vs.bind_address +
                          "', which this machine cannot receive on (" + b.error().message +
                          "); give one of its addresses (`ip -4 addr`), or 0.0.0.0 for all");
  }
  auto calibration = unit_calibration(s);
  if (!calibration) return rt::Unexpected<rt::Error>{calibration.error()};
  auto model = formats::job_model(s.model, s.pipeline.classification.model);
  if (!model) return rt::Unexpected<rt::Error>{model.error()};
  std::string line = "calibration " + vs.calibration.string() + " (" +
                     std::to_string(calibration->num_lasers) + " lasers), ";
  line += *model != nullptr ? "model " + s.pipeline.classification.model.string()
                            : std::string("no model (tracks stay unclassified)");
  line += ", DDS domain " + std::to_string(s.dds.domain_id) + " with " +
          (s.dds.config_uri.empty() ? std::string("Cyclone's defaults") : s.dds.config_uri);
  if (s.run.can && s.can) {
    auto db = can::load_dbc(s.can->dbc);
    if (!db) return rt::Unexpected<rt::Error>{db.error()};
    // The signals the config names must be in it, as at start-up.
    auto decoder = can::OdometryDecoder::create(*db, s.can->signals);
    if (!decoder) return rt::Unexpected<rt::Error>{decoder.error()};
    line += ", CAN signals from " + s.can->dbc.string();
    if (s.can->transport == can::Transport::kSocketCan) {
      // The interface as SocketCanReader::open finds it.
      if (auto i = can::interface_index(s.can->socketcan.interface); !i) {
        return rt::make_error(config.string() + ": 'can.interface' is '" +
                              s.can->socketcan.interface +
                              "', which this machine does not have: " + i.error().message);
      }
      line += " on " + s.can->socketcan.interface;
    } else if (s.can->transport == can::Transport::kGsUsb) {
      // The adapter as GsUsbDevice::open finds it (opened for a moment, not claimed).
      if (auto present = can::GsUsbDevice::check_present(); !present) {
        return rt::make_error(config.string() +
                              ": 'can.transport' is gs_usb: " + present.error().message);
      }
      line += " on a gs_usb adapter";
    }
  } else {
    line += ", CAN off";
  }
  // The domain as the publisher makes it: Cyclone parses the XML and finds its interfaces.
  if (auto d = dds::check_domain(s.dds); !d) {
    return rt::make_error(config.string() + ": 'dds.config_file': " + d.error().message);
  }
  return line;
}

Component::Component(std::unique_ptr<Live> live) : live_(std::move(live)) {}
Component::~Component() = default;

rt::Result<std::unique_ptr<Component>> Component::create(const ComponentSettings& settings) {
  auto live = std::make_unique<Live>();
  Live& l = *live;
  l.settings = settings;
  ComponentSettings& s = l.settings;
  settings::VelodyneSettings& vs = s.pipeline.velodyne;
  settings::EgoSettings& es = s.pipeline.ego;
  const settings::RunSettings& rs = s.run;
  auto calibration = unit_calibration(s);
  if (!calibration) return rt::Unexpected<rt::Error>{calibration.error()};
  l.calibration = std::move(*calibration);

  // Start-up: every allocation of the run happens from here to the threads' start.
  if (rs.lock_memory) {
    if (auto r = rt::lock_memory(); !r)
      std::fprintf(stderr, "%s: warning: %s\n", s.name.c_str(), r.error().message.c_str());
  }
  auto model = formats::job_model(s.model, s.pipeline.classification.model);
  if (!model) return rt::Unexpected<rt::Error>{model.error()};
  l.model = *model;
  l.model_path = !s.model.empty() && s.model != "none" ? std::filesystem::path(s.model)
                                                       : s.pipeline.classification.model;
  const pipeline::PipelineConfig pc{.deskew = es.deskew,
                                    .segmenter = s.pipeline.segmenter,
                                    .tracker = s.pipeline.tracker,
                                    .classifier = s.pipeline.classification.classifier,
                                    .model = l.model,
                                    .describe = false,
                                    .split_classification = true,
                                    .publish_tentative = s.dds.tentative_tracks,
                                    .trailer = velodyne::traits(vs.assembler.decoder.model).trailer,
                                    .cloud_stride = s.dds.point_cloud_stride,
                                    .cloud_max_points = dds::kMaxCloudPoints,
                                    .clock = pipeline::StageClock::kMonotonic};
  if (auto r = dds::ScanPublishing::check_capacities(pc); !r)
    return rt::Unexpected<rt::Error>{r.error()};
  auto receiver = io::UdpReceiver::open({.bind_address = vs.bind_address,
                                         .port = vs.port,
                                         .receive_buffer_bytes = vs.receive_buffer_bytes,
                                         .sender_address = vs.sender_address,
                                         .batch = 32,
                                         .max_payload = 2048});
  if (!receiver) return rt::Unexpected<rt::Error>{receiver.error()};
  l.receiver.emplace(std::move(*receiver));
  if (rs.ins == settings::InsTransport::kTcp) {
    auto c = applanix::TcpClient::open({.address = rs.ins_address, .port = es.ins_port});
    if (!c) return rt::Unexpected<rt::Error>{c.error()};
    l.inputs.tcp.emplace(std::move(*c));
  } else if (rs.ins == settings::InsTransport::kUdp) {
    auto u = applanix::UdpListener::open({.bind_address = "0.0.0.0",
                                          .port = es.ins_port,
                                          .receive_buffer_bytes = 1 << 20,
                                          .sender_address = "",
                                          .batch = 32,
                                          .max_payload = 8192});
    if (!u) return rt::Unexpected<rt::Error>{u.error()};
    l.inputs.udp.emplace(std::move(*u));
  }
  if (s.can) {
    if (auto r = open_can(*s.can, l.inputs); !r) return rt::Unexpected<rt::Error>{r.error()};
    es.estimator.odometry = s.can->dead_reckoning;
  }
  // The writers last: a reader that sees them matched may send at once, and the inputs are open.
  auto publisher = dds::Publisher::create(s.dds);
  if (!publisher) return rt::Unexpected<rt::Error>{publisher.error()};
  l.publisher = std::move(*publisher);
  l.frame.emplace(es.origin);
  l.history.emplace(es.history);
  l.estimator.emplace(es.estimator, *l.frame, *l.history);
  l.stream.emplace(l.calibration, vs.assembler, static_cast<std::size_t>(vs.scan_slots));
  l.pipeline.emplace(pc);
  l.results.emplace(rs.result_slots, [&] { return Frame{l.pipeline->make_result()}; });
  l.scan_publishing.emplace(*l.publisher, s.dds.tentative_tracks,
                            dds::ScanPublishing::classes_of(pc));
  l.monitor.emplace(rs.deadline, kHealthStages);
  l.watchdog.start(
      {rs.velodyne_timeout_ns, l.inputs.ins() ? es.estimator.ins_timeout_ns : std::int64_t{0},
       s.can ? s.can->dead_reckoning.stale_timeout_ns : std::int64_t{0}, std::int64_t{0}},
      rt::monotonic_ns());
  if (l.model != nullptr) l.model_handover.hash = classification::model_hash(*l.model);
  l.can_report.emplace(CanReport{l.watchdog, kCan, l.can_cells});
  l.summary.latencies.reserve(kHealthStages + 1);
  std::fprintf(stderr, "%s: Velodyne UDP %s:%u, INS %s, CAN %s, DDS domain %u; Ctrl-C stops\n",
               s.name.c_str(), vs.bind_address.c_str(), l.receiver->port(),
               rs.ins == settings::InsTransport::kTcp
                   ? (rs.ins_address + ":" + std::to_string(es.ins_port) + " (tcp)").c_str()
               : rs.ins == settings::InsTransport::kUdp
                   ? ("udp port " + std::to_string(es.ins_port)).c_str()
                   : "none (parked sensor)",
               s.can ? can_description(*s.can).c_str() : "none", s.dds.domain_id);
  return std::unique_ptr<Component>(new Component(std::move(live)));
}

void Component::run() {
  Live& l = *live_;
  const settings::RunSettings& rs = l.settings.run;
  std::optional<rt::CpuLatencyRequest> cpu_latency;  // held while the run lasts
  if (rs.cpu_wake_latency_us >= 0) {
    if (auto r = rt::CpuLatencyRequest::hold(rs.cpu_wake_latency_us); r) {
      cpu_latency.emplace(std::move(*r));
    } else {
      std::fprintf(stderr, "%s: warning: %s\n", l.settings.name.c_str(), r.error().message.c_str());
    }
  }
  // The worker threads start with SIGINT, SIGTERM and SIGHUP blocked, so only the caller's thread
  // takes them (no receive call is interrupted).
  sigset_t signals, previous;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGHUP);
  pthread_sigmask(SIG_BLOCK, &signals, &previous);
  std::thread receiver([&] {
    start_thread(l, "receiver", rs.receiver);
    receiver_loop(l);
  });
  std::thread can_thread;
  if (l.inputs.gs_usb) {
    can_thread = std::thread([&] {
      start_thread(l, "can", rs.pose);  // the pose thread's priority and CPU
      (void)read_can_until_end(*l.inputs.gs_usb, *l.inputs.odometry, *l.can_report);
      l.inputs.can_done.store(true, std::memory_order_release);
    });
  }
  std::thread pose;
  if (l.inputs.ins() || l.inputs.can()) {
    pose = std::thread([&] {
      start_thread(l, "pose", rs.pose);
      pose_loop(l);
    });
  }
  std::thread perception([&] {
    start_thread(l, "perception", rs.perception);
    perception_loop(l);
  });
  std::thread publisher([&] {
    start_thread(l, "publisher", rs.publisher);
    publisher_loop(l);
  });
  pthread_sigmask(SIG_SETMASK, &previous, nullptr);

  // Until a stop: stop(), the time limit or the scan limit; model reloads on the way.
  const std::int64_t start = rt::monotonic_ns();
  std::shared_ptr<const classification::TrackClassifierModel> next_model;
  for (;;) {
    const std::uint32_t seen = l.control.generation();
    if (l.stop_requested.load()) break;
    if (next_model != nullptr && !l.model_handover.ready.load(std::memory_order_acquire)) {
      l.model = std::move(next_model);  // swapped in: the old one is freed here
      next_model = nullptr;
      std::fprintf(stderr, "%s: model %s (%016llx) in use\n", l.settings.name.c_str(),
                   l.model_path.c_str(),
                   static_cast<unsigned long long>(l.model_handover.incoming_hash));
    }
    if (next_model == nullptr && l.reload_requested.exchange(false)) reload(l, next_model);
    const std::int64_t elapsed = rt::monotonic_ns() - start;
    if (l.settings.stop_after_s > 0 &&
        static_cast<double>(elapsed) * 1e-9 >= l.settings.stop_after_s)
      break;
    if (l.settings.stop_after_scans > 0 &&
        l.counts.get(Count::kPublished) >= l.settings.stop_after_scans)
      break;
    l.control.wait(seen, kControlNs);
  }
  l.stopping.store(true, std::memory_order_release);
  l.inputs.stop();
  receiver.join();
  if (can_thread.joinable()) can_thread.join();
  if (pose.joinable()) pose.join();
  perception.join();
  publisher.join();
  fill_summary(l, start);
}

void Component::stop() noexcept {
  live_->stop_requested.store(true);
  live_->control.notify();
}

void Component::reload_model() noexcept {
  live_->reload_requested.store(true);
  live_->control.notify();
}

const Summary& Component::summary() const noexcept {
  return live_->summary;
}

std::uint16_t Component::lidar_port() const noexcept {
  return live_->receiver->port();
}

namespace {
Component* g_signalled = nullptr;  // run_with_signals' component while it runs
void on_stop(int) {
  if (g_signalled != nullptr) g_signalled->stop();
}
void on_reload(int) {
  if (g_signalled != nullptr) g_signalled->reload_model();
}
}  // namespace

void run_with_signals(Component& component) {
  g_signalled = &component;
  struct sigaction stop {};
  stop.sa_handler = on_stop;
  struct sigaction reload {};
  reload.sa_handler = on_reload;
  struct sigaction old_int {
  }, old_term{}, old_hup{};
  sigaction(SIGINT, &stop, &old_int);
  sigaction(SIGTERM, &stop, &old_term);
  sigaction(SIGHUP, &reload, &old_hup);
  component.run();
  sigaction(SIGINT, &old_int, nullptr);
  sigaction(SIGTERM, &old_term, nullptr);
  sigaction(SIGHUP, &old_hup, nullptr);
  g_signalled = nullptr;
}

}  // namespace stac::runtime
