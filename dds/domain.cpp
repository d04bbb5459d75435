#include "dds/domain.hpp"

#include <cstdlib>
#include <string>

#include "dds/identity.hpp"
#include "dds/topics.hpp"

namespace stac::dds {

rt::Result<dds_entity_t> create_domain(const PublisherConfig& config, ExistingDomain existing) {
  if (config.domain_id > 230) {
    return rt::make_error("DDS domain " + std::to_string(config.domain_id) + ": must be 0..230");
  }
  if (auto s = check_identity_keys(config.config_uri); !s)
    return rt::Unexpected<rt::Error>{s.error()};
  if (config.config_uri.empty()) return dds_entity_t{0};
  const dds_entity_t domain = dds_create_domain(config.domain_id, config.config_uri.c_str());
  if (domain == DDS_RETCODE_PRECONDITION_NOT_MET && existing == ExistingDomain::kJoin)
    return dds_entity_t{0};
  if (domain == DDS_RETCODE_PRECONDITION_NOT_MET) {
    return dds_error("creating DDS domain " + std::to_string(config.domain_id) + " with " +
                         config.config_uri + ": this process made it already",
                     domain);
  }
  if (domain < 0) {
    return dds_error("DDS domain " + std::to_string(config.domain_id) +
                         ": the Cyclone DDS configuration " + config.config_uri +
                         " cannot be used (not Cyclone XML, an element Cyclone does not know, or "
                         "an interface this machine does not have: Cyclone says which, above; "
                         "config/dds/loopback.xml is a working example)",
                     domain);
  }
  return domain;
}

rt::Status check_domain(const PublisherConfig& config) {
  PublisherConfig c = config;
  if (c.config_uri.empty()) {
    // What the first participant's default domain reads.
    const char* uri = std::getenv("CYCLONEDDS_URI");
    c.config_uri = uri != nullptr && *uri != '\0' ? uri : "<CycloneDDS/>";
  }
  auto domain = create_domain(c, ExistingDomain::kRefuse);
  if (!domain) return rt::Unexpected<rt::Error>{domain.error()};
  // With DDS Security, a participant for a moment: Cyclone checks the identity, permissions and
  // governance against their CAs only when it makes one (the start would fail there).
  if (uses_security(c.config_uri)) {
    const dds_entity_t participant = dds_create_participant(c.domain_id, nullptr, nullptr);
    if (participant < 0) {
      dds_delete(*domain);
      return dds_error("DDS domain " + std::to_string(c.domain_id) +
                           ": DDS Security: " + c.config_uri +
                           " gives an identity, permissions or governance Cyclone refuses (a "
                           "certificate or document its CA did not sign, a key it cannot read: "
                           "Cyclone says which, above)",
                       participant);
    }
    dds_delete(participant);
  }
  dds_delete(*domain);
  return {};
}

}  // namespace stac::dds
