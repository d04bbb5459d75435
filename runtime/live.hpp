// The state of one run of the live component, shared by its thread loops (one file each) and
// built whole by Component::create(). Internal to runtime/.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "dds/publisher.hpp"
#include "dds/scan_publishing.hpp"
#include "drivers/applanix/tcp_client.hpp"
#include "drivers/applanix/udp_listener.hpp"
#include "drivers/can/odometry_input.hpp"
#include "drivers/io/udp_receiver.hpp"
#include "drivers/velodyne/calibration.hpp"
#include "drivers/velodyne/scan_stream.hpp"
#include "ego/ego_estimator.hpp"
#include "pipeline/scan_pipeline.hpp"
#include "rt/counters.hpp"
#include "rt/deadline_monitor.hpp"
#include "rt/slot_exchange.hpp"
#include "rt/spsc_ring.hpp"
#include "rt/wakeup.hpp"
#include "rt/watchdog.hpp"
#include "runtime/can_input.hpp"
#include "runtime/component.hpp"

namespace stac::runtime {

enum Input : std::size_t { kLidar, kIns, kCan };
inline constexpr const char* kInputNames[] = {"lidar", "ins", "can"};

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
inline constexpr const char* kStageNames[] = {
    "wait", "deskew", "segment", "track", "classify", "classify_deferred", "handover", "publish"};

// What the threads count for health and the summary (each counter written by one thread).
enum class Count : std::size_t {
  kPackets,        // receiver: datagrams read
  kReceiveErrors,  // receiver: failed reads
  kKernelDrops,    // receiver: the socket's drops (copied from the receiver's counters)
  kWrongSize,      // receiver: the decoder's refusals (AssemblerCounters) ...
  kInvalidBlock,
  kDuplicates,
  kLateFirings,
  kOtherModel,      // receiver: packets whose bytes name another model (decoded as configured)
  kInsBadChecksum,  // pose: the INS parser's (ParserCounters) and the TCP connection's
  kInsBadFraming,   //   length, terminator, oversize, truncated
  kInsMalformed,
  kInsGarbageBytes,
  kInsConnectFailures,
  kInsDisconnects,  //   disconnects, stalls and streams without a message
  kScans,           // perception: complete scans processed
  kIncomplete,      // perception: scans not processed (incomplete)
  kPacketsLost,     // perception: packets lost on the wire, of every scan taken (azimuth steps)
  kClassesCurrent,  // perception: published tracks classified before / after publication
  kClassesLate,
  kPublished,      // publisher: scans published
  kPublishErrors,  // publisher: DDS write failures
  kModelRefused,   // main: model reloads refused
  kCount
};

// One perception result in a slot of the perception -> publisher exchange.
struct Frame {
  pipeline::ScanResult result;
  std::int64_t last_firing_ns = 0;     // receive clock (CLOCK_REALTIME, kernel stamps)
  std::int64_t started_ns = 0;         // perception took the scan
  std::int64_t finished_ns = 0;        // perception pushed the result
  std::uint64_t segment_overflow = 0;  // cumulative, as seen by perception at this scan
  std::uint64_t without_pose = 0;      // scans not deskewed (no pose at their time)
  std::uint64_t classes_late = 0;      // published tracks classified after publication (budget)
};

// Odometry updates in flight from the can thread to the pose thread, which drains them every
// 5 ms or sooner: 1024 are 50 ms of a 1 Mbit/s bus full of the shortest frames (about 20,000/s),
// ten drain periods. Full: the newest update is dropped and counted (can.overflow).
inline constexpr std::size_t kOdometryRing = 1024;

// The pose thread's inputs (and the can thread's), opened by create().
struct PoseInputs {
  std::optional<applanix::TcpClient> tcp;
  std::optional<applanix::UdpListener> udp;
  // can.transport: socketcan or cannelloni, polled by the pose thread between its INS reads.
  std::optional<can::OdometryInput<can::SocketCanReader>> socketcan;
  std::optional<can::OdometryInput<can::CannelloniReader>> cannelloni;
  // can.transport: gs_usb, read by the can thread into `odometry`, which the pose thread drains.
  std::optional<can::OdometryInput<can::GsUsbDevice>> gs_usb;
  std::optional<rt::SpscRing<can::OdometryUpdate>> odometry;
  std::atomic<bool> can_done{false};  // the can thread ended (stopped, or the adapter is gone)
  [[nodiscard]] bool ins() const { return tcp || udp; }
  [[nodiscard]] bool can() const { return socketcan || cannelloni || gs_usb; }
  [[nodiscard]] can::CanInputCounters can_counters() const;  // once the readers ended
  void stop();
};

// A model handed from the main thread to perception (reload_model()): main fills `incoming` and
// sets `ready`; perception swaps it in between scans and clears `ready`. Main then drops the old
// model (never freed on the perception thread).
struct ModelHandover {
  std::atomic<bool> ready{false};
  std::shared_ptr<const classification::TrackClassifierModel> incoming;
  std::uint64_t incoming_hash = 0;  // main's, with `incoming`
  std::atomic<std::uint64_t> hash{0};
  std::atomic<std::uint32_t> reloads{0};
};

struct Component::Live {
  ComponentSettings settings;
  velodyne::Calibration calibration;
  std::filesystem::path model_path;                                   // the file a reload reads
  std::shared_ptr<const classification::TrackClassifierModel> model;  // in use (main's)
  std::unique_ptr<dds::Publisher> publisher;
  std::optional<io::UdpReceiver> receiver;
  PoseInputs inputs;
  std::optional<ego::LocalFrame> frame;
  std::optional<ego::PoseHistory> history;
  std::optional<ego::EgoEstimator> estimator;
  std::optional<velodyne::ScanStream> stream;
  std::optional<pipeline::ScanPipeline> pipeline;
  std::optional<rt::SlotExchange<Frame>> results;
  std::optional<dds::ScanPublishing> scan_publishing;
  std::optional<rt::DeadlineMonitor> monitor;
  rt::Watchdog watchdog;
  rt::Counters<Count> counts;
  CanCounterCells can_cells;
  std::optional<CanReport> can_report;
  ModelHandover model_handover;
  std::atomic<ego::EgoSource> ego_source{ego::EgoSource::kNone};  // the newest pose's
  // Stop: requested (stop() or a limit); the receiver drains its socket first, then each thread
  // ends once the one before it is done.
  std::atomic<bool> stopping{false}, stop_requested{false}, reload_requested{false};
  std::atomic<bool> receiver_done{false}, perception_done{false};
  rt::Wakeup scans_ready;    // receiver -> perception: a scan (or the receiver's end)
  rt::Wakeup results_ready;  // perception -> publisher: a result (or perception's end)
  rt::Wakeup control;        // -> the main thread: stop or reload requested
  Summary summary;
};

// The thread loops (each in its own file).
void receiver_loop(Component::Live& live) noexcept;
void pose_loop(Component::Live& live) noexcept;
void perception_loop(Component::Live& live) noexcept;
void publisher_loop(Component::Live& live) noexcept;
// Opens the configured CAN transport into live.inputs.
rt::Status open_can(can::CanConfig& config, PoseInputs& inputs);
std::string can_description(const can::CanConfig& c);

}  // namespace stac::runtime
