#!/usr/bin/env bash
# The group induction experiment of docs/learning.md (the thesis's Fig. 2.6 on simulated drives):
# a few labelled tracks per class, an empty street as B0, a stream of unlabeled drives (one
# chunk a round), the oracle answering the active-learning questions, accuracy on held-out drives
# after every round; beside it (a) `stac train` on the same user labels + B0 without induction
# and (b) `stac train` on every label of every drive, and (b) again on the first 1, 2, 4 and 8
# drives (supervised_curve.tsv: the thesis's Fig. 2.5). No test uses these seeds.
#
#   tools/scripts/induction_experiment.sh [WORK_DIR]     (default: build/induction-experiment)
#
# Environment: STAC (default build/tools/stac), JOBS (drives made in parallel, default 1),
# DURATION (s per drive, default 15), SEED_LABELS (per class, default 5), ASK (questions per
# class about the least confident tracks after each chunk, default 5: about as many user labels
# per class as the issue's target allows, 100), ASK_CONFIDENT (per class
# about confident positives never shown, default 0: the thesis's user inspected only the
# low-confidence tracks, 2.5.2), BUFFER (unlabeled groups kept, default 1200: the thesis sized
# its 20,000 to B0's 150,000 frames, so that inducted positives and B0 are of one order of
# magnitude; this B0 has about 9,000 segments), ROUNDS (boosting rounds of the baselines, 1000),
# B0 (the background drives, default "empty:301 empty:302 empty:303"), INDUCT_ARGS (more options
# of stac induct, e.g. --dual).
set -euo pipefail
cd "$(dirname "$0")/../.."
STAC=${STAC:-build/tools/stac}
WORK=${1:-build/induction-experiment}
JOBS=${JOBS:-1}
DURATION=${DURATION:-15}
SEED_LABELS=${SEED_LABELS:-5}
ASK=${ASK:-5}
ASK_CONFIDENT=${ASK_CONFIDENT:-0}
BUFFER=${BUFFER:-1200}
ROUNDS=${ROUNDS:-1000}
read -r -a BACKGROUND <<< "${B0:-empty:301 empty:302 empty:303}"
LABELS=(urban:311)
STREAM=(urban:312 urban:313 urban:314 urban:315 urban:316 intersection:319 crowd:320
        urban:318 urban:331 urban:332 intersection:333 urban:334 urban:335 crowd:336
        urban:337 intersection:338 urban:339 parking-lot:340)
TEST=(urban:317 urban:341 intersection:342 crowd:343 urban:344)

source tools/scripts/simulated_drives.sh
induction_drives

# train_scored NAME DATA_OPTION...: `stac train` on the datasets into WORK/NAME.stacmodel (its
# output also in WORK/NAME.log), scored on the held-out drives (report WORK/NAME/); sets acc
# (track accuracy) and tracks (what it was trained on, from stac train's first line).
train_scored() {
  local name=$1
  shift
  "$STAC" train "$@" --rounds "$ROUNDS" --out "$WORK/$name.stacmodel" 2>&1 | tee "$WORK/$name.log"
  "$STAC" eval --classes "${test_data[@]}" --model "$WORK/$name.stacmodel" --report "$WORK/$name"
  acc=$(sed -n 's/.*"track_accuracy": *\([0-9.]*\).*/\1/p' "$WORK/$name/metrics.json" | head -n 1)
  tracks=$(sed -n 's/^stac train: \([0-9]* tracks ([^;]*\);.*/\1)/p' "$WORK/$name.log")
}

# Fully supervised with fewer labels (the thesis's Fig. 2.5): every label of the first N of the
# labels' and the stream's drives, and B0; then (b), every label of all of them, and B0. A line
# each in supervised_curve.tsv.
drives=("${LABELS[@]}" "${STREAM[@]}")
printf 'drives\ttracks\ttrack_accuracy\n' > "$WORK/supervised_curve.tsv"
for n in 1 2 4 8; do
  mapfile -t part < <(dataset_options --data "${BACKGROUND[@]}" "${drives[@]:0:n}")
  train_scored "supervised_$n" "${part[@]}" > /dev/null
  printf '%s\t%s\t%s\n' "$n" "$tracks" "$acc" >> "$WORK/supervised_curve.tsv"
done
train_scored supervised_all "${everything[@]}"
printf '%s\t%s\t%s\n' "${#drives[@]}" "$tracks" "$acc" >> "$WORK/supervised_curve.tsv"
all_acc=$acc

# Group induction, the oracle answering; after each round, the same labels without induction.
rm -rf "$WORK/state"
# shellcheck disable=SC2086  # INDUCT_ARGS: words
"$STAC" induct --state "$WORK/state" --classes car,pedestrian,bicyclist "${bg[@]}" "${labels[@]}" \
  --baseline \
  --labels-per-class "$SEED_LABELS" "${stream[@]}" --rounds 2 --oracle --ask "$ASK" \
  --ask-confident "$ASK_CONFIDENT" --buffer "$BUFFER" ${INDUCT_ARGS:-} "${test[@]}" \
  --export "$WORK/user_labels"
"$STAC" eval --classes "${test_data[@]}" --model "$WORK/state/model.stacmodel" \
  --report "$WORK/group_induction"

# (a) the same user labels and B0, no induction.
train_scored supervised_labels --data "$WORK/user_labels"
labels_acc=$acc

# The chart again, with the baselines as lines.
"$STAC" induct --state "$WORK/state" --reference "stac train, every label (b)=$all_acc" \
  --reference "stac train, final user labels (a)=$labels_acc"
echo "$0: $WORK/state/learning.png; history $WORK/state/history.jsonl; reports in" \
  "$WORK/{group_induction,supervised_labels,supervised_all}/metrics.json"
