#!/usr/bin/env bash
# Builds the libFuzzer harnesses (clang, AddressSanitizer + UBSan) and runs each over its corpus
# (docs/reliability.md "Fuzzing").
#   fuzz/run.sh [SECONDS]      each harness for SECONDS (default 60), new inputs into a scratch
#                              corpus beside the seeds; a per-target line: executions, coverage,
#                              crashes
#   fuzz/run.sh --regress      each harness once over its seed corpus (CI)
# A crash, a leak-free sanitizer report or a timeout leaves its input in build-fuzz/crashes/ and
# makes the script fail. Environment: BUILD (build-fuzz), JOBS (nproc).
set -euo pipefail
cd "$(dirname "$0")/.."
mode=time
seconds=60
if [[ ${1:-} == --regress ]]; then mode=regress; elif [[ -n ${1:-} ]]; then seconds=$1; fi
build=${BUILD:-build-fuzz}
jobs=${JOBS:-$(nproc)}
targets=(velodyne_stream_fuzz applanix_stream_fuzz can_text_fuzz model_file_fuzz json_lines_fuzz
         config_files_fuzz pcap_file_fuzz dataset_file_fuzz gs_usb_frame_fuzz candump_file_fuzz
         velodyne_status_fuzz)

if [[ ! -d fuzz/corpus ]]; then python3 fuzz/make_seeds.py; fi
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_C_COMPILER=clang-14 -DCMAKE_CXX_COMPILER=clang++-14 \
  -DCMAKE_CXX_FLAGS=-fsanitize=fuzzer-no-link -DSTAC_SANITIZE=address -DSTAC_FUZZ=ON \
  -DBUILD_TESTING=OFF -DSTAC_BUILD_BENCHMARKS=OFF >/dev/null
cmake --build "$build" -j "$jobs" --target "${targets[@]}"

mkdir -p "$build/crashes"
failed=0
export ASAN_OPTIONS=detect_leaks=0:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1
printf '%-22s %12s %10s %8s %s\n' target executions seconds cov crashes
for t in "${targets[@]}"; do
  log="$build/$t.log"
  if [[ $mode == regress ]]; then
    args=(-runs=0 "fuzz/corpus/$t")
  else
    mkdir -p "$build/corpus/$t"
    args=(-max_total_time="$seconds" -timeout=10 -rss_limit_mb=4096 "$build/corpus/$t" "fuzz/corpus/$t")
  fi
  dict=()
  [[ -f fuzz/dict/$t.dict ]] && dict=(-dict="fuzz/dict/$t.dict")
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
