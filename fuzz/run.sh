#!/usr/bin/env bash
# Builds the libFuzzer harnesses (clang, AddressSanitizer + UBSan) and runs each over its corpus
# (docs/reliability.md "Fuzzing").
#   fuzz/run.sh [SECONDS]      each harness for SECONDS (default 60), new inputs into a scratch
#                              corpus beside the seeds; a per-target line: executions, coverage,
#                              crashes
#   fuzz/run.sh --regress      each harness once over its seed corpus (CI)
#   fuzz/run.sh --campaign RUNS [TARGET...]
#                              a long campaign, resumable: each harness (or those named) runs in
#                              chunks of at most CHUNK (default 1 M) executions until its
#                              ledger, fuzz/campaign/TARGET.tsv (in git, so a campaign goes on
#                              across machines; a line per chunk: UTC end, runs, seconds,
#                              coverage, crashes), adds up to RUNS; run it under `nice`
#                              beside other work, stop it at any time (the chunk in progress is
#                              lost, the corpus it grew is kept); an input's time limit is 120 s,
#                              not 10, as a niced process waits behind the rest of the machine;
#                              campaign runs take ASAN_OPTIONS without quarantine and malloc
#                              contexts (1.4x faster; rerun a crash input by hand for its stacks);
#                              a second campaign on the same target may run beside it from
#                              another build tree (BUILD=build-fuzz2), one core each: both add
#                              to the one ledger, read again before every chunk
# fuzz/dict/TARGET.dict is a harness's dictionary; fuzz/options/TARGET.options holds more libFuzzer
# flags for it, one a line (e.g. -max_len=8448), used when fuzzing, not by --regress.
# A crash, a leak-free sanitizer report or a timeout leaves its input in build-fuzz/crashes/ and
# makes the script fail. Environment: BUILD (build-fuzz), JOBS (nproc).
set -euo pipefail
cd "$(dirname "$0")/.."
mode=time
seconds=60
campaign_runs=0
if [[ ${1:-} == --regress ]]; then
  mode=regress
elif [[ ${1:-} == --campaign ]]; then
  mode=campaign
  campaign_runs=${2:?"fuzz/run.sh --campaign RUNS [TARGET...]: how many executions per target"}
  [[ $campaign_runs =~ ^[1-9][0-9]*$ ]] || { echo "fuzz/run.sh: RUNS must be a positive count, not '$campaign_runs'" >&2; exit 2; }
elif [[ -n ${1:-} ]]; then
  seconds=$1
fi
build=${BUILD:-build-fuzz}
jobs=${JOBS:-$(nproc)}
targets=(velodyne_stream_fuzz applanix_stream_fuzz can_text_fuzz model_file_fuzz json_lines_fuzz
         config_files_fuzz pcap_file_fuzz dataset_file_fuzz gs_usb_frame_fuzz candump_file_fuzz
         velodyne_status_fuzz cannelloni_fuzz kitti_text_fuzz velodyne_position_fuzz
         calibration_xml_fuzz view_client_fuzz induction_state_fuzz label_http_fuzz)

# fuzz/options/TARGET.options: more libFuzzer flags, one a line (blank lines and # comments
# skipped), appended to the array named by $2. Not in --regress, which replays every seed whole.
add_options() {
  local -n into=$2
  [[ -f fuzz/options/$1.options ]] || return 0
  local line
  while IFS= read -r line || [[ -n $line ]]; do
    line=${line%$'\r'}
    [[ -z $line || $line == \#* ]] && continue
    into+=("$line")
  done < "fuzz/options/$1.options"
}

# Seeds: fuzz/corpus/TARGET (in git: made from the project's files, and every crash input) and
# $build/seeds/TARGET, cut from ../shared/data at each run (kept out of the repository).
rm -rf "$build/seeds"
python3 fuzz/make_seeds.py --shared "$build/seeds"
seed_dirs() {  # the seed folders of harness $1 that exist, into the array named by $2
  local -n into=$2
  local d
  for d in "$build/seeds/$1" "fuzz/corpus/$1"; do [[ -d $d ]] && into+=("$d"); done
  return 0
}
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_C_COMPILER=clang-14 -DCMAKE_CXX_COMPILER=clang++-14 \
  -DCMAKE_CXX_FLAGS=-fsanitize=fuzzer-no-link -DSTAC_SANITIZE=address -DSTAC_FUZZ=ON \
  -DBUILD_TESTING=OFF -DSTAC_BUILD_BENCHMARKS=OFF >/dev/null
cmake --build "$build" -j "$jobs" --target "${targets[@]}"

mkdir -p "$build/crashes"
failed=0
export ASAN_OPTIONS=detect_leaks=0:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1

if [[ $mode == campaign ]]; then
  chosen=("${@:3}")
  [[ ${#chosen[@]} -gt 0 ]] || chosen=("${targets[@]}")
  mkdir -p "$build/campaign" fuzz/campaign
  chunk_max=${CHUNK:-1000000}
  [[ $chunk_max =~ ^[1-9][0-9]*$ ]] || { echo "fuzz/run.sh: CHUNK must be a positive count, not '$chunk_max'" >&2; exit 2; }
  printf '%-22s %12s %10s %8s %s\n' target executions seconds cov crashes
  for t in "${chosen[@]}"; do
    [[ " ${targets[*]} " == *" $t "* ]] || { echo "fuzz/run.sh: no harness '$t' (${targets[*]})" >&2; exit 2; }
    ledger="fuzz/campaign/$t.tsv"
    dict=()
    [[ -f fuzz/dict/$t.dict ]] && dict=(-dict="fuzz/dict/$t.dict")
    add_options "$t" dict
    seeds=()
    seed_dirs "$t" seeds
    mkdir -p "$build/corpus/$t"
    while :; do
      done_runs=$(awk -F'\t' '{s += $2} END {print s + 0}' "$ledger" 2>/dev/null || echo 0)
      ((done_runs < campaign_runs)) || break
      chunk=$((campaign_runs - done_runs < chunk_max ? campaign_runs - done_runs : chunk_max))
      log="$build/campaign/$t.log"
      start=$(date +%s)
      crashes=0
      ASAN_OPTIONS="$ASAN_OPTIONS:quarantine_size_mb=0:malloc_context_size=0:max_malloc_fill_size=0" \
        "$build/fuzz/$t" "${dict[@]}" -artifact_prefix="$build/crashes/$t-" -print_final_stats=1 \
        -runs="$chunk" -timeout=120 -rss_limit_mb=4096 "$build/corpus/$t" "${seeds[@]}" \
        >"$log" 2>&1 || crashes=1
      runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
      cov=$(grep -o 'cov: [0-9]*' "$log" | tail -1 | cut -d' ' -f2)
      printf '%s\t%s\t%s\t%s\t%s\n' "$(date -u +%FT%TZ)" "${runs:-0}" "$(($(date +%s) - start))" \
        "${cov:-0}" "$crashes" >>"$ledger"
      if [[ $crashes != 0 ]]; then failed=1; cp "$log" "$build/crashes/$t-campaign.log"; break; fi
    done
    awk -F'\t' -v t="$t" '{r += $2; s += $3; c = $4; x += $5}
      END {printf "%-22s %12d %10d %8d %s\n", t, r, s, c, x}' "$ledger"
  done
  exit $failed
fi
printf '%-22s %12s %10s %8s %s\n' target executions seconds cov crashes
for t in "${targets[@]}"; do
  log="$build/$t.log"
  seeds=()
  seed_dirs "$t" seeds
  if [[ $mode == regress ]]; then
    args=(-runs=0 "${seeds[@]}")
  else
    mkdir -p "$build/corpus/$t"
    args=(-max_total_time="$seconds" -timeout=10 -rss_limit_mb=4096 "$build/corpus/$t" "${seeds[@]}")
  fi
  dict=()
  [[ -f fuzz/dict/$t.dict ]] && dict=(-dict="fuzz/dict/$t.dict")
  [[ $mode == regress ]] || add_options "$t" dict
  start=$(date +%s)
  if "$build/fuzz/$t" "${dict[@]}" -artifact_prefix="$build/crashes/$t-" -print_final_stats=1 \
      "${args[@]}" >"$log" 2>&1; then
    crashes=0
  else
    crashes=1
    failed=1
  fi
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  cov=$(grep -o 'cov: [0-9]*' "$log" | tail -1 | cut -d' ' -f2)
  printf '%-22s %12s %10s %8s %s\n' "$t" "${runs:-?}" "$(($(date +%s) - start))" "${cov:-?}" \
    "$([[ $crashes == 0 ]] && echo 0 || echo "see $log")"
done
exit $failed
