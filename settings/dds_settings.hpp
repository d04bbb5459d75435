// The `dds:` section of config/stac.yaml: the publishing edge's domain, topic names and Cyclone
// configuration (docs/dds.md). Every key is required; errors name `dds.<key>`.
#pragma once

#include <filesystem>
#include <string>

#include "dds/publisher.hpp"
#include "rt/expected.hpp"

namespace stac::settings {

rt::Result<dds::PublisherConfig> load_dds_settings(const std::filesystem::path& config_file);

// The commands' --domain (< 0: the config's) and --dds-config (a Cyclone XML file; empty: the
// config's) over `c`.
void override_dds(dds::PublisherConfig& c, int domain, const std::string& cyclone_xml);

}  // namespace stac::settings
