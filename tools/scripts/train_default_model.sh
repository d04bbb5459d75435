#!/usr/bin/env bash
# Reproduces the shipped track classifier, config/models/stac_default.stacmodel, from simulated
# drives: `stac sim` -> `stac dataset` per drive, `stac train` on the training drives, and
# `stac eval --classes` on held-out drives (docs/classification.md, "The default model").
# Deterministic: the same binary gives the same model bytes.
#
#   tools/scripts/train_default_model.sh [WORK_DIR]     (default: build/default-model)
#
# Environment: STAC (the binary, default build/tools/stac), JOBS (drives simulated and described
# in parallel, default 1), DURATION (s per drive, default 20), OUT (the model file written, default
# config/models/stac_default.stacmodel).
set -euo pipefail
cd "$(dirname "$0")/../.."
STAC=${STAC:-build/tools/stac}
WORK=${1:-build/default-model}
JOBS=${JOBS:-1}
DURATION=${DURATION:-20}
OUT=${OUT:-config/models/stac_default.stacmodel}
# scenario:seed. No test uses these seeds, and nothing but this evaluation uses the held-out ones.
TRAIN=(urban:101 urban:102 urban:103 urban:104 urban:105 urban:106 urban:107 urban:108
       urban:109 urban:110 urban:111 urban:112 urban:113 urban:114 urban:115 urban:116
       urban:117 urban:118 urban:119 urban:120 urban:125 urban:126 urban:127 urban:128
       intersection:121 intersection:122 intersection:123 intersection:124
       crowd:131 crowd:132 parking-lot:141 parking-lot:142 highway:151 empty:161 empty:162
       crowd:194 highway:193 intersection:187 intersection:188 intersection:189 intersection:190
       parking-lot:191 parking-lot:192 urban:171 urban:172 urban:173 urban:174 urban:175
       urban:176 urban:177 urban:178 urban:179 urban:180 urban:181 urban:182 urban:183
       urban:184 urban:185 urban:186)
TEST=(urban:201 urban:202 urban:203 urban:204 intersection:221 empty:261)

source tools/scripts/simulated_drives.sh
echo "$0: ${#TRAIN[@]} training and ${#TEST[@]} held-out drives of ${DURATION} s in $WORK"
make_drives "${TRAIN[@]}" "${TEST[@]}"

train_args=() test_args=()
for d in "${TRAIN[@]}"; do train_args+=(--data "$WORK/$d/data"); done
for d in "${TEST[@]}"; do test_args+=(--data "$WORK/$d/data"); done
mkdir -p "$(dirname "$OUT")"
"$STAC" train "${train_args[@]}" --rounds 10000 --ensemble 4 --out "$OUT"
"$STAC" eval --classes "${test_args[@]}" --model "$OUT" --report "$WORK/eval"
echo "$0: model $OUT; held-out figures $WORK/eval/metrics.json (tracks.csv, confusion.png, pr.png)"
