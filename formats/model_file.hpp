// Track classifier model files (the bytes of classification::serialize, docs/classification.md
// "Model format"): every failure names the file and says what to do.
#pragma once

#include <filesystem>
#include <memory>
#include <string>

#include "perception/classification/model.hpp"
#include "rt/expected.hpp"

namespace stac::formats {

// Writes through a temporary file, fsynced and renamed over `path` (durable_file.hpp), so a
// failed write or a kill leaves no half model.
rt::Status write_model_file(const std::filesystem::path& path,
                            const classification::TrackClassifierModel& model);
// Missing, unreadable, truncated, corrupt, another format version or descriptor layout: an error
// "<path>: <what>; <what to do>".
rt::Result<classification::TrackClassifierModel> read_model_file(const std::filesystem::path& path);

// The model a per-scan job classifies with: the command line's `option` when given ("none": no
// model), else the config's `configured` path (empty: no model). Null: tracks stay unclassified.
rt::Result<std::shared_ptr<const classification::TrackClassifierModel>> job_model(
    const std::string& option, const std::filesystem::path& configured);

}  // namespace stac::formats
