// The `dds:` section of config/stac.yaml: the publishing edge's domain, topic names and Cyclone
// configuration (docs/dds.md). Every key is required; errors name `dds.<key>`.
#pragma once

#include <filesystem>

#include "dds/publisher.hpp"
#include "rt/expected.hpp"

namespace stac::settings {

rt::Result<dds::PublisherConfig> load_dds_settings(const std::filesystem::path& config_file);

}  // namespace stac::settings
