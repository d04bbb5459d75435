#!/usr/bin/env bash
# The new-class experiment of docs/learning.md: teach the shipped model a class it does not have
# (a kind of the simulator's background objects, trees by default) with group induction and at
# most a hundred user labels, its own three classes kept as they are (`stac induct --model ...
# --add-classes tree`). B0 is drives without that kind (`stac sim --without tree`); the first
# labels are 5 of the kind and 5 background tracks of one drive; a stream of unlabeled drives,
# one chunk a round, the oracle answering the questions about the new class; then every model
# scored on held-out drives: the shipped model (the kind is background to it), the taught one,
# and (b) `stac train` on every label of every drive with the four classes. No test uses these
# seeds.
#
#   tools/scripts/new_class_experiment.sh [WORK_DIR]     (default: build/new-class-experiment)
#
# Environment: CLASS (the simulator kind taught, default tree; a pole is rarely a track of its
# own), STAC (default build/tools/stac), MODEL (default config/models/stac_default.stacmodel),
# JOBS (drives made in parallel, default 1), DURATION (s per drive, default 30), SEED_LABELS
# (tracks of the kind and of background to start with, default 5), ASK (questions per kind after
# each chunk, default 4), ROUNDS (boosting rounds of (b), default 1000).
set -euo pipefail
cd "$(dirname "$0")/../.."
STAC=${STAC:-build/tools/stac}
MODEL=${MODEL:-config/models/stac_default.stacmodel}
WORK=${1:-build/new-class-experiment}
JOBS=${JOBS:-1}
CLASS=${CLASS:-tree}
DURATION=${DURATION:-30}
SEED_LABELS=${SEED_LABELS:-5}
ASK=${ASK:-4}
ROUNDS=${ROUNDS:-1000}
DATASET_ARGS="--class $CLASS"
BACKGROUND=("empty:401:$CLASS" "empty:402:$CLASS" "urban:403:$CLASS")
LABELS=(urban:411)
STREAM=(urban:412 urban:413 intersection:414 parking-lot:415 urban:416 urban:417
        intersection:418 urban:419 parking-lot:420 urban:421 crowd:422 urban:423)
TEST=(urban:431 urban:432 intersection:433 parking-lot:434)

source tools/scripts/simulated_drives.sh
echo "$0: teaching '$CLASS'"
induction_drives

# The shipped model on the held-out drives: the new kind is background to it.
"$STAC" eval --classes "${test_data[@]}" --model "$MODEL" --report "$WORK/shipped"

# (b) fully supervised, four classes: every label of the labels' and the stream's drives, and B0.
"$STAC" train "${everything[@]}" --rounds "$ROUNDS" --out "$WORK/supervised_all.stacmodel"
"$STAC" eval --classes "${test_data[@]}" --model "$WORK/supervised_all.stacmodel" \
  --report "$WORK/supervised_all"

# Group induction from the shipped model, the new class added, the oracle answering.
rm -rf "$WORK/state"
"$STAC" induct --state "$WORK/state" --model "$MODEL" --add-classes "$CLASS" "${bg[@]}" \
  "${labels[@]}" --labels-per-class "$SEED_LABELS" "${stream[@]}" --rounds 2 --oracle \
  --ask "$ASK" "${test[@]}" --baseline
"$STAC" eval --classes "${test_data[@]}" --model "$WORK/state/model.stacmodel" \
  --report "$WORK/taught"

# The table of docs/learning.md: one-vs-all track accuracy (ADBF) per class, and the new
# class's precision and recall from the confusion matrix.
node - "$WORK" "$CLASS" <<'EOF'
const fs = require('fs');
const [work, taught] = process.argv.slice(2);
const read = (name) => JSON.parse(fs.readFileSync(`${work}/${name}/metrics.json`));
const row = (name, what) => {
  const m = read(name);
  const cells = ['car', 'pedestrian', 'bicyclist', taught].map((c) =>
    m[`track.adbf.${c}`] === undefined ? '-' : m[`track.adbf.${c}`].toFixed(3));
  let pr = '-';
  const k = m.classes.indexOf(taught);
  if (k >= 0) {
    const c = m.track_confusion_adbf;
    const tp = c[k][k];
    const predicted = c.reduce((s, r) => s + r[k], 0);
    const actual = c[k].reduce((s, v) => s + v, 0);
    pr = `${(tp / Math.max(1, predicted)).toFixed(3)} / ${(tp / Math.max(1, actual)).toFixed(3)}`;
  }
  console.log(`| ${what} | ${cells.join(' | ')} | ${pr} | ${m.tracks} |`);
};
const labels = fs.readFileSync(`${work}/state/labels.jsonl`, 'utf8').trim().split('\n')
  .map((l) => JSON.parse(l));
const per = {};
for (const a of labels) per[a.label] = (per[a.label] || 0) + 1;
console.log(`user labels: ${JSON.stringify(per)}`);
console.log(`| model | car | pedestrian | bicyclist | ${taught} | ${taught} precision / recall | tracks |`);
console.log('|---|---|---|---|---|---|---|');
row('shipped', `shipped model (three classes; ${taught} is background to it)`);
row('taught', `shipped model + ${taught} by group induction`);
row('supervised_all', '(b) `stac train`, every label, four classes');
EOF
echo "$0: reports in $WORK/{shipped,taught,supervised_all}/metrics.json; history" \
  "$WORK/state/history.jsonl"
