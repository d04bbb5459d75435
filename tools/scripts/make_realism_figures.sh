#!/bin/sh
# Reproduces the realism figures and numbers of docs/simulator.md: simulated urban drives compared
# with the six real KITTI scans in ../shared/data/kitti. Run from the repository root after a build.
#   sh tools/scripts/make_realism_figures.sh [BUILD_DIR] [WORK_DIR]
set -eu
STAC="${1:-build}/tools/stac"
WORK="${2:-/tmp/stac-realism}"
mkdir -p "$WORK" docs/img
# A 2 s drive (20 scans): the clean comparison.
"$STAC" sim --scenario urban --seed 1 --duration 2 --out "$WORK/urban2.pcap" --truth "$WORK/urban2.truth.jsonl"
"$STAC" sim-compare --sim "$WORK/urban2.pcap" --report "$WORK/urban2"
# A 20 s drive (200 scans): a longer stretch, with the stop at the crossing and traffic around the ego.
"$STAC" sim --scenario urban --seed 1 --duration 20 --out "$WORK/urban20.pcap" --truth "$WORK/urban20.truth.jsonl"
"$STAC" sim-compare --sim "$WORK/urban20.pcap" --report "$WORK/urban20"
for f in birds_eye_side_by_side points_per_ring ring_elevation range_histogram intensity_histogram; do
  cp "$WORK/urban2/$f.png" "docs/img/realism_$f.png"
done
cp "$WORK/urban20/points_per_scan.png" docs/img/realism_points_per_scan_urban20.png
echo "figures in docs/img/realism_*.png; tables in $WORK/urban2/realism.md and $WORK/urban20/realism.md"
