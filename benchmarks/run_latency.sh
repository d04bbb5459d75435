#!/usr/bin/env bash
# End-to-end latency of `stac run` with classification on (the published tracks classified before
# publication within run.classify_budget_ms: the summary's `classes` line), and DDS publish -> receive latency,
# over loopback (docs/benchmarks.md, "stac run: end to end"): a simulated 20 s urban drive
# replayed at the sensor's pace into `stac run`, `stac echo --latency` as the subscriber.
#
#   benchmarks/run_latency.sh [default|rt] [OUT_DIR]
#
# default: config/stac.yaml as shipped (no real-time scheduling; Cyclone loopback.xml for both).
# rt: the same with run.*_priority/_cpu set (receiver 80, pose 75, publisher 70 on CPU 0;
#     perception 60 on CPU 1), run.cpu_wake_latency_us 0 (idle cores poll: no halted core to
#     wake) and the subscriber on config/dds/loopback-rt.xml (its receive thread at real-time
#     priority). Needs the right to SCHED_FIFO (root or RLIMIT_RTPRIO) and root for the PM QoS
#     request (else `stac run` warns and runs without it).
# Environment: STAC (default build/tools/stac), SEED (2026), DURATION (20 s), DOMAIN (160).
set -euo pipefail
cd "$(dirname "$0")/.."
MODE=${1:-default}
OUT=${2:-build/run-latency}
STAC=${STAC:-build/tools/stac}
SEED=${SEED:-2026}
DURATION=${DURATION:-20}
DOMAIN=${DOMAIN:-160}
mkdir -p "$OUT"
CONFIG=config/stac.yaml
ECHO_DDS=config/dds/loopback.xml
if [[ "$MODE" == rt ]]; then
  CONFIG=config/run-latency-rt.yaml  # beside stac.yaml, so its relative paths still hold
  sed -e 's/^  receiver_priority: 0 /  receiver_priority: 80 /' -e 's/^  receiver_cpu: -1 /  receiver_cpu: 0 /' \
      -e 's/^  perception_priority: 0$/  perception_priority: 60/' -e 's/^  perception_cpu: -1$/  perception_cpu: 1/' \
      -e 's/^  publisher_priority: 0$/  publisher_priority: 70/' -e 's/^  publisher_cpu: -1$/  publisher_cpu: 0/' \
      -e 's/^  pose_priority: 0 /  pose_priority: 75 /' -e 's/^  pose_cpu: -1$/  pose_cpu: 0/' \
      -e 's/^  cpu_wake_latency_us: -1 /  cpu_wake_latency_us: 0 /' \
      config/stac.yaml > "$CONFIG"
  trap 'rm -f config/run-latency-rt.yaml' EXIT
  ECHO_DDS=config/dds/loopback-rt.xml
elif [[ "$MODE" != default ]]; then
  echo "$0: mode '$MODE': use default or rt" >&2; exit 2
fi
pcap="$OUT/urban$SEED.pcap"
[[ -f "$pcap" ]] || "$STAC" sim --scenario urban --seed "$SEED" --duration "$DURATION" \
  --out "$pcap" --truth "$OUT/urban$SEED.truth.jsonl" > "$OUT/sim.log" 2>&1
scans=$(( ${DURATION%.*} * 10 - 12 ))  # complete scans the subscriber waits for
udp=$(python3 -c 'import socket;s=socket.socket(socket.AF_INET,socket.SOCK_DGRAM);s.bind(("127.0.0.1",0));print(s.getsockname()[1])')
tcp=$(python3 -c 'import socket;s=socket.socket();s.bind(("127.0.0.1",0));print(s.getsockname()[1])')
"$STAC" run --config "$CONFIG" --domain "$DOMAIN" --bind 127.0.0.1 --port "$udp" --ins tcp \
  --ins-address 127.0.0.1 --ins-port "$tcp" > "$OUT/run.log" 2>&1 &
run_pid=$!
"$STAC" echo tracked_objects --config "$CONFIG" --domain "$DOMAIN" --dds-config "$ECHO_DDS" \
  --latency --count "$scans" --timeout $(( ${DURATION%.*} + 40 )) > "$OUT/echo.log" 2>&1 &
echo_pid=$!
sleep 3
"$STAC" replay --in "$pcap" --to 127.0.0.1 --port "$udp" --tcp-port "5602:$tcp" --wait-tcp \
  > "$OUT/replay.log" 2>&1
wait "$echo_pid" || true
kill -INT "$run_pid"; wait "$run_pid" || true
echo "$0: $MODE, load $(cut -d' ' -f1-3 /proc/loadavg)"
grep '^  classes' "$OUT/run.log" || true
sed -n '/^  deadline/,$p' "$OUT/run.log"
grep "latency over" "$OUT/echo.log" || { echo "$0: the subscriber saw too few samples:"; tail -3 "$OUT/echo.log"; }
