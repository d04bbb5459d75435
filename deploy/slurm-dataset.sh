#!/usr/bin/env bash
# A fleet's captures into one track dataset on a Slurm cluster: one `stac dataset` per capture as
# a job array, then one job that joins the parts (`stac dataset --merge`) when all have succeeded.
#
# Usage: slurm-dataset.sh --list CAPTURES.txt --out DIR [options] [-- sbatch options...]
#   --list FILE        one capture per line: `CAPTURE [TRUTH.jsonl]`, CAPTURE a .pcap or a KITTI
#                      raw drive folder (with a truth file the tracks are labelled; all lines with
#                      one or all without). A TAB separates capture and truth; without a TAB, a
#                      line that names an existing capture is that capture (spaces and all), else
#                      a space does (`a.pcap a.jsonl`: two paths without spaces; a line that reads
#                      both ways is refused). Spaces around a path, CR line ends and a byte order
#                      mark are dropped; blank lines and lines starting with # are skipped (write
#                      ./#name for such a file). Relative paths: relative to FILE.
#   --out DIR          DIR/parts/NNNNN/ (one dataset per capture, with its log), then DIR/tracks.bin
#                      and DIR/manifest.json: the merged dataset (`stac train --data DIR`)
#   --stac PATH        the stac executable the nodes run (default: `stac` on PATH, else this
#                      source tree's build/tools/stac)
#   --parallel N       at most N tasks at once (sbatch --array=...%N; default: no limit)
#   --dataset-args "A" more options for every `stac dataset` (e.g. "--class pole --no-deskew"),
#                      split at spaces
#   --dataset-arg W    one more word for every `stac dataset`, spaces and all (repeatable, in
#                      order with --dataset-args: --dataset-arg --config --dataset-arg "my c.yaml")
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
# Words as a shell reads them back: the dry run's and the logs' command lines.
quoted() { local q; printf -v q '%q ' "$@"; echo "${q% }"; }
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
self=$here/$(basename "${BASH_SOURCE[0]}")

mode=submit list="" out="" stac="" parallel="" dataset_args=() sbatch_extra=()
# The value of option $1, the next word $2 (absent when $# is 1): refused when missing, empty, or
# an option (a path that starts with - is written ./-name). --dataset-args and --dataset-arg take
# options.
value() {
  (($# > 1)) || usage_error "$1 needs a value"
  [[ -n $2 || $1 == --dataset-args ]] || usage_error "$1 needs a value, not an empty word"
  [[ $1 == --dataset-arg* || $2 != -* ]] || usage_error "$1 needs a value, not the option '$2'"
}
while (($#)); do
  case $1 in
    --list) value "$@"; list=$2; shift 2 ;;
    --out) value "$@"; out=$2; shift 2 ;;
    --stac) value "$@"; stac=$2; shift 2 ;;
    --parallel) value "$@"; parallel=$2; shift 2 ;;
    # Words split at spaces (no glob), as on a command line.
    --dataset-args) value "$@"; read -ra words <<< "$2"; dataset_args+=("${words[@]}"); shift 2 ;;
    # One word as given.
    --dataset-arg) value "$@"; dataset_args+=("$2"); shift 2 ;;
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

# $1 without the spaces (and CRs) around it.
trim() {
  local s=$1
  s=${s#"${s%%[![:space:]]*}"}
  printf '%s' "${s%"${s##*[![:space:]]}"}"
}

# A capture: a file (a pcap) or a KITTI raw drive folder (what `stac dataset --in` takes).
is_capture() { [[ -f $1 || -d $1/velodyne_points/data ]]; }
# Path $1 of the list, absolute: relative to the list's folder, $base.
absolute() { if [[ $1 == /* ]]; then printf '%s' "$1"; else printf '%s/%s' "$base" "$1"; fi; }

# The list, as absolute "capture<TAB>truth" lines: DIR/captures.txt once submitted.
read_list() {
  local file=$1 base n=0 line capture truth whole fields
  base=$(cd "$(dirname "$file")" && pwd)
  while IFS= read -r line || [[ -n $line ]]; do
    n=$((n + 1))
    ((n > 1)) || line=${line#$'\xef\xbb\xbf'}  # a byte order mark (Windows editors)
    line=${line%$'\r'}
    [[ -z ${line//[[:space:]]/} || $line =~ ^[[:space:]]*# ]] && continue
    if [[ $line == *$'\t'* ]]; then  # CAPTURE<TAB>TRUTH: spaces inside the paths are theirs
      capture=$(trim "${line%%$'\t'*}") truth=$(trim "${line#*$'\t'}")
      [[ $truth != *$'\t'* ]] || die "$file:$n: a line is CAPTURE<TAB>TRUTH, not three fields"
      [[ -n $capture ]] || die "$file:$n: no capture before the TAB"
    else
      # One path (spaces and all) if it names a capture, else `CAPTURE TRUTH` split at a space;
      # refused when both would do.
      whole=$(absolute "$(trim "$line")")
      read -ra fields <<< "$line"
      if ((${#fields[@]} == 2)) && is_capture "$whole" &&
        is_capture "$(absolute "${fields[0]}")" && [[ -f $(absolute "${fields[1]}") ]]; then
        die "$file:$n: '$(trim "$line")' is a capture, and a capture and its truth file: put a" \
          "TAB after the capture (then its truth file, if any)"
      elif is_capture "$whole" || ((${#fields[@]} == 1)); then
        capture=$(trim "$line") truth=""
      elif ((${#fields[@]} == 2)); then
        capture=${fields[0]} truth=${fields[1]}
      else
        die "$file:$n: no capture '$(trim "$line")', and more than two words: put a TAB between" \
          "the capture and its truth file when a path holds a space"
      fi
    fi
    capture=$(absolute "$capture")
    is_capture "$capture" || die "$file:$n: no capture $capture (a file, or a KITTI raw drive" \
      "folder: one with velodyne_points/data)"
    if [[ -n $truth ]]; then
      truth=$(absolute "$truth")
      [[ -f $truth ]] || die "$file:$n: no truth file $truth"
    fi
    [[ $capture$truth != *[$'\t\n']* ]] || die "$file:$n: a path with a TAB or a line break"
    printf '%s%s\n' "$capture" "${truth:+$'\t'$truth}"
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
  local line capture truth part args cmd
  line=$(sed -n "$((id + 1))p" "$out/captures.txt")
  [[ -n $line ]] || die "task $id: $out/captures.txt has no line $((id + 1))"
  IFS=$'\t' read -r capture truth <<< "$line"
  part=$(printf '%s/parts/%05d' "$out" "$id")
  rm -rf "$part" && mkdir -p "$part"
  cmd=("$(cat "$out/stac.path")" dataset --in "$capture")
  [[ -z $truth ]] || cmd+=(--truth "$truth")
  cmd+=(--out "$part")
  mapfile -d '' -t args < "$out/dataset-args"
  cmd+=("${args[@]}")
  echo "task $id on $(hostname): $(quoted "${cmd[@]}")" > "$part/log"
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
    [[ -f $part/done ]] ||
      die "part $k ($(sed -n "$((k + 1))p" "$out/captures.txt" | tr '\t' ' ')) is not done: see $part/log"
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
with_truth=$(grep -c $'\t' <<< "$captures" || true)
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
  quoted "${submit_array[@]}"
  merge=$(quoted "${submit_merge[@]}")
  echo "${merge/--parsable/--parsable --dependency=afterok:<array job>}"
  k=0
  while IFS=$'\t' read -r capture truth; do
    cmd=("$stac_path" dataset --in "$capture")
    [[ -z $truth ]] || cmd+=(--truth "$truth")
    cmd+=(--out "$(printf '%s/parts/%05d' "$out" "$k")" "${dataset_args[@]}")
    echo "task $k: $(quoted "${cmd[@]}")"
    k=$((k + 1))
  done <<< "$captures"
  echo "merge: $(quoted "$stac_path" dataset --merge "$out/parts/00000") ... --out $(quoted "$out")"
  exit 0
fi

# What the tasks and the merge read: the list, the executable, the options.
mkdir -p "$out"
echo "$captures" > "$out/captures.txt"
echo "$stac_path" > "$out/stac.path"
# NUL-separated words (printf of no word would write one empty word)
: > "$out/dataset-args"
((${#dataset_args[@]} == 0)) || printf '%s\0' "${dataset_args[@]}" > "$out/dataset-args"
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
