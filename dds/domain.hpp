// The Cyclone domain a PublisherConfig names, made one way by the publisher, the readers of
// `stac echo` and `stac-node --check`.
#pragma once

#include <dds/dds.h>

#include "dds/publisher.hpp"
#include "rt/expected.hpp"

namespace stac::dds {

// What create_domain does when this process made the domain already.
enum class ExistingDomain {
  kRefuse,  // an error: its configuration may not be config_uri
  kJoin,    // 0 is returned: participants join it with the configuration it was made with
};

// Checks DDS Security's identity keys (check_identity_keys), then creates domain
// config.domain_id with config.config_uri: Cyclone parses the XML (printing where it stopped on
// stderr), finds the interfaces it names and opens its sockets; nothing is announced before a
// participant is made. Returns the domain's handle (dds_delete it after its participants), or 0
// when none was made: config_uri empty (the first participant makes the default domain, from
// $CYCLONEDDS_URI), or the domain exists and `existing` is kJoin. Errors name the XML and what
// to fix.
rt::Result<dds_entity_t> create_domain(const PublisherConfig& config, ExistingDomain existing);

// `stac-node --check`: creates the domain as the start does (with config_uri, else
// $CYCLONEDDS_URI, else Cyclone's defaults) and deletes it again; without a participant, unless
// the configuration sets up DDS Security: then one is made and deleted at once (only that shows
// whether Cyclone takes the identity, and it is what the start would make).
rt::Status check_domain(const PublisherConfig& config);

}  // namespace stac::dds
