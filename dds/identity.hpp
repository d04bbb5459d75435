// DDS Security's local identity, checked before Cyclone is given it (docs/dds.md, "Security").
// Cyclone 0.10 refuses a certificate its CA did not sign, an unreadable key and the like when
// the participant is made, but it starts a participant whose private key is not the key of its
// identity certificate: no peer can then authenticate it, and it serves nobody without a word.
#pragma once

#include <string>

#include "rt/expected.hpp"

namespace stac::dds {

// For each <Security><Authentication> of the Cyclone configuration `config_uri` (as given to
// dds_create_domain: "file://PATH", "file:PATH", a path, or the XML itself; empty: the
// environment's CYCLONEDDS_URI), an error naming both files when the private key (file: or
// data:, PEM, with its <Password>) does not belong to the identity certificate. What cannot be
// read here (a pkcs11: key, a missing file, a malformed PEM) is left to Cyclone, which refuses it
// with its own message.
[[nodiscard]] rt::Status check_identity_keys(const std::string& config_uri);

// Whether a configuration of `config_uri` (read as above) sets up DDS Security (an
// <Authentication>): then only a participant shows whether Cyclone takes the identity (a
// certificate its CA did not sign, permissions or governance not signed by theirs).
[[nodiscard]] bool uses_security(const std::string& config_uri);

}  // namespace stac::dds
