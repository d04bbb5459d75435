// Labelled track datasets (what `stac dataset` writes and `stac train` / `stac eval --classes`
// read; docs/classification.md "Dataset format"): DIR/tracks.bin (binary, checksummed) and
// DIR/manifest.json (counts per class, for people).
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "perception/classification/grid_classifier.hpp"
#include "rt/expected.hpp"

namespace stac::tools {

// One labelled track: per segment it was updated with (in time order), the segment's
// descriptors and the track's holistic descriptor after that segment.
struct DatasetTrack {
  std::uint64_t id = 0;      // tracker id (unique within one source)
  std::uint32_t source = 0;  // index into Dataset::sources
  classification::ObjectClass label = classification::ObjectClass::kBackground;
  std::uint32_t segments = 0;
  std::vector<float> segment_rows;   // segments * segment dimensions, row-major
  std::vector<float> holistic_rows;  // segments * holistic dimensions, row-major
};

struct Dataset {
  std::vector<std::string> sources;  // "capture truth" of each run
  std::vector<DatasetTrack> tracks;
};

inline constexpr std::uint32_t kDatasetFormatVersion = 1;

// Creates DIR when missing; overwrites tracks.bin and manifest.json.
rt::Result<bool> write_dataset(const std::filesystem::path& dir, const Dataset& data);
// Errors name the file and what is wrong (missing, truncated, checksum, version, layout).
rt::Result<Dataset> read_dataset(const std::filesystem::path& dir);
// Appends `more` to `into` (sources renumbered).
void append_dataset(Dataset& into, Dataset&& more);

}  // namespace stac::tools
