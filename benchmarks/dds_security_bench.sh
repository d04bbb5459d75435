#!/usr/bin/env bash
# The cost of DDS Security (docs/benchmarks.md, "DDS Security"): the same simulated drive published
# by `stac process --dds` to `stac echo --latency` in another process, plain loopback DDS and with
# the secure configuration of deploy/dds-security.sh (authentication, access control, discovery and
# every STAC topic encrypted), in alternating runs. Prints per run the publish -> receive latency
# (p50, p99, max) of tracked_objects and the CPU seconds of the subscriber and of the publisher.
#   benchmarks/dds_security_bench.sh [BUILD_DIR] [RUNS]     (default: build 3)
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$here/build}
runs=${2:-3}
stac=$build/tools/stac
[[ -x $stac ]] || { echo "dds_security_bench: no $stac (build first)" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
export DDS_TEST_TAG="stac-security-bench-$$"
domain=$((100 + $$ % 100))

"$stac" sim --scenario urban --seed 11 --duration 30 --out "$work/run.pcap" \
  --truth "$work/run.truth.jsonl" >/dev/null 2>&1
"$here/deploy/dds-security.sh" "$work/sec" --subscriber viewer >/dev/null
plain_xml=$here/config/dds/loopback.xml

one_run() {  # one_run MODE PUBLISHER_XML SUBSCRIBER_XML
  /usr/bin/time -f "%U %S" -o "$work/echo.cpu" "$stac" echo tracked_objects --latency \
    --count "$scans" --timeout 120 --domain "$domain" --dds-config "$3" >"$work/echo.out" 2>&1 &
  local echo_pid=$!
  /usr/bin/time -f "%U %S" -o "$work/proc.cpu" "$stac" process "$work/run.pcap" \
    --tracks "$work/tracks.jsonl" --dds --dds-config "$2" --domain "$domain" --dds-wait 60 \
    >"$work/proc.out" 2>&1
  wait "$echo_pid" || true
  local lat
  lat=$(sed -n 's/.*latency over \([0-9]*\) samples: p50 \([0-9]*\) us, p99 \([0-9]*\) us, max \([0-9]*\) us.*/\1 \2 \3 \4/p' "$work/echo.out")
  [[ -n $lat ]] || { echo "dds_security_bench: $1 run: no latency line:" >&2; cat "$work/echo.out" >&2; exit 1; }
  read -r n p50 p99 max <<<"$lat"
  read -r eu es <"$work/echo.cpu"
  read -r pu ps <"$work/proc.cpu"
  awk -v m="$1" -v n="$n" -v a="$p50" -v b="$p99" -v c="$max" -v e="$eu + $es" -v p="$pu + $ps" \
    'BEGIN { split(e, x, " [+] "); split(p, y, " [+] ");
             printf "%-7s %8s %8s %8s %8s %12.2f %14.2f\n", m, n, a, b, c, x[1] + x[2], y[1] + y[2] }'
}

scans=$("$stac" process "$work/run.pcap" --tracks "$work/tracks.jsonl" 2>&1 |
  sed -n 's/.*-> .*: \([0-9]*\) complete scans.*/\1/p')
echo "dds_security_bench: $scans scans a run, $runs runs of each, domain $domain"
printf '%-7s %8s %8s %8s %8s %12s %14s\n' mode samples p50_us p99_us max_us echo_cpu_s process_cpu_s
for ((i = 0; i < runs; ++i)); do
  one_run plain "$plain_xml" "$plain_xml"
  one_run secure "$work/sec/stac/cyclonedds.xml" "$work/sec/viewer/cyclonedds.xml"
done
