// The live component (docs/run.md): the HDL-64E's UDP packets, the Applanix INS and the vehicle
// CAN bus in; deskewed, segmented, tracked and classified scans out on DDS, with the deadline and
// the inputs watched and published as health. Threads (docs/architecture.md):
//   receiver   UdpReceiver (Velodyne) -> ScanStream slots                      receiver_loop.cpp
//   pose       Applanix (TCP or UDP) and SocketCAN (or the can thread's ring)
//              -> EgoEstimator -> PoseHistory                                  pose_loop.cpp
//   can        gs_usb only: blocking libusb reads -> odometry ring -> pose      can_input.hpp
//   perception ScanStream -> ScanPipeline -> result slots                      perception_loop.cpp
//   publisher  result slots -> DDS topics and health                           publisher_loop.cpp
// Everything is allocated by create(); run() starts the threads and returns once stopped, after
// perception and the publisher drained what was received.
#pragma once

#include <array>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "dds/publisher.hpp"
#include "drivers/can/config.hpp"
#include "drivers/can/odometry_input.hpp"
#include "rt/expected.hpp"
#include "settings/run_settings.hpp"
#include "settings/settings.hpp"

namespace stac::runtime {

struct ComponentSettings {
  settings::PipelineSettings pipeline{};
  dds::PublisherConfig dds;
  settings::RunSettings run{};
  std::optional<can::CanConfig> can;  // when run.can
  // The track classifier: a model file, "none", or empty for classification.model. SIGHUP (or
  // reload_model()) reads the same file again.
  std::string model;
  double stop_after_s = 0;             // > 0: run() stops by itself after this long
  std::uint64_t stop_after_scans = 0;  // > 0: ... once this many scans are published
  std::string name = "stac run";       // how messages on stderr begin
};

// The config file's sections the component reads (velodyne, ego, segmentation, tracking,
// classification, dds, run and, when run.can, can); the first error names file and key.
rt::Result<ComponentSettings> load_component_settings(const std::filesystem::path& config);

// `stac-node --check` of the settings loaded from `config` (which parsing checked the addresses
// of): loads every file Component::create would (the calibration, the model and, with run.can,
// the DBC and its signals), finds the SocketCAN interface, and creates the DDS domain with the
// Cyclone XML as the publisher does, then deletes it (Cyclone opens its sockets; no participant,
// so nothing is announced). Returns a line saying what was loaded, or the first error, naming
// `config` and the key.
rt::Result<std::string> check_component_files(const ComponentSettings& settings,
                                              const std::filesystem::path& config);

// What a run did: counts by cause and latencies (ms), as the summary prints them.
struct Summary {
  struct Latency {
    const char* name = "";
    double p50_ms = 0, p99_ms = 0, max_ms = 0;
  };
  struct Input {
    const char* name = "";
    const char* state = "";
    std::uint64_t stalls = 0;
  };
  double elapsed_s = 0;
  bool stop_requested = false;  // stop() ended the run (a signal), not a limit
  std::uint64_t received = 0, kernel_drops = 0, truncated = 0, receive_errors = 0;
  std::uint64_t packets_lost = 0, wrong_size = 0, invalid_block = 0, duplicates = 0;
  std::uint64_t other_model = 0;  // packets whose bytes name another model (decoded as set)
  std::uint64_t late_firings = 0;
  std::uint64_t scans = 0, published = 0, incomplete = 0, below_completeness = 0;
  double min_completeness = 0;
  std::uint64_t scan_slots_full = 0, result_slots_full = 0, publish_errors = 0;
  std::uint64_t pool_overflow = 0, dropped_detections = 0;
  bool has_model = false;
  std::uint64_t model_hash = 0, model_refused = 0;
  std::uint32_t model_reloads = 0;
  bool has_classifier = false;
  std::uint64_t classes_current = 0, classes_late = 0;
  double classify_budget_ms = 0;
  std::uint64_t ins_fixes = 0, dead_reckoned = 0, without_pose = 0;
  bool has_ins = false;
  std::uint64_t poses_rejected = 0, ins_impossible = 0, time_jumps = 0, backward_jumps = 0;
  std::uint64_t ins_bad_checksum = 0, ins_bad_framing = 0, ins_malformed = 0;
  std::uint64_t ins_garbage_bytes = 0, ins_connect_failures = 0, ins_disconnects = 0;
  bool has_can = false;
  std::string can_description;
  can::CanInputCounters can;
  std::uint64_t can_ring_full = 0;
  std::array<Input, 3> inputs{};
  double deadline_ms = 0;
  std::uint64_t deadline_misses = 0, deadline_scans = 0;
  std::vector<Latency> latencies;  // each health stage, then end-to-end
};
void print_summary(const Summary& summary, const std::string& name, std::FILE* out);
// The same summary as JSON (every count of print_summary's, grouped as it groups them), for
// programs that read it (`stac run --summary-json`, `stac demo`) instead of parsing the text.
std::string summary_json(const Summary& summary);

class Component {
 public:
  // Opens the sockets, the DDS participant and the CAN device, reads the calibration and the
  // model, and allocates every buffer of the run. Fails with a message naming what to fix.
  static rt::Result<std::unique_ptr<Component>> create(const ComponentSettings& settings);
  ~Component();
  Component(const Component&) = delete;
  Component& operator=(const Component&) = delete;

  // Runs until stop() (or the settings' limits); then stops the inputs, lets perception and the
  // publisher drain, and joins every thread.
  void run();
  // Any thread or a signal handler (async-signal-safe): ends run().
  void stop() noexcept;
  // Any thread or a signal handler (async-signal-safe): read the model file again and swap it in
  // between scans (the same classes; a bad file is refused, counted, and the model kept).
  void reload_model() noexcept;

  // What the last run() did (after it returned).
  [[nodiscard]] const Summary& summary() const noexcept;
  // The Velodyne UDP port bound (the configured one, or the kernel's choice for port 0).
  [[nodiscard]] std::uint16_t lidar_port() const noexcept;

  struct Live;  // the run's state (runtime/live.hpp)

 private:
  explicit Component(std::unique_ptr<Live> live);
  std::unique_ptr<Live> live_;
};

// Runs `component` with SIGINT and SIGTERM calling stop() and SIGHUP reload_model(), as the
// process's handlers until it returns (one component at a time).
void run_with_signals(Component& component);

}  // namespace stac::runtime
