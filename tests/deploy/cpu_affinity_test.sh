#!/usr/bin/env bash
# deploy/stac-cpu-affinity, the systemd generator, with the stac-node just built: a config that
# pins threads to CPUs 3, 1 and 3 gives a drop-in with CPUAffinity=1 3 (and systemd-analyze, when
# installed, accepts the unit with it); a config that pins none, a missing config and one that
# does not load give no drop-in and exit 0 (a generator never fails the boot).
# Usage: cpu_affinity_test.sh SOURCE_DIR STAC_NODE
set -euo pipefail
src=$(cd "$1" && pwd)
node=$(realpath "$2")
fail() { echo "cpu_affinity_test: FAIL: $*" >&2; exit 1; }
work=$(mktemp -d /tmp/stac-cpu-affinity-test.XXXXXX)
trap 'rm -rf "$work"' EXIT
generate() { STAC_CONFIG=$1 STAC_NODE=$node sh "$src/deploy/stac-cpu-affinity" "$2" "$2" "$2"; }

cp -r "$src/config/." "$work/config"
sed -i 's/^  receiver_cpu: -1 /  receiver_cpu: 3 /; s/^  perception_cpu: -1/  perception_cpu: 1/;
        s/^  publisher_cpu: -1/  publisher_cpu: 3/' "$work/config/stac.yaml"
generate "$work/config/stac.yaml" "$work/out"
dropin=$work/out/stac.service.d/50-cpu-affinity.conf
[[ -f $dropin ]] || fail "no drop-in for a config with CPUs"
grep -qx 'CPUAffinity=1 3' "$dropin" || fail "drop-in: $(cat "$dropin")"
grep -qx '\[Service\]' "$dropin" || fail "drop-in has no [Service] section"
if command -v systemd-analyze > /dev/null; then
  mkdir -p "$work/unit/stac.service.d"
  sed "s|/usr/bin/stac-node|$node|" "$src/deploy/stac.service" > "$work/unit/stac.service"
  cp "$dropin" "$work/unit/stac.service.d/"
  out=$(SYSTEMD_UNIT_PATH="$work/unit:" systemd-analyze verify "$work/unit/stac.service" 2>&1) ||
    fail "systemd-analyze verify with the drop-in: $out"
  [[ -z $out ]] || fail "systemd-analyze verify with the drop-in: $out"
fi
for config in "$src/config/stac.yaml" "$work/missing.yaml"; do
  generate "$config" "$work/none"
  [[ ! -e $work/none/stac.service.d ]] || fail "a drop-in for $config"
done
echo "velodyne: [" > "$work/broken.yaml"
generate "$work/broken.yaml" "$work/none" || fail "the generator failed on a broken config"
[[ ! -e $work/none/stac.service.d ]] || fail "a drop-in for a broken config"
echo "cpu_affinity_test: CPUAffinity=1 3 from the config; nothing without CPUs or config"
