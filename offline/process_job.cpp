// The offline process job (process_job.hpp): the options read, the drive opened, each scan through
// the pipeline and into the tracks file (and pictures, and DDS), the summary.
#include "offline/process_job.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include "dds/idl_types.hpp"
#include "dds/scan_publishing.hpp"
#include "drivers/io/pcap_reader.hpp"
#include "drivers/velodyne/scan_stream.hpp"
#include "evaluation/tracks_jsonl.hpp"
#include "evaluation/truth_composition.hpp"
#include "formats/capture_input.hpp"
#include "formats/capture_poses.hpp"
#include "formats/capture_sensor.hpp"
#include "formats/kitti_raw.hpp"
#include "formats/model_file.hpp"
#include "formats/recorded_drive.hpp"
#include "pictures/birds_eye.hpp"
#include "pipeline/scan_pipeline.hpp"
#include "rt/clock.hpp"
#include "rt/formatted.hpp"
#include "settings/dds_settings.hpp"
#include "settings/settings.hpp"

namespace stac::offline {

using namespace stac::settings;
using namespace stac::formats;
namespace {

// --dds: the publishing edge, created before the loop; with --dds-wait, waits for a reader.
struct ProcessDds {
  std::unique_ptr<dds::Publisher> publisher;
  std::optional<dds::ScanPublishing> scans;
};
rt::Result<ProcessDds> open_dds(const dds::PublisherConfig& settings, const ProcessJobOptions& o,
                                const pipeline::PipelineConfig& pc) {
  if (auto r = dds::ScanPublishing::check_capacities(pc); !r)
    return rt::Unexpected<rt::Error>{r.error()};
  auto p = dds::Publisher::create(settings);
  if (!p) return rt::Unexpected<rt::Error>{p.error()};
  ProcessDds out{std::move(*p), std::nullopt};
  out.scans.emplace(*out.publisher, settings.tentative_tracks, dds::ScanPublishing::classes_of(pc));
  const dds_entity_t writer = out.publisher->writer(dds::Topic::kTrackedObjects);
  for (double waited = 0; waited < o.dds_wait_s; waited += 0.01) {
    dds_publication_matched_status_t m{};
    if (dds_get_publication_matched_status(writer, &m) == 0 && m.current_count > 0) break;
    dds_sleepfor(DDS_MSECS(10));
  }
  return out;
}

struct Stage {
  const char* name;
  std::vector<double> ms;
};

std::string stats_table(const std::vector<Stage>& stages) {
  std::string text = rt::formatted("  %-17s %9s %9s %9s   (CPU ms per scan, one core)\n", "stage",
                                   "median", "p99", "max");
  for (const Stage& s : stages) {
    if (s.ms.empty()) continue;
    std::vector<double> v = s.ms;
    std::sort(v.begin(), v.end());
    const auto at = [&](double q) {
      return v[std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size())))];
    };
    text += rt::formatted("  %-17s %9.3f %9.3f %9.3f\n", s.name, at(0.5), at(0.99), v.back());
  }
  return text;
}

// One scan from above in its vehicle frame at the scan's start: the points by height, the
// segments (grey), the confirmed tracks (orange, with id and class) and the coasting ones (blue).
rt::Status save_scan_picture(const std::filesystem::path& png, const velodyne::Scan& scan,
                             const pipeline::ScanResult& r,
                             const classification::ClassNames& classes, const std::string& legend) {
  pictures::BirdsEye view(pictures::BirdsEyeOptions{});
  const Eigen::Isometry3d vehicle_T_world = r.world_T_vehicle_start.inverse();
  const Eigen::Isometry3d vehicle_T_sensor = vehicle_T_world * r.world_T_sensor;
  const double yaw0 = pipeline::yaw_of(r.world_T_vehicle_start.linear());
  for (const velodyne::Point& p : scan.points) {
    const Eigen::Vector3d v = vehicle_T_sensor * Eigen::Vector3d(p.x, p.y, p.z);
    view.add_point(static_cast<float>(v.x()), static_cast<float>(v.y()),
                   static_cast<float>(v.z() - vehicle_T_sensor.translation().z()));
  }
  const auto box = [&](double x, double y, double length, double width, double yaw,
                       pictures::Bgr colour) {
    Eigen::Vector3d c = vehicle_T_world * Eigen::Vector3d(x, y, 0);
    view.add_box(static_cast<float>(c.x()), static_cast<float>(c.y()), static_cast<float>(length),
                 static_cast<float>(width), static_cast<float>(yaw - yaw0), colour);
    return c;
  };
  for (std::size_t i = 0; i < r.segments.segments.size(); ++i) {
    const pipeline::WorldBox b = r.world_box(i);
    (void)box(b.x, b.y, b.length, b.width, b.yaw, pictures::Bgr{150, 150, 150});
  }
  for (std::size_t i = 0; i < r.tracked.tracks.size(); ++i) {
    const tracking::Track& t = r.tracked.tracks[i];
    if (t.state == tracking::TrackState::kTentative) continue;
    const bool confirmed = t.state == tracking::TrackState::kConfirmed;
    const pictures::Bgr colour =
        confirmed ? pictures::Bgr{0, 140, 255} : pictures::Bgr{255, 120, 0};
    const Eigen::Vector3d c = box(t.position.x(), t.position.y(), t.length, t.width, t.yaw, colour);
    // Named when the class is one of the model's (background tracks only boxed: a street holds
    // many).
    const bool classified = i < r.classes.size() && r.classes[i].classified;
    const std::string name =
        classified ? classification::class_name(classes, r.classes[i].label) : "";
    if (classified && name == "background") continue;
    // (appended, not one `+` expression: GCC 12's -Wrestrict misfires on that one inlined here)
    std::string text = "#";
    text += std::to_string(t.id);
    if (!name.empty()) text.append(" ").append(name);
    view.add_label(static_cast<float>(c.x()), static_cast<float>(c.y()), text, colour);
  }
  view.add_legend(legend);
  view.add_legend("segments grey, confirmed tracks orange, coasting blue");
  return view.save(png);
}

}  // namespace

rt::Status run_process_job(const ProcessJobOptions& o, const JobOutput& output) {
  const auto say = [&](const std::string& text) { output.say(text); };
  const std::filesystem::path config = config_path(o.config);
  auto settings = load_pipeline_settings(config);
  if (!settings) return rt::make_error(settings.error().message);
  VelodyneSettings& vs = settings->velodyne;
  EgoSettings& ego_settings = settings->ego;

  // The truth (for segmentation metrics) and the frame it is written in.
  std::vector<evaluation::TruthScanRecord> truth;
  if (!o.truth.empty()) {
    auto t = evaluation::read_truth_file(o.truth);
    if (!t) return rt::make_error(t.error().message);
    truth = std::move(*t);
    if (!truth.empty() && truth.front().origin && !ego_settings.origin) {
      const auto& g = *truth.front().origin;
      ego_settings.origin = ego::Geodetic{g[0], g[1], g[2]};
    }
  }
  if (!o.origin.empty()) {
    auto g = parse_origin(o.origin);
    if (!g) return rt::make_error(g.error().message);
    ego_settings.origin = *g;
  }
  // A KITTI raw drive folder, or a capture: its sensor, calibration and poses.
  auto recorded = RecordedDrive::open(o.in, *settings, {o.calib, o.sensor, !o.no_deskew});
  if (!recorded) return rt::make_error(recorded.error().message);
  const KittiRawDrive* drive = recorded->kitti();
  const CapturePoses* poses = recorded->poses();
  if (!o.pictures.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(o.pictures, ec);
    if (ec)
      return rt::make_error(o.pictures + ": cannot create the pictures folder: " + ec.message());
  }
  auto model = job_model(o.model, settings->classification.model);
  if (!model) return rt::make_error(model.error().message);
  const classification::ClassNames model_classes =
      *model ? (*model)->classes : classification::ClassNames{};
  std::ofstream out(o.tracks);
  if (!out) return rt::make_error(o.tracks + ": cannot create the tracks file");

  // The frame the tracks are written in (recorded on every line, so stac eval can compare).
  evaluation::TracksFrame frame = evaluation::TracksFrame::kVehicle;
  std::array<double, 3> frame_origin{};
  if (poses && poses->frame->anchored()) {
    const ego::Geodetic g = poses->frame->origin();
    frame = evaluation::TracksFrame::kEnu;
    frame_origin = {g.lat_deg, g.lon_deg, g.alt_m};
  }

  // Everything the per-scan loop uses is allocated here.
  pipeline::PipelineConfig pc = evaluation::offline_pipeline_config(*settings, *model);
  // The classification in stac run's two steps, one right after the other (the same classes as
  // in one): the tracks it publishes, then the others and the accumulated clouds.
  pc.split_classification = true;
  std::optional<dds::PublisherConfig> dds_settings;  // --dds: the config's dds:, with the options
  if (o.dds) {
    auto ds = load_dds_settings(config);
    if (!ds) return rt::make_error(ds.error().message);
    override_dds(*ds, o.domain, o.dds_config);
    if (o.point_cloud_stride >= 0)
      ds->point_cloud_stride = static_cast<std::uint32_t>(o.point_cloud_stride);
    dds_settings = std::move(*ds);
    pc.cloud_stride = dds_settings->point_cloud_stride;  // as stac run publishes the cloud
    pc.publish_tentative = dds_settings->tentative_tracks;
    pc.cloud_max_points = dds::kMaxCloudPoints;
  }
  pipeline::ScanPipeline pipeline(pc);
  pipeline::ScanResult result = pipeline.make_result();
  std::optional<ProcessDds> dds_out;
  if (dds_settings) {
    auto d = open_dds(*dds_settings, o, pc);
    if (!d) return rt::make_error(d.error().message);
    dds_out.emplace(std::move(*d));
  }
  std::uint64_t dds_errors = 0;

  // seg+track: the two stages of issue 5's per-scan budget, summed per scan.
  // classify: the tracks stac run publishes (before publication there); classify_deferred: the
  // others and the tracks' accumulated clouds (after it).
  std::vector<Stage> stages{
      {"decode", {}},    {"deskew", {}},   {"segment", {}},           {"track", {}},
      {"seg+track", {}}, {"classify", {}}, {"classify_deferred", {}}, {"total", {}}};
  std::uint64_t scans = 0, truth_matched = 0;
  std::size_t truth_next = 0;
  std::string line;
  std::int64_t decode_ns = 0;
  std::string picture_error;

  auto handle = [&](velodyne::Scan& scan) {
    pipeline.process(scan, recorded->pose_history(), result);
    const std::int64_t finish_start = rt::thread_cpu_ns();
    pipeline.finish_scan(scan);
    const std::int64_t finish_ns = rt::thread_cpu_ns() - finish_start;
    // Offline nothing waits: every track's class after both steps (the tentative ones too).
    if (pipeline.classifier() != nullptr)
      pipeline.classifier()->report(result.tracked, result.classes);
    const std::int64_t* ns = result.stage_ns;
    stages[0].ms.push_back(static_cast<double>(decode_ns) * 1e-6);
    stages[1].ms.push_back(static_cast<double>(ns[pipeline::kDeskew]) * 1e-6);
    stages[2].ms.push_back(static_cast<double>(ns[pipeline::kSegment]) * 1e-6);
    stages[3].ms.push_back(static_cast<double>(ns[pipeline::kTrack]) * 1e-6);
    stages[4].ms.push_back(static_cast<double>(ns[pipeline::kSegment] + ns[pipeline::kTrack]) *
                           1e-6);
    if (pipeline.classifier() != nullptr) {
      stages[5].ms.push_back(static_cast<double>(ns[pipeline::kClassify]) * 1e-6);
      stages[6].ms.push_back(static_cast<double>(finish_ns) * 1e-6);
    }
    stages[7].ms.push_back(static_cast<double>(decode_ns + ns[pipeline::kDeskew] +
                                               ns[pipeline::kSegment] + ns[pipeline::kTrack] +
                                               ns[pipeline::kClassify] + finish_ns) *
                           1e-6);
    decode_ns = 0;

    // The record (outside the timed stages).
    const Eigen::Isometry3d& start = result.world_T_vehicle_start;
    evaluation::TracksScan rec;
    rec.frame = frame;
    rec.origin = frame_origin;
    rec.scan = result.sequence;
    rec.stamp_ns = result.stamp_ns;
    rec.ego = {start.translation().x(), start.translation().y(), start.translation().z(),
               pipeline::yaw_of(start.linear())};
    rec.segments.resize(result.segments.segments.size());
    for (std::size_t i = 0; i < result.segments.segments.size(); ++i) {
      const pipeline::WorldBox b = result.world_box(i);
      rec.segments[i] = {static_cast<std::uint32_t>(i),
                         result.segments.segments[i].count,
                         b.x,
                         b.y,
                         b.z,
                         b.length,
                         b.width,
                         b.height,
                         b.yaw,
                         {},
                         false};
    }
    for (std::size_t i = 0; i < result.tracked.tracks.size(); ++i) {
      evaluation::TrackRecord& r =
          rec.tracks.emplace_back(evaluation::track_record(result.tracked.tracks[i]));
      if (i < result.classes.size() && result.classes[i].classified) {
        const classification::TrackClass& c = result.classes[i];
        r.classified = true;
        r.cls = classification::class_name(model_classes, c.label);
        for (std::size_t k = 0; k < model_classes.size(); ++k)
          r.log_odds.push_back(static_cast<double>(c.log_odds[k]));
      }
    }
    if (!truth.empty()) {
      if (const evaluation::TruthScanRecord* ts =
              evaluation::nearest_truth_scan(truth, truth_next, result.stamp_ns)) {
        evaluation::truth_composition(*ts, scan, result.segments, result.world_T_sensor,
                                      rec.segments);
        ++truth_matched;
      }
    }
    line.clear();
    evaluation::append_json_line(rec, line);
    out << line;
    if (!o.pictures.empty() && picture_error.empty()) {
      char name[32];
      std::snprintf(name, sizeof(name), "scan_%06llu.png", static_cast<unsigned long long>(scans));
      const std::string legend = "scan " + std::to_string(scans) + ", " +
                                 std::to_string(result.segments.segments.size()) + " segments, " +
                                 std::to_string(result.tracked.tracks.size()) + " tracks" +
                                 (result.has_pose ? "" : " (no pose: vehicle frame)");
      if (auto saved = save_scan_picture(std::filesystem::path(o.pictures) / name, scan, result,
                                         model_classes, legend);
          !saved)
        picture_error = saved.error().message;
    }
    if (dds_out) {
      auto st = dds_out->scans->publish(
          result, scans, result.has_pose ? ego::EgoSource::kIns : ego::EgoSource::kNone);
      if (auto c = dds_out->scans->publish_cloud(result, scans); !c && st)
        st = rt::Unexpected<rt::Error>{c.error()};
      pipeline.want_cloud(dds_out->scans->cloud_reader());
      if (!st && dds_errors++ == 0)
        say(rt::formatted("stac process: DDS: %s\n", st.error().message.c_str()));
    }
    ++scans;
  };

  {
    auto read = recorded->for_each_scan(
        [&](velodyne::Scan& scan, std::int64_t ns) {
          decode_ns += ns;
          handle(scan);
          return true;
        },
        [&](double done, double total) { output.advance("process", done, total); });
    if (!read) return rt::make_error(read.error().message);
  }
  out.close();
  if (!out) return rt::make_error(o.tracks + ": write failed");
  const std::string capture_error = recorded->capture_error();
  const io::PcapReader* reader = recorded->reader();
  const velodyne::ScanStream* stream = recorded->stream();
  const KittiScanCounts& kitti_points = recorded->kitti_points();

  say(rt::formatted("stac process: %s -> %s: %llu complete scans\n", o.in.c_str(), o.tracks.c_str(),
                    static_cast<unsigned long long>(scans)));
  if (drive) {
    say(rt::formatted(
        "  input       KITTI raw drive: %zu scans (velodyne_points/data), times %s%s; "
        "%llu points, %llu left out (not finite, or beyond 1 km)\n",
        drive->scans.size(),
        drive->stamps_from_file ? "from velodyne_points/timestamps.txt"
                                : "100 ms apart (no velodyne_points/timestamps.txt)",
        drive->sweep_start_ns.empty()
            ? ", each scan one instant (no timestamps_start/_end.txt: not deskewed)"
            : ", each point's by its azimuth in its sweep (timestamps_start/_end.txt)",
        static_cast<unsigned long long>(kitti_points.points),
        static_cast<unsigned long long>(kitti_points.refused)));
  } else {
    const velodyne::AssemblerCounters& ac = stream->assembler().counters();
    say(rt::formatted("  capture     %s\n  dropped     %s\n",
                      capture_frames_summary(reader->counters(), ac.packets, vs.port).c_str(),
                      packet_drops_summary(ac).c_str()));
  }
  if (poses && drive) {
    say(rt::formatted(
        "  ego         %llu OXTS records, %llu poses (%llu impossible, %llu time jumps, "
        "%llu jumps back); %llu scans without a pose; sensor mounting from %s\n",
        static_cast<unsigned long long>(poses->group1),
        static_cast<unsigned long long>(poses->counters.ins_fixes),
        static_cast<unsigned long long>(poses->counters.impossible),
        static_cast<unsigned long long>(poses->counters.time_jumps),
        static_cast<unsigned long long>(poses->counters.backward_jumps),
        static_cast<unsigned long long>(pipeline.scans_without_pose()), poses->mounting.c_str()));
  } else if (poses) {
    say(rt::formatted(
        "  ego         %llu INS fixes (%llu skipped before a GPS week, %llu not aligned, "
        "%llu impossible, %llu time jumps, %llu jumps back); "
        "scan clock: %s; %llu scans without a pose (not deskewed)\n"
        "  ins input   dropped: bad checksum %llu, bad framing %llu, malformed %llu; %llu "
        "bytes skipped\n",
        static_cast<unsigned long long>(poses->counters.ins_fixes),
        static_cast<unsigned long long>(poses->counters.no_absolute_time),
        static_cast<unsigned long long>(poses->counters.not_aligned),
        static_cast<unsigned long long>(poses->counters.impossible),
        static_cast<unsigned long long>(poses->counters.time_jumps),
        static_cast<unsigned long long>(poses->counters.backward_jumps),
        ego::to_string(result.clock_source),
        static_cast<unsigned long long>(pipeline.scans_without_pose()),
        static_cast<unsigned long long>(poses->parser.bad_checksum),
        static_cast<unsigned long long>(poses->parser.bad_length) + poses->parser.bad_terminator +
            poses->parser.oversize,
        static_cast<unsigned long long>(poses->parser.malformed),
        static_cast<unsigned long long>(poses->parser.garbage_bytes)));
  } else {
    say(rt::formatted(
        "  ego         %s: parked sensor, world = vehicle frame\n",
        o.no_deskew ? "--no-deskew"
        : drive     ? "no oxts/ in the drive"
                    : ("no INS stream on port " + std::to_string(ego_settings.ins_port)).c_str()));
  }
  const auto& tc = pipeline.tracker().counters();
  say(rt::formatted(
      "  tracks      %llu spawned, %llu live at the end; pool overflow %llu, detections "
      "dropped %llu\n",
      static_cast<unsigned long long>(tc.spawned),
      static_cast<unsigned long long>(pipeline.tracker().live_tracks()),
      static_cast<unsigned long long>(tc.pool_overflow),
      static_cast<unsigned long long>(tc.dropped_detections)));
  if (!truth.empty()) {
    say(rt::formatted(
        "  truth       %llu of %llu scans matched to a truth scan (segment composition written)\n",
        static_cast<unsigned long long>(truth_matched), static_cast<unsigned long long>(scans)));
  }
  if (dds_out) {
    say(rt::formatted(
        "  dds         %llu scans published on tracked_objects, segments, ego_pose; %llu failed\n",
        static_cast<unsigned long long>(scans - dds_errors),
        static_cast<unsigned long long>(dds_errors)));
  }
  say(stats_table(stages));
  if (!o.pictures.empty()) {
    if (!picture_error.empty()) return rt::make_error("--pictures: " + picture_error);
    say(rt::formatted("  pictures    %llu in %s (scan_NNNNNN.png)\n",
                      static_cast<unsigned long long>(scans), o.pictures.c_str()));
  }
  if (!capture_error.empty()) return rt::make_error(capture_breaks_off(capture_error));
  if (scans == 0 && reader) return rt::make_error(recorded->nothing_decoded());
  return {};
}

}  // namespace stac::offline
