// The per-scan JSON-lines files: what `stac process` writes (tracks file) and what `stac sim`
// writes (truth file), and their readers for `stac eval`. One JSON object per line; times are UTC
// seconds printed with 9 decimals (parsed back to ns within about 0.3 us: a double).
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "perception/tracking/track.hpp"
#include "rt/expected.hpp"

namespace stac::evaluation {

struct EgoRecord {
  double x = 0, y = 0, z = 0, yaw = 0;  // world frame (m, rad)
};

struct SegmentRecord {
  std::uint32_t id = 0;
  std::uint32_t points = 0;
  double x = 0, y = 0, z = 0, length = 0, width = 0, height = 0, yaw = 0;  // world (m, rad)
  // Truth composition (only when `stac process` had the truth): (truth object id, points of this
  // segment inside that box); id -1 counts the points in no box.
  std::vector<std::pair<std::int64_t, std::uint32_t>> truth;
  bool has_truth = false;
};

struct TrackRecord {
  std::uint64_t id = 0;
  std::string state;  // tentative | confirmed | coasting
  double x = 0, y = 0, z = 0, vx = 0, vy = 0;
  double length = 0, width = 0, height = 0, yaw = 0;
  std::uint32_t points = 0, age = 0;
  std::int32_t segment = -1;  // segment id updated this scan, -1 when coasting
  // `stac process --model`: the track's class (ADBF) and log odds (car, pedestrian, bicyclist).
  bool classified = false;
  std::string cls;
  std::vector<double> log_odds;  // one per model class (docs/classification.md)
};

// The world frame a tracks file is written in (`frame`, with `origin` for kEnu).
enum class TracksFrame {
  kUnknown,  // a file from before the frame was recorded
  kEnu,      // ENU on the tangent plane of `origin` (the INS's local frame)
  kVehicle,  // no pose (no INS stream, or --no-deskew): world = the vehicle frame of each scan
};

struct TracksScan {
  TracksFrame frame = TracksFrame::kUnknown;
  std::array<double, 3> origin{};  // kEnu: lat, lon (deg), alt (m, WGS84 ellipsoid)
  std::uint64_t scan = 0;
  std::int64_t stamp_ns = 0;
  EgoRecord ego;
  std::vector<SegmentRecord> segments;
  std::vector<TrackRecord> tracks;
};

struct TruthObjectRecord {
  std::uint32_t id = 0;
  std::string cls;  // car, pedestrian, bicyclist, building, wall, fence, tree, bush, pole, ...
  double x = 0, y = 0, z = 0, length = 0, width = 0, height = 0, yaw = 0;  // box centre, world
  double vx = 0, vy = 0;
  std::uint32_t points = 0;
};

struct TruthScanRecord {
  std::optional<std::array<double, 3>> origin;  // the world's geodetic anchor (lat, lon, alt)
  std::uint64_t scan = 0;
  std::int64_t stamp_ns = 0;
  std::int64_t end_stamp_ns = 0;  // its last firing ("end_time"); 0 when the file has none
  EgoRecord ego;
  std::vector<TruthObjectRecord> objects;
};

// The record of one tracker track (state name, filtered position and velocity, smoothed box).
TrackRecord track_record(const tracking::Track& track);

// Appends one JSON line (with its '\n') to out.
void append_json_line(const TracksScan& scan, std::string& out);

// Parsers of one line; the error names the missing or malformed key (no file or line: the
// readers add them).
rt::Result<TracksScan> parse_tracks_line(std::string_view line);
rt::Result<TruthScanRecord> parse_truth_line(std::string_view line);

// Whole files; errors read "<file>:<line>: <what>". Blank lines are skipped. `progress`, when
// set, is called now and then with the bytes read so far.
using ReadProgress = std::function<void(std::uint64_t bytes)>;
rt::Result<std::vector<TracksScan>> read_tracks_file(const std::filesystem::path& file,
                                                     const ReadProgress& progress = {});
rt::Result<std::vector<TruthScanRecord>> read_truth_file(const std::filesystem::path& file,
                                                         const ReadProgress& progress = {});

}  // namespace stac::evaluation
