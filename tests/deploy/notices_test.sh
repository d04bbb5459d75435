#!/usr/bin/env bash
# THIRD-PARTY-NOTICES.md names the Debian package of every library that `stac` and `stac-node`
# link directly (their ELF NEEDED entries, found with dpkg -S), and the package installs it with
# LICENSE (deploy/CMakeLists.txt). A new dependency without its notice fails here.
# Usage: notices_test.sh SOURCE_DIR STAC STAC_NODE
set -euo pipefail
source_dir=$1
shift
notices=$source_dir/THIRD-PARTY-NOTICES.md
fail() { echo "notices: $*" >&2; exit 1; }
[[ -f $source_dir/LICENSE ]] || fail "LICENSE is missing"
grep -q "Apache License" "$source_dir/LICENSE" || fail "LICENSE is not the Apache License"
[[ -f $notices ]] || fail "$notices is missing"
checked=0
for exe in "$@"; do
  mapfile -t needed < <(readelf -d "$exe" | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p')
  ((${#needed[@]} > 0)) || fail "$exe: no NEEDED entries read"
  for soname in "${needed[@]}"; do
    path=$(ldd "$exe" | awk -v so="$soname" '$1 == so {print $3}')
    [[ -n $path ]] || fail "$exe: ldd does not resolve $soname"
    real=$(readlink -f "$path")
    package=$(dpkg -S "$real" 2>/dev/null || dpkg -S "$path" 2>/dev/null || true)
    package=${package%%:*}
    [[ -n $package ]] || fail "$soname ($real) belongs to no Debian package: name its origin and licence"
    grep -q -- "$package" "$notices" || fail "$exe links $soname from $package, which THIRD-PARTY-NOTICES.md does not name"
    checked=$((checked + 1))
  done
done
echo "notices: $checked linked libraries, each named with its licence"
