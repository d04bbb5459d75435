#!/usr/bin/env bash
# Makes what DDS Security needs for STAC's domain (docs/dds.md, "Security"): a test identity CA and
# permissions CA, the governance signed by the permissions CA, and for every participant an identity
# (key and certificate signed by the identity CA), a permissions document signed by the permissions
# CA, and a ready Cyclone XML (the base XML with a <Security> section) to give to `stac run
# --dds-config`, `stac echo --dds-config` or CYCLONEDDS_URI.
#
#   deploy/dds-security.sh OUT_DIR [--publisher NAME]... [--subscriber NAME]... [--base XML]
#                          [--days N] [--plugins DIR]
#
# --publisher NAME   may publish STAC's topics (stac/* and the ROS 2 names rt/stac/*); default:
#                    one publisher named 'stac' when none is given
# --subscriber NAME  may read STAC's topics, and publish nothing
# --base XML         the Cyclone XML to add security to (default config/dds/loopback.xml; the
#                    vehicle's is config/dds/vehicle.xml)
# --days N           validity of the CAs and certificates (default 3650)
# --plugins DIR      where Cyclone's security plugins are (default: Debian's libddsc0debian folder)
#
# The CAs made here are for tests and a first vehicle setup: on a fleet, sign with the fleet's own
# CAs and keep their keys off the vehicle. OUT_DIR/<NAME>/ holds key.pem, which must stay private.
set -euo pipefail

here=$(cd "$(dirname "$0")/.." && pwd)
usage() { sed -n '2,20p' "$0" | sed 's/^# \{0,1\}//'; exit "${1:-2}"; }
die() { echo "dds-security: $*" >&2; exit 1; }

(($# >= 1)) || usage
[[ $1 == -h || $1 == --help ]] && usage 0
out=$1
shift
publishers=() subscribers=()
base="$here/config/dds/loopback.xml"
days=3650
plugins=/usr/lib/$(gcc -print-multiarch 2>/dev/null || echo x86_64-linux-gnu)/libddsc0debian
while (($#)); do
  case $1 in
    --publisher) (($# >= 2)) || die "--publisher needs a name"; publishers+=("$2"); shift 2 ;;
    --subscriber) (($# >= 2)) || die "--subscriber needs a name"; subscribers+=("$2"); shift 2 ;;
    --base) (($# >= 2)) || die "--base needs a file"; base=$2; shift 2 ;;
    --days) (($# >= 2)) || die "--days needs a number"; days=$2; shift 2 ;;
    --plugins) (($# >= 2)) || die "--plugins needs a folder"; plugins=$2; shift 2 ;;
    -h | --help) usage 0 ;;
    *) die "unknown argument '$1' (see --help)" ;;
  esac
done
((${#publishers[@]})) || publishers=(stac)
[[ $days =~ ^[1-9][0-9]{0,4}$ ]] || die "--days must be a whole number from 1 to 99999, not '$days'"
[[ -f $base ]] || die "--base '$base' is not a file"
grep -q '</Domain>' "$base" || die "--base '$base' has no <Domain> element to add security to"
for lib in auth ac crypto; do
  [[ -f $plugins/libdds_security_$lib.so ]] ||
    die "no $plugins/libdds_security_$lib.so: install libddsc0debian (Cyclone's security plugins)"
done
command -v openssl >/dev/null || die "openssl is missing: apt-get install openssl"
for name in "${publishers[@]}" "${subscribers[@]}"; do
  [[ $name =~ ^[A-Za-z0-9][A-Za-z0-9_.-]{0,63}$ ]] ||
    die "participant name '$name': letters, digits, '_', '.', '-' only (at most 64)"
done

mkdir -p "$out"
out=$(cd "$out" && pwd)
ssl() { openssl "$@" 2>/dev/null || { openssl "$@" >/dev/null; die "openssl $1 failed"; }; }

make_ca() {  # make_ca FILE_STEM COMMON_NAME
  [[ -f $1.pem ]] && return 0  # kept: certificates already issued stay valid
  ssl req -x509 -newkey rsa:2048 -nodes -keyout "$1.key" -out "$1.pem" -days "$days" \
    -subj "/C=NL/O=STAC/CN=$2" -addext basicConstraints=critical,CA:TRUE
  chmod 600 "$1.key"
}
make_ca "$out/identity_ca" "STAC Identity CA"
make_ca "$out/permissions_ca" "STAC Permissions CA"

sign() {  # sign IN OUT: S/MIME signed by the permissions CA, as DDS Security reads it
  ssl smime -sign -in "$1" -text -out "$2" -signer "$out/permissions_ca.pem" \
    -inkey "$out/permissions_ca.key"
}
sign "$here/config/dds/security/governance.xml" "$out/governance.p7s"

not_before=$(date -u +%Y-%m-%dT%H:%M:%S)
not_after=$(date -u -d "+$days days" +%Y-%m-%dT%H:%M:%S)
participant() {  # participant NAME ROLE
  local name=$1 role=$2 dir="$out/$1" subject="CN=$1,O=STAC,C=NL"
  mkdir -p "$dir"
  ssl req -newkey rsa:2048 -nodes -keyout "$dir/key.pem" -out "$dir/cert.csr" \
    -subj "/C=NL/O=STAC/CN=$name"
  chmod 600 "$dir/key.pem"
  ssl x509 -req -in "$dir/cert.csr" -CA "$out/identity_ca.pem" -CAkey "$out/identity_ca.key" \
    -CAcreateserial -out "$dir/cert.pem" -days "$days"
  rm -f "$dir/cert.csr"
  local grant
  if [[ $role == publisher ]]; then
    grant="<publish><topics><topic>stac/*</topic><topic>rt/stac/*</topic></topics></publish>
          <subscribe><topics><topic>stac/*</topic><topic>rt/stac/*</topic></topics></subscribe>"
  else
    grant="<subscribe><topics><topic>stac/*</topic><topic>rt/stac/*</topic></topics></subscribe>"
  fi
  cat >"$dir/permissions.xml" <<XML
<?xml version="1.0" encoding="UTF-8"?>
<!-- Made by deploy/dds-security.sh: '$name' may $([[ $role == publisher ]] && echo "publish and read" || echo "read") STAC's topics. -->
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_permissions.xsd">
  <permissions>
    <grant name="$name">
      <subject_name>$subject</subject_name>
      <validity><not_before>$not_before</not_before><not_after>$not_after</not_after></validity>
      <allow_rule>
        <domains><id_range><min>0</min><max>230</max></id_range></domains>
        $grant
      </allow_rule>
      <default>DENY</default>
    </grant>
  </permissions>
</dds>
XML
  sign "$dir/permissions.xml" "$dir/permissions.p7s"
  local security
  security=$(cat <<XML
    <Security>
      <Authentication>
        <Library path="$plugins/libdds_security_auth.so" initFunction="init_authentication" finalizeFunction="finalize_authentication"/>
        <IdentityCA>file:$out/identity_ca.pem</IdentityCA>
        <IdentityCertificate>file:$dir/cert.pem</IdentityCertificate>
        <PrivateKey>file:$dir/key.pem</PrivateKey>
      </Authentication>
      <AccessControl>
        <Library path="$plugins/libdds_security_ac.so" initFunction="init_access_control" finalizeFunction="finalize_access_control"/>
        <PermissionsCA>file:$out/permissions_ca.pem</PermissionsCA>
        <Governance>file:$out/governance.p7s</Governance>
        <Permissions>file:$dir/permissions.p7s</Permissions>
      </AccessControl>
      <Cryptographic>
        <Library path="$plugins/libdds_security_crypto.so" initFunction="init_crypto" finalizeFunction="finalize_crypto"/>
      </Cryptographic>
    </Security>
XML
)
  awk -v sec="$security" '/<\/Domain>/ && !done { print sec; done = 1 } { print }' "$base" \
    >"$dir/cyclonedds.xml"
  echo "dds-security: $name ($role): $dir/cyclonedds.xml"
}
for name in "${publishers[@]}"; do participant "$name" publisher; done
for name in "${subscribers[@]}"; do participant "$name" subscriber; done
