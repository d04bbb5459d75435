// The `segmentation:` section of config/stac.yaml, validated once at start-up. Every key is
// required; errors name the file and the key.
#pragma once

#include <filesystem>

#include "perception/segmentation/segmenter.hpp"
#include "rt/expected.hpp"

namespace stac::tools {

rt::Result<segmentation::SegmenterConfig> load_segmentation_settings(
    const std::filesystem::path& config_file);

}  // namespace stac::tools
