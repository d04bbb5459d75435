#!/usr/bin/env bash
# The soak (issue 31; docs/reliability.md "Soak"): a simulated drive replayed forever, Velodyne
# packets and the INS stream, into `stac run` on loopback for SECONDS; resident memory sampled
# every few seconds and every health sample kept. Prints, per sixth of the run, the scans
# published, the end-to-end latency (p50, p99, max) and the resident memory, then checks:
#   - stac run is alive at the end and stops cleanly (exit 0 on SIGINT);
#   - it published at least one scan a second throughout (no hang);
#   - every complete scan was published or counted as a drop;
#   - resident memory grew less than MAX_GROWTH_KB (default 8192) after the first sixth.
# Exit 0 when all hold. CI runs a short one (ctest: Soak.ShortRun..., 60 s); the documented run
# is an hour:  tools/scripts/soak.sh 3600 /tmp/soak
# Usage: tools/scripts/soak.sh [SECONDS (default 60)] [DIR (default: a fresh temporary one)]
set -euo pipefail
here=$(cd "$(dirname "$0")/../.." && pwd)
seconds=${1:-60}
dir=${2:-$(mktemp -d /tmp/stac_soak.XXXXXX)}
rm -rf "$dir/health.txt" "$dir/rss.tsv"
STAC=${STAC:-$here/build/tools/stac}
max_growth_kb=${MAX_GROWTH_KB:-8192}
domain=${SOAK_DOMAIN:-203}
[[ $seconds =~ ^[0-9]+$ && $seconds -ge 30 ]] || { echo "soak: SECONDS must be a whole number >= 30, not '$seconds'" >&2; exit 2; }
[[ -x $STAC ]] || { echo "soak: $STAC is missing: build first (cmake --build build)" >&2; exit 2; }
# The shipped configuration's calibration is a file of ../shared/data: without it, skip (77, as
# ctest is told) like the tests that need that data.
calib=$here/../shared/data/velodyne/calib/rosdrivers_64e_s2.1-sztaki.yaml
[[ -f $calib || -n ${STAC_CONFIG:-} ]] || { echo "soak: skipped: $calib is missing (../shared/data)"; exit 77; }
mkdir -p "$dir"
echo "soak: ${seconds} s in $dir"

# Free loopback ports for the lidar (UDP) and the INS (TCP).
read -r udp ins < <(python3 - <<'EOF' 2>/dev/null || echo "$((20000 + RANDOM % 10000)) $((30000 + RANDOM % 10000))"
import socket
u = socket.socket(socket.AF_INET, socket.SOCK_DGRAM); u.bind(("127.0.0.1", 0))
t = socket.socket(socket.AF_INET, socket.SOCK_STREAM); t.bind(("127.0.0.1", 0))
print(u.getsockname()[1], t.getsockname()[1])
EOF
)

if ! "$STAC" sim --scenario urban --seed 5 --duration 20 --out "$dir/drive.pcap" \
  --truth "$dir/drive.jsonl" > "$dir/sim.log" 2>&1; then
  echo "soak: stac sim failed:" >&2
  tail -n 3 "$dir/sim.log" >&2
  exit 1
fi
dds=(--dds-config "$here/config/dds/loopback.xml" --domain "$domain")
pids=()
cleanup() { for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done; }
trap cleanup EXIT
"$STAC" run "${dds[@]}" --bind 127.0.0.1 --port "$udp" --ins tcp --ins-address 127.0.0.1 \
  --ins-port "$ins" > "$dir/run.log" 2>&1 &
run=$!
pids+=("$run")
# Each health sample with its arrival second (scan stamps are sensor time: they go back on every
# pass of the replay).
stdbuf -oL "$STAC" echo health "${dds[@]}" --count 0 --timeout $((seconds + 30)) 2> "$dir/echo.log" \
  > >(while IFS= read -r line; do printf '%(%s)T %s\n' -1 "$line"; done > "$dir/health.txt") &
echo_pid=$!
pids+=("$echo_pid")
sleep 2
"$STAC" replay --in "$dir/drive.pcap" --port "$udp" --tcp-port "5602:$ins" --wait-tcp --forever \
  > "$dir/replay.log" 2>&1 &
replay=$!
pids+=("$replay")

# Resident memory every 5 s, with a bar of the time gone.
: > "$dir/rss.tsv"
start=$(date +%s)
while :; do
  now=$(( $(date +%s) - start ))
  (( now >= seconds )) && break
  kill -0 "$run" 2>/dev/null || { echo "soak: stac run died at ${now} s (see $dir/run.log)" >&2; exit 1; }
  rss=$(awk '/^VmRSS/ {print $2}' "/proc/$run/status")
  printf '%d\t%d\n' "$now" "$rss" >> "$dir/rss.tsv"
  printf '\r  %3d%% %5d s  rss %d kB ' $((100 * now / seconds)) "$now" "$rss" >&2
  sleep 5
done
echo >&2
kill -INT "$replay"; wait "$replay" || true
kill -INT "$run"
code=0; wait "$run" || code=$?
sleep 1  # the last health samples
kill "$echo_pid" 2>/dev/null || true
wait "$echo_pid" 2>/dev/null || true
sleep 0.5  # the timestamping loop writes out what it read
trap - EXIT
[[ $code -eq 0 ]] || { echo "soak: stac run exited with $code (see $dir/run.log)" >&2; exit 1; }

# Per sixth of the run: scans, latency, memory. health.txt lines: "health scan N t=T e2e=Uus ...".
awk -v seconds="$seconds" -v max_growth="$max_growth_kb" -v t0="$start" '
  FNR == NR { rss_t[FNR] = $1; rss_v[FNR] = $2; nr = FNR; next }
  $2 == "health" && /e2e=/ {
    t = $1 - t0
    if (t < 0 || t >= seconds) next
    match($0, /e2e=[0-9]+/); e = substr($0, RSTART + 4, RLENGTH - 4) + 0
    if (e == 0) next                      # health without a scan
    b = int(t * 6 / seconds)
    n[b]++; lat[b, n[b]] = e
  }
  function sort_bin(b,   i, j, v) {
    for (i = 2; i <= n[b]; i++) { v = lat[b, i]; for (j = i - 1; j >= 1 && lat[b, j] > v; j--) lat[b, j + 1] = lat[b, j]; lat[b, j + 1] = v }
  }
  function rss_at(s,   i, v) { v = rss_v[1]; for (i = 1; i <= nr; i++) if (rss_t[i] <= s) v = rss_v[i]; return v }
  END {
    printf "%-13s %7s %10s %10s %10s %10s\n", "part (s)", "scans", "p50 ms", "p99 ms", "max ms", "rss kB"
    bad = 0
    for (b = 0; b < 6; b++) {
      sort_bin(b)
      from = b * seconds / 6; to = (b + 1) * seconds / 6
      if (n[b] == 0) { printf "%5d-%-7d %7d\n", from, to, 0; bad = 1; continue }
      p50 = lat[b, int(0.5 * (n[b] - 1)) + 1]; p99 = lat[b, int(0.99 * (n[b] - 1)) + 1]
      printf "%5d-%-7d %7d %10.1f %10.1f %10.1f %10d\n", from, to, n[b], p50 / 1000, p99 / 1000, lat[b, n[b]] / 1000, rss_at(to)
      if (n[b] < seconds / 6 * 0.9) { printf "soak: fewer than one scan a second in %d-%d s\n", from, to; bad = 1 }
    }
    growth = rss_at(seconds) - rss_at(seconds / 6)
    printf "rss growth after the first part: %d kB (limit %d)\n", growth, max_growth
    if (growth >= max_growth) bad = 1
    exit bad
  }' "$dir/rss.tsv" "$dir/health.txt" || { echo "soak: FAILED (see above and $dir)" >&2; exit 1; }

# Every complete scan published or counted as a drop.
summary() { grep -oE "$1" "$dir/run.log" | head -1 | grep -oE '[0-9]+' | head -1; }
complete=$(summary '[0-9]+ received \(complete\)')
published=$(summary '\), [0-9]+ published')
result_full=$(summary 'result slots full [0-9]+')
if [[ -z $complete || $complete -ne $((published + result_full)) ]]; then
  echo "soak: $complete complete scans, $published published + $result_full counted (see $dir/run.log)" >&2
  exit 1
fi
grep -E '^ +(packets|scans|drops|ego|ins|latency|end-to-end)' "$dir/run.log" | head -8
echo "soak: ok (${complete} complete scans, ${published} published; files in $dir)"
