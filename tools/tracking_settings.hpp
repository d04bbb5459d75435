// The `tracking:` section of config/stac.yaml, validated once at start-up. Every key is
// required; a missing or invalid key gives an error naming the file and the key.
#pragma once

#include <filesystem>

#include "perception/tracking/tracker.hpp"
#include "rt/expected.hpp"

namespace stac::tools {

rt::Result<tracking::TrackerConfig> load_tracking_config(const std::filesystem::path& config_file);

}  // namespace stac::tools
