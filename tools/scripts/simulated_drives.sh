# Sourced by tools/scripts/train_default_model.sh, induction_experiment.sh and
# new_class_experiment.sh: simulated drives made
# into labelled datasets, JOBS at a time. Needs STAC (the binary), WORK (the folder) and DURATION
# (s per drive) set; `make_drives scenario:seed[:kind] ...` makes WORK/scenario:seed[:kind]/data
# for each drive whose dataset is not there yet (a third field: a kind left out of the world,
# `stac sim --without`). DATASET_ARGS (e.g. "--class pole") goes to every `stac dataset`.

# One drive: simulated and described, skipped when its dataset is already there.
drive() {
  local name seed without dir="$WORK/$1"
  IFS=: read -r name seed without <<< "$1"
  [[ -f "$dir/data/manifest.json" ]] && return 0
  mkdir -p "$dir"
  # shellcheck disable=SC2086  # DATASET_ARGS: words
  "$STAC" sim --scenario "$name" --seed "$seed" --duration "$DURATION" \
    ${without:+--without "$without"} \
    --out "$dir/run.pcap" --truth "$dir/run.truth.jsonl" > "$dir/sim.log" 2>&1
  # shellcheck disable=SC2086
  "$STAC" dataset --in "$dir/run.pcap" --truth "$dir/run.truth.jsonl" --out "$dir/data.tmp" \
    ${DATASET_ARGS:-} > "$dir/dataset.log" 2>&1
  rm -rf "$dir/data" && mv "$dir/data.tmp" "$dir/data"
  rm -f "$dir/run.pcap"  # 90 MB a drive; the dataset is what training reads
  echo "  $1: $(tail -n 1 "$dir/dataset.log")"
}

make_drives() {
  [[ -x "$STAC" ]] || { echo "$0: $STAC is missing: build first (cmake --build build)" >&2; exit 1; }
  mkdir -p "$WORK"
  export -f drive
  export STAC WORK DURATION DATASET_ARGS
  printf '%s\n' "$@" | xargs -P "${JOBS:-1}" -I{} bash -c 'drive {}'
}

# The group induction experiments' drives: BACKGROUND, LABELS, STREAM and TEST (scenario:seed
# lists) made, and their datasets as the options of stac induct, train and eval, in the arrays
# bg (--background), labels (--labels), stream (--unlabeled), test (--eval), test_data (--data)
# and everything (--data: B0, the labels' and the stream's drives).
induction_drives() {
  local all=("${BACKGROUND[@]}" "${LABELS[@]}" "${STREAM[@]}" "${TEST[@]}")
  echo "$0: ${#all[@]} drives of ${DURATION} s in $WORK"
  make_drives "${all[@]}"
  mapfile -t bg < <(dataset_options --background "${BACKGROUND[@]}")
  mapfile -t labels < <(dataset_options --labels "${LABELS[@]}")
  mapfile -t stream < <(dataset_options --unlabeled "${STREAM[@]}")
  mapfile -t test < <(dataset_options --eval "${TEST[@]}")
  mapfile -t test_data < <(dataset_options --data "${TEST[@]}")
  mapfile -t everything < <(dataset_options --data "${BACKGROUND[@]}" "${LABELS[@]}" "${STREAM[@]}")
}

dataset_options() {  # dataset_options FLAG DRIVE... -> FLAG WORK/DRIVE/data ...
  local flag=$1
  shift
  for d in "$@"; do printf '%s\n' "$flag" "$WORK/$d/data"; done
}
