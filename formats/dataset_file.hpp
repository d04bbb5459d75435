// Labelled track datasets (what `stac dataset` writes and `stac train` / `stac eval --classes`
// read; docs/classification.md "Dataset format"): DIR/tracks.bin (binary, checksummed) and
// DIR/manifest.json (counts per class, for people).
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "perception/classification/grid_classifier.hpp"
#include "perception/learning/track_training.hpp"
#include "rt/expected.hpp"

namespace stac::formats {

// One labelled track: per segment it was updated with (in time order), the segment's
// descriptors and the track's holistic descriptor after that segment.
// One segment of a track as a person sees it (`stac label`): a sample of its points relative to
// the segment's centroid, x, y, z, intensity per point (m, sensor axes: x forward, z up).
struct TrackSnapshot {
  std::uint32_t segment = 0;  // which of the track's segments, 0-based
  std::vector<float> points;  // 4 floats per point
};
inline constexpr std::size_t kMaxSnapshots = 4;         // per track, spread over its segments
inline constexpr std::size_t kMaxSnapshotPoints = 400;  // per snapshot, an even sample

struct DatasetTrack {
  std::uint64_t id = 0;      // tracker id (unique within one source)
  std::uint32_t source = 0;  // index into Dataset::sources
  classification::ClassIndex label = classification::kBackground;  // into Dataset::classes
  std::uint32_t segments = 0;
  // Segments that are tracking or under-segmentation errors (off_label_segments() below: not
  // mostly the track's own object). Over-segmentation (a piece of a car) is not one.
  std::uint32_t off_label_segments = 0;
  std::vector<float> segment_rows;   // segments * segment dimensions, row-major
  std::vector<float> holistic_rows;  // segments * holistic dimensions, row-major
  // Version 5 (empty in older datasets): the segments' centroids in the world frame of the run
  // (x, y per segment, m), and up to kMaxSnapshots segments' points.
  std::vector<float> path;
  std::vector<TrackSnapshot> snapshots;
};

struct Dataset {
  classification::ClassNames classes = classification::default_class_names();  // labels index it
  // False: made without truth (`stac dataset` without --truth): every label is a placeholder
  // (background); only `stac induct --unlabeled` takes it.
  bool labelled = true;
  std::vector<std::string> sources;  // each run's files (source_of(); source_files())
  std::vector<DatasetTrack> tracks;
  // Read: tracks.bin's checksum (its last 8 bytes), which names this dataset's contents (a state
  // of `stac induct` keeps it, so a dataset remade at the same path is not taken for the one it
  // read). Not written: write_dataset computes its own.
  std::uint64_t checksum = 0;
};

// A run's source as Dataset::sources keeps it: its capture (or drive folder) and, for labelled
// tracks, its truth file, apart by a NUL (which no path holds; stored as one string, so datasets
// of earlier builds read as they were). Datasets made before 2026-12-08 joined the two with a
// space, which a path may hold: such a source reads back whole as its capture.
std::string source_of(const std::string& capture, const std::string& truth);
struct SourceFiles {
  std::string capture, truth;  // truth empty: unlabeled, or a source of an older dataset
};
SourceFiles source_files(const std::string& source);

// Version 5 adds each track's path and point snapshots; version 4 says whether the tracks are
// labelled; version 3 stores the class names (version 2: the default three, background label 3).
// Versions 2 to 4 still read (without paths and snapshots; 2 and 3 labelled).
inline constexpr std::uint32_t kDatasetFormatVersion = 5;

// The thesis's rule (ch. 1, the Stanford Track Collection): a track in which more than 10% of
// the segments are tracking or under-segmentation errors is inconsistent, and is left out of
// training and of the accuracy (`stac train`, `stac eval --classes`, which also reports it with
// every track counted). The thesis applies it to foreground tracks: here a track labelled
// background is inconsistent when more than 10% of its segments are mostly one foreground object.
inline constexpr double kMaxOffLabelFraction = 0.1;
// One segment's truth for that rule: the foreground truth object holding more than half of the
// segment's points (-1: none; background, or several objects under-segmented) and its class.
struct SegmentTruth {
  std::int64_t object = -1;
  classification::ClassIndex cls = classification::kBackground;
};
// DatasetTrack::off_label_segments of a track labelled `label`: for a foreground label, the
// segments that are not mostly its own object (the one most of its segments of that class are
// mostly of); for background, the segments that are mostly one foreground object.
std::uint32_t off_label_segments(classification::ClassIndex label,
                                 std::span<const SegmentTruth> segments);
[[nodiscard]] inline bool consistent(const DatasetTrack& t) noexcept {
  return static_cast<double>(t.off_label_segments) <=
         kMaxOffLabelFraction * static_cast<double>(t.segments);
}

// A track as training takes it: its label, every segment row, and its last holistic descriptor
// (the rows are moved out of `t`).
learning::TrackExample track_example(DatasetTrack t);

// Creates DIR when missing; replaces tracks.bin, then manifest.json, each durably (written to a
// temporary file, fsynced, renamed): a kill leaves the old or the new tracks.bin, whole. The
// manifest names its tracks.bin by checksum (tracks_bin_checksum_fnv1a64: the file's last 8
// bytes, little-endian).
rt::Status write_dataset(const std::filesystem::path& dir, const Dataset& data);
// Errors name the file and what is wrong (missing, truncated, checksum, version, layout).
rt::Result<Dataset> read_dataset(const std::filesystem::path& dir);
// The bytes of a tracks.bin, `name` naming them in errors (read_dataset; the fuzzing harness).
rt::Result<Dataset> parse_dataset(std::span<const std::uint8_t> bytes, const std::string& name);
// read_dataset, refusing a dataset without labels with a message saying what `job` needs.
rt::Result<Dataset> read_labelled_dataset(const std::filesystem::path& dir, const std::string& job);
// A labelled dataset's labels onto the classes `to`, by name: each of `to` must be one of the
// dataset's; its other classes become background (1-vs-all: none of `to`). Fails, changing
// nothing and naming `name` and the missing class, when one of `to` is not the dataset's.
rt::Status map_classes(Dataset& data, const classification::ClassNames& to,
                       const std::string& name);

// Appends `more` to `into` (sources renumbered). Fails (nothing appended) when their classes
// differ or one is labelled and the other not; `more_name` names `more` in the message.
rt::Status append_dataset(Dataset& into, Dataset&& more, const std::string& more_name);

}  // namespace stac::formats
