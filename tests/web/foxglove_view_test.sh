#!/usr/bin/env bash
# `stac view` with a real Foxglove client: stac view serves DDS domain D over WebSocket; the node
# client (foxglove_view.mjs, @foxglove/ws-protocol) subscribes to every channel; `stac echo`
# prints the same four topics; `stac demo` drives them (a simulated drive, live, with health).
# Then every message the client got is checked against the official Foxglove schemas and, scan by
# scan, against what stac echo printed; the reading client must have got every message built,
# and the stalled one's must have been dropped and counted. Then `stac demo --view` (the server
# inside the demo) waits for a client and serves it the whole drive; a `stac process --dds` of a
# capture reaches it too. Last, clients that do not
# speak the protocol are refused or answered with an error status, and counted.
# Usage: foxglove_view_test.sh BUILD_DIR DOMAIN
set -euo pipefail
build=$(cd "$1" && pwd)
domain=$2
web=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
stac=$build/tools/stac
fail() { echo "foxglove_view_test: FAIL: $*" >&2; exit 1; }
[[ -d $web/node_modules/@foxglove/ws-protocol ]] || fail "no $web/node_modules: run deploy/install-deps.sh"
export DDS_TEST_TAG=stac-view-test-$$
work=$(mktemp -d /tmp/stac-view-test.XXXXXX)
pids=()
cleanup() {
  for pid in "${pids[@]}"; do kill "$pid" 2> /dev/null || true; done
  rm -rf "$work"
}
trap cleanup EXIT
# The ws:// URL a stac view (or demo --view) prints into FILE; fails if PID stops first.
wait_for_url() {
  local file=$1 pid=$2 url=""
  for _ in $(seq 1 300); do
    url=$(grep -o 'ws://[0-9.]*:[0-9]*' "$file" | head -1 || true)
    [[ -n $url ]] && break
    kill -0 "$pid" 2> /dev/null || { cat "$file" >&2; fail "it stopped before serving"; }
    sleep 0.1
  done
  [[ -n $url ]] || { cat "$file" >&2; fail "no ws:// URL in $file"; }
  echo "$url"
}
# Waits (10 s at most) until FILE holds TEXT; else fails saying WHAT did not happen.
wait_for_line() {
  local file=$1 text=$2 what=$3
  for _ in $(seq 1 100); do
    grep -q "$text" "$file" && return 0
    sleep 0.1
  done
  cat "$file" >&2
  fail "$what"
}
# The messages a `listen` client wrote to FILE per kind: clouds, tracks, poses, health; fails
# when any message did not fit its schema.
received_counts() {
  node -e 'const j = require(process.argv[1]);
    if (j.invalid.length) { console.error(j.invalid.join("\n")); process.exit(1); }
    console.log([j.clouds, j.tracks, j.poses, j.health].map((a) => a.length).join(" "))' "$1"
}

"$stac" view --port 0 --domain "$domain" --seconds 300 --client-buffer-mb 4 2> "$work/view.log" &
view=$!
pids+=("$view")
url=$(wait_for_url "$work/view.log" "$view")
node "$web/foxglove_view.mjs" listen "$url" "$work/client.json" > "$work/client.log" 2>&1 &
client=$!
pids+=("$client")
wait_for_line "$work/client.log" "subscribed 4" "the client did not subscribe to 4 channels"
node "$web/foxglove_view.mjs" stall "$url" > "$work/stall.log" 2>&1 &
pids+=("$!")
wait_for_line "$work/stall.log" "stalled" "the stalling client did not subscribe"
echo "foxglove_view_test: a client reads everything and one has stalled, on $url"
echos=()
for topic in tracked_objects point_cloud ego_pose health; do
  "$stac" echo "$topic" --domain "$domain" --timeout 300 > "$work/echo_$topic.txt" 2> /dev/null &
  echos+=("$!")
  pids+=("$!")
done
sleep 2  # the echo readers matched before the drive starts
"$stac" demo --domain "$domain" --seconds 6 --out "$work/demo" > "$work/demo.log" 2>&1 ||
  { tail -20 "$work/demo.log" >&2; fail "stac demo"; }
sleep 1
kill "${echos[@]}" 2> /dev/null || true
# stac view stops first: it sends each client what it queued, then its close, and the reading
# client writes what it got when the close arrives (killing the client first lost the messages
# still on their way to it when the machine was loaded).
kill -INT "$view"
wait "$view" || { cat "$work/view.log" >&2; fail "stac view's exit"; }
wait "$client" || { cat "$work/client.log" >&2; fail "the client"; }
cat "$work/view.log"
MIN_MATCHED=${MIN_MATCHED:-20} node "$web/foxglove_view.mjs" compare "$work/client.json" "$work" | tee "$work/compare.log"
# The reading client (client 1) got every message stac view built, but for those stac view
# counted as dropped to it (it fell behind: only when the machine is loaded) or to all (backlog).
built=$(sed -n 's/^ *\/stac\/[a-z_]* .* built \([0-9]*\),.*/\1/p' "$work/view.log" | tr '\n' ' ')
backlogs=$(sed -n 's/^ *\/stac\/.* + \([0-9]*\) (backlog)$/\1/p' "$work/view.log" | tr '\n' ' ')
dropped1=$(sed -n 's/^ *client 1 (.*): sent [0-9]*, dropped \([0-9]*\) (slow client)$/\1/p' "$work/view.log")
received=$(sed -n 's/^received: //p' "$work/compare.log")
read -ra b <<< "$built"
read -ra r <<< "$received"
read -ra k <<< "$backlogs"
((${#b[@]} == 4 && ${#r[@]} == 4 && ${#k[@]} == 4)) && [[ -n $dropped1 ]] ||
  fail "stac view's summary lacks a channel's counts or client 1's line"
total_built=0 total_received=0
for i in 0 1 2 3; do
  ((r[i] <= b[i])) || fail "channel $i: the reading client received ${r[i]} of ${b[i]} built"
  total_built=$((total_built + b[i] - k[i])) total_received=$((total_received + r[i]))
done
((total_received == total_built - dropped1)) ||
  fail "built per channel: $built; the reading client received: $received; dropped to it $dropped1, backlog $backlogs"
((dropped1 == 0)) || echo "foxglove_view_test: the reading client fell behind: $dropped1 messages dropped to it, counted"
grep -Eq '^ *client 2 \(.*\): sent [0-9]+, dropped [1-9][0-9]* \(slow client\)$' "$work/view.log" ||
  fail "stac view counted no drop to the stalled client (client 2)"
grep -q 'clients 2 (refused 0, bad messages 0)' "$work/view.log" || fail "stac view's client count"
# The stalled client's point clouds (the big messages) were dropped and counted; the reading
# client's messages are all accounted for (above), and the demo published every scan.
grep -E '/stac/point_cloud .* dropped [1-9][0-9]* \(slow client\)' "$work/view.log" > /dev/null ||
  fail "stac view dropped nothing to the stalled client"
grep -q 'dropped 0 (slow client) + 0 (backlog)' <(grep /stac/health "$work/view.log") || true

# stac demo --view: the demo waits for the viewer, then serves it every scan, and closes.
"$stac" demo --view --view-port 0 --domain "$domain" --seconds 4 --out "$work/demo2" > "$work/demo2.log" 2> "$work/demo2.err" &
demo=$!
pids+=("$demo")
url=$(wait_for_url "$work/demo2.err" "$demo")
node "$web/foxglove_view.mjs" listen "$url" "$work/demo2.json" > "$work/client2.log" 2>&1 &
client=$!
pids+=("$client")
wait "$demo" || { tail -20 "$work/demo2.err" >&2; fail "stac demo --view"; }
wait "$client" || { cat "$work/client2.log" >&2; fail "the client of stac demo --view"; }
grep -q "a viewer is subscribed" "$work/demo2.err" || fail "stac demo --view did not wait for the viewer"
built=$(sed -n 's/^ *\/stac\/[a-z_]* .* built \([0-9]*\),.*/\1/p' "$work/demo2.log" | tr '\n' ' ')
received=$(received_counts "$work/demo2.json")
[[ "$built" == "$received " && $built != "0 "* ]] ||
  fail "stac demo --view built per channel: $built; its client received: $received"
echo "foxglove_view_test: stac demo --view served its viewer every message: $received"

# stac process --dds of a capture (the first demo's drive), as fast as it goes: the viewer gets
# the newest samples of each topic, all of them valid.
"$stac" view --port 0 --domain "$domain" --seconds 120 2> "$work/view4.log" &
view=$!
pids+=("$view")
url=$(wait_for_url "$work/view4.log" "$view")
node "$web/foxglove_view.mjs" listen "$url" "$work/process.json" > "$work/client4.log" 2>&1 &
client=$!
pids+=("$client")
wait_for_line "$work/client4.log" "subscribed 4" "the client did not subscribe to 4 channels"
"$stac" process "$work/demo/drive.pcap" --tracks "$work/process.jsonl" --dds --domain "$domain" \
  --dds-wait 10 > "$work/process.log" 2>&1 || { tail -20 "$work/process.log" >&2; fail "stac process --dds"; }
sleep 1
kill -TERM "$client"
wait "$client" || { cat "$work/client4.log" >&2; fail "the client of stac process --dds"; }
kill -INT "$view"
wait "$view" || fail "stac view's exit"
received=$(received_counts "$work/process.json") || fail "invalid messages from stac process --dds"
read -r clouds tracks poses _ <<< "$received"
((clouds > 0 && tracks > 0 && poses > 0)) || fail "from stac process --dds the viewer got $received"
echo "foxglove_view_test: stac process --dds reached the viewer: $clouds clouds, $tracks track updates, $poses poses"

# Clients that misbehave.
"$stac" view --port 0 --domain "$domain" --seconds 60 2> "$work/view3.log" &
view=$!
pids+=("$view")
url=$(wait_for_url "$work/view3.log" "$view")
node "$web/foxglove_view.mjs" misbehave "$url" || fail "the misbehaving clients"
sleep 0.5
kill -INT "$view"
wait "$view" || fail "stac view's exit"
grep -q 'clients 1 (refused 1, bad messages 3)' "$work/view3.log" ||
  { cat "$work/view3.log" >&2; fail "stac view did not count the refused client and the bad messages"; }
echo "foxglove_view_test: bad clients refused or answered, and counted"
