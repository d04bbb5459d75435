# Sourced by tools/scripts/train_default_model.sh and tools/scripts/induction_experiment.sh: simulated drives made
# into labelled datasets, JOBS at a time. Needs STAC (the binary), WORK (the folder) and DURATION
# (s per drive) set; `make_drives scenario:seed ...` makes WORK/scenario:seed/data for each drive
# whose dataset is not there yet.

# One drive: simulated and described, skipped when its dataset is already there.
drive() {
  local name=${1%%:*} seed=${1##*:} dir="$WORK/$1"
  [[ -f "$dir/data/manifest.json" ]] && return 0
  mkdir -p "$dir"
  "$STAC" sim --scenario "$name" --seed "$seed" --duration "$DURATION" \
    --out "$dir/run.pcap" --truth "$dir/run.truth.jsonl" > "$dir/sim.log" 2>&1
  "$STAC" dataset --in "$dir/run.pcap" --truth "$dir/run.truth.jsonl" --out "$dir/data.tmp" \
    > "$dir/dataset.log" 2>&1
  rm -rf "$dir/data" && mv "$dir/data.tmp" "$dir/data"
  rm -f "$dir/run.pcap"  # 90 MB a drive; the dataset is what training reads
  echo "  $1: $(tail -n 1 "$dir/dataset.log")"
}

make_drives() {
  [[ -x "$STAC" ]] || { echo "$0: $STAC is missing: build first (cmake --build build)" >&2; exit 1; }
  mkdir -p "$WORK"
  export -f drive
  export STAC WORK DURATION
  printf '%s\n' "$@" | xargs -P "${JOBS:-1}" -I{} bash -c 'drive {}'
}
