#!/usr/bin/env bash
# A fleet's captures into one track dataset on a Slurm cluster: one `stac dataset` per capture as
# a job array, then one job that joins the parts (`stac dataset --merge`) when all have succeeded.
#
# Usage: slurm-dataset.sh --list CAPTURES.txt --out DIR [options] [-- sbatch options...]
#   --list FILE        one capture per line: `CAPTURE.pcap [TRUTH.jsonl]` (with a truth file the
#                      tracks are labelled; all lines with one or all without). Blank lines and
#                      lines starting with # are skipped. Relative paths: relative to FILE.
#   --out DIR          DIR/parts/NNNNN/ (one dataset per capture, with its log), then DIR/tracks.bin
#                      and DIR/manifest.json: the merged dataset (`stac train --data DIR`)
#   --stac PATH        the stac executable the nodes run (default: `stac` on PATH, else this
#                      source tree's build/tools/stac)
#   --parallel N       at most N tasks at once (sbatch --array=...%N; default: no limit)
#   --dataset-args "A" more options for every `stac dataset` (e.g. "--class pole --no-deskew")
#   --dry-run          print the sbatch commands and each task's command line, submit nothing
#   --local            run the tasks and the merge here, one after the other, without Slurm (the
#                      same steps a node runs: for a machine without a cluster, and the tests)
# An option without its value, or an unknown one, stops it with rc 2 (1: a bad list, a failure).
# Every option after -- goes to both sbatch calls (--partition, --time, --mem, --account...).
# Prints the array job's id and the merge job's id; `squeue -u $USER` follows them, and
# DIR/parts/NNNNN/log holds each task's output.
#
# The nodes run `slurm-dataset.sh --task` and `--merge` (with the list's copy in DIR); they need
# the captures, DIR and stac at the same paths (a shared file system).
set -euo pipefail

usage() { awk 'NR > 1 && !/^#/ { exit } NR > 1' "$0" | sed 's/^# \{0,1\}//'; exit 0; }
die() { echo "slurm-dataset: $*" >&2; exit 1; }
# A wrong command line: rc 2, nothing made.
usage_error() { printf 'slurm-dataset: %s (--help: the usage)\n' "$*" >&2; exit 2; }
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
self=$here/$(basename "${BASH_SOURCE[0]}")

mode=submit list="" out="" stac="" parallel="" dataset_args="" sbatch_extra=()
# The value of option $1, the next word $2 (absent when $# is 1): refused when missing, empty, or
# an option (a path that starts with - is written ./-name). --dataset-args takes options.
value() {
  (($# > 1)) || usage_error "$1 needs a value"
  [[ -n $2 || $1 == --dataset-args ]] || usage_error "$1 needs a value, not an empty word"
  [[ $1 == --dataset-args || $2 != -* ]] || usage_error "$1 needs a value, not the option '$2'"
}
while (($#)); do
  case $1 in
    --list) value "$@"; list=$2; shift 2 ;;
    --out) value "$@"; out=$2; shift 2 ;;
    --stac) value "$@"; stac=$2; shift 2 ;;
    --parallel) value "$@"; parallel=$2; shift 2 ;;
    --dataset-args) value "$@"; dataset_args=$2; shift 2 ;;
    --dry-run) mode=dry-run; shift ;;
    --local) mode=local; shift ;;
    --task) mode=task; shift ;;
    --merge) mode=merge; shift ;;
    -h | --help) usage ;;
    --) shift; sbatch_extra=("$@"); break ;;
    *) usage_error "unknown option '$1'" ;;
  esac
done
[[ -n $out ]] || usage_error "--out DIR is required (where the parts and the merged dataset go)"
[[ -z $parallel || $parallel =~ ^[1-9][0-9]*$ ]] ||
  usage_error "--parallel needs a positive number, not '$parallel'"

# The list, as absolute "capture truth" lines: DIR/captures.txt once submitted.
read_list() {
  local file=$1 base n=0 line capture truth extra
  base=$(cd "$(dirname "$file")" && pwd)
  while IFS= read -r line || [[ -n $line ]]; do
    n=$((n + 1))
    [[ -z ${line//[[:space:]]/} || $line =~ ^[[:space:]]*# ]] && continue
    read -r capture truth extra <<< "$line"
    [[ -z ${extra:-} ]] || die "$file:$n: a line is 'CAPTURE [TRUTH]', not three fields"
    [[ $capture == /* ]] || capture=$base/$capture
    [[ -f $capture ]] || die "$file:$n: no capture $capture"
    if [[ -n ${truth:-} ]]; then
      [[ $truth == /* ]] || truth=$base/$truth
      [[ -f $truth ]] || die "$file:$n: no truth file $truth"
    fi
    echo "$capture${truth:+ $truth}"
  done < "$file"
}

# The stac the nodes run: an absolute path.
find_stac() {
  if [[ -n $stac ]]; then
    [[ -x $stac ]] || die "--stac $stac is not an executable"
    echo "$(cd "$(dirname "$stac")" && pwd)/$(basename "$stac")"
  elif command -v stac > /dev/null; then
    command -v stac
  elif [[ -x $here/../build/tools/stac ]]; then
    echo "$(cd "$here/../build/tools" && pwd)/stac"
  else
    die "no stac on PATH or in build/tools: give --stac PATH"
  fi
}

# One task: line SLURM_ARRAY_TASK_ID of DIR/captures.txt into DIR/parts/NNNNN.
run_task() {
  local id=${SLURM_ARRAY_TASK_ID:?--task runs inside a Slurm array job (SLURM_ARRAY_TASK_ID)}
  local line capture truth part
  line=$(sed -n "$((id + 1))p" "$out/captures.txt")
  [[ -n $line ]] || die "task $id: $out/captures.txt has no line $((id + 1))"
  read -r capture truth <<< "$line"
  part=$(printf '%s/parts/%05d' "$out" "$id")
  rm -rf "$part" && mkdir -p "$part"
  local cmd=("$(cat "$out/stac.path")" dataset --in "$capture" ${truth:+--truth "$truth"} --out "$part")
  # shellcheck disable=SC2206  # the extra options are words, as on a command line
  cmd+=($(cat "$out/dataset-args"))
  echo "task $id on $(hostname): ${cmd[*]}" > "$part/log"
  if ! "${cmd[@]}" >> "$part/log" 2>&1; then
    echo "slurm-dataset: task $id failed: $capture (log: $part/log)" >&2
    tail -5 "$part/log" >&2
    exit 1
  fi
  touch "$part/done"
}

# The merge: every part must be done; their datasets join into DIR.
run_merge() {
  local n parts=() k part
  n=$(wc -l < "$out/captures.txt")
  for ((k = 0; k < n; k++)); do
    part=$(printf '%s/parts/%05d' "$out" "$k")
    [[ -f $part/done ]] || die "part $k ($(sed -n "$((k + 1))p" "$out/captures.txt")) is not done: see $part/log"
    parts+=(--merge "$part")
  done
  "$(cat "$out/stac.path")" dataset "${parts[@]}" --out "$out"
}

case $mode in
  task) run_task; exit 0 ;;
  merge) run_merge; exit 0 ;;
esac

[[ -n $list ]] || usage_error "--list CAPTURES.txt is required"
[[ -f $list ]] || die "no list file $list"
captures=$(read_list "$list")
n=$(grep -c . <<< "$captures" || true)
((n > 0)) || die "$list names no capture"
with_truth=$(awk 'NF == 2' <<< "$captures" | wc -l)
((with_truth == 0 || with_truth == n)) ||
  die "$list: $with_truth of $n captures have a truth file: all or none (labelled or unlabeled)"
stac_path=$(find_stac)

out=$(realpath -m "$out")
array="0-$((n - 1))${parallel:+%$parallel}"
submit_array=(sbatch --parsable --job-name=stac-dataset --array="$array"
  --output="$out/parts/slurm-%A_%a.out" "${sbatch_extra[@]}" "$self" --task --out "$out")
submit_merge=(sbatch --parsable --job-name=stac-dataset-merge --output="$out/merge.out"
  "${sbatch_extra[@]}" "$self" --merge --out "$out")

if [[ $mode == dry-run ]]; then
  echo "$n captures -> $out"
  echo "${submit_array[*]}"
  echo "${submit_merge[*]/--parsable/--parsable --dependency=afterok:<array job>}"
  k=0
  while read -r capture truth; do
    printf 'task %d: %s dataset --in %s%s --out %s/parts/%05d%s\n' "$k" "$stac_path" "$capture" \
      "${truth:+ --truth $truth}" "$out" "$k" "${dataset_args:+ $dataset_args}"
    k=$((k + 1))
  done <<< "$captures"
  echo "merge: $stac_path dataset --merge $out/parts/00000 ... --out $out"
  exit 0
fi

# What the tasks and the merge read: the list, the executable, the options.
mkdir -p "$out"
echo "$captures" > "$out/captures.txt"
echo "$stac_path" > "$out/stac.path"
echo "$dataset_args" > "$out/dataset-args"
mkdir -p "$out/parts"

if [[ $mode == local ]]; then
  for ((k = 0; k < n; k++)); do
    SLURM_ARRAY_TASK_ID=$k "$self" --task --out "$out"
    echo "slurm-dataset: part $((k + 1))/$n done"
  done
  "$self" --merge --out "$out"
  exit 0
fi

command -v sbatch > /dev/null || die "sbatch not found: is this a Slurm login node? (--local runs here)"
array_id=$("${submit_array[@]}") || die "sbatch of the array failed"
array_id=${array_id%%;*}
merge_id=$("${submit_merge[@]:0:2}" --dependency=afterok:"$array_id" "${submit_merge[@]:2}") ||
  die "sbatch of the merge failed (the array $array_id runs; cancel it with scancel $array_id)"
echo "array job $array_id ($n tasks), merge job ${merge_id%%;*} after it; the dataset: $out"
