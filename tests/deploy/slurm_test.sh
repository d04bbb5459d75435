#!/usr/bin/env bash
# deploy/slurm-dataset.sh on two simulated drives:
#   - --dry-run prints the array (one task per capture, the --parallel limit), the merge job after
#     it, and each task's stac command line;
#   - a list naming a missing capture, or mixing labelled and unlabeled captures, is refused with
#     the line named;
#   - --local runs the tasks and the merge here: the merged dataset holds every part's tracks;
#   - what a hostile user gives it (issue 47): an option without its value or an unknown one is
#     refused with rc 2, naming it; a list written on Windows (CRLF, a byte order mark) with
#     comments, paths with spaces (the list's folder, the drives, --out) and a TAB between capture
#     and truth runs as the plain list does; a line that could split two ways is refused; a KITTI
#     raw drive folder (../shared/data/kitti-raw-seq, linked into a folder with a space) is a
#     capture;
#   - on a one-node Slurm cluster started here (munged, slurmctld and slurmd from Debian's
#     slurm-wlm, on a private config, state folder and ports; root only), the real submission of
#     the Windows list with spaces, into a folder with a space, makes the same tracks.bin as
#     --local, byte for byte. Without slurm-wlm or root that part is skipped
#     and the test says so.
# Usage: slurm_test.sh BUILD_DIR SOURCE_DIR
set -euo pipefail
build=$(cd "$1" && pwd)
src=$(cd "$2" && pwd)
stac=$build/tools/stac
script=$src/deploy/slurm-dataset.sh
fail() { echo "slurm_test: FAIL: $*" >&2; exit 1; }
work=$(mktemp -d /tmp/stac-slurm-test.XXXXXX)
cluster=""
daemons=()  # the cluster's pids, stopped at exit whatever happened
cleanup() {
  set +e
  if [[ -n $cluster ]]; then
    SLURM_CONF=$cluster/slurm.conf scontrol shutdown > /dev/null 2>&1
    for pid in "${daemons[@]}"; do kill "$pid" 2> /dev/null; done
    for _ in $(seq 1 50); do
      alive=0
      for pid in "${daemons[@]}"; do kill -0 "$pid" 2> /dev/null && alive=1; done
      ((alive)) || break
      sleep 0.2
    done
    for pid in "${daemons[@]}"; do kill -9 "$pid" 2> /dev/null; done
  fi
  rm -rf "$work"
}
trap cleanup EXIT
cd "$work"

for s in 1 2; do
  "$stac" sim --scenario urban --seed "$s" --duration 3 --out "d$s.pcap" --truth "d$s.truth.jsonl" \
    > "sim$s.log" 2>&1 || { cat "sim$s.log" >&2; fail "stac sim"; }
done
printf '# two drives\nd1.pcap d1.truth.jsonl\n\nd2.pcap d2.truth.jsonl\n' > list.txt

# The dry run.
dry=$("$script" --list list.txt --out out --stac "$stac" --parallel 3 --dry-run -- --time=10)
echo "$dry"
grep -q -- "--array=0-1%3 .*--time=10 .*slurm-dataset.sh --task --out $work/out" <<< "$dry" || fail "dry run: the array"
grep -q -- "--dependency=afterok:<array job> .*slurm-dataset.sh --merge --out $work/out" <<< "$dry" || fail "dry run: the merge"
grep -qx "task 1: $stac dataset --in $work/d2.pcap --truth $work/d2.truth.jsonl --out $work/out/parts/00001" <<< "$dry" ||
  fail "dry run: task 1's command"
[[ ! -e out ]] || fail "the dry run created $work/out"

# Bad lists.
printf 'd1.pcap d1.truth.jsonl\nnope.pcap\n' > missing.txt
if msg=$("$script" --list missing.txt --out bad --stac "$stac" --local 2>&1); then fail "a missing capture was accepted"; fi
[[ $msg == *"missing.txt:2: no capture $work/nope.pcap"* ]] || fail "missing capture: $msg"
printf 'd1.pcap d1.truth.jsonl\nd2.pcap\n' > mixed.txt
if msg=$("$script" --list mixed.txt --out bad --stac "$stac" --local 2>&1); then fail "a mixed list was accepted"; fi
[[ $msg == *"1 of 2 captures have a truth file"* ]] || fail "mixed list: $msg"

# Here, without Slurm: the merged dataset holds both parts' tracks.
"$script" --list list.txt --out local --stac "$stac" --local > local.log 2>&1 || { cat local.log >&2; fail "--local"; }
cat local.log
tracks() { sed -n 's/^.*: \([0-9][0-9]*\) tracks (.*/\1/p' "$1" | tail -1; }
a=$(tracks local/parts/00000/log) b=$(tracks local/parts/00001/log) all=$(tracks local.log)
[[ -n $a && -n $b && -n $all ]] || fail "no track counts in the logs"
((a > 0 && b > 0 && all == a + b)) || fail "merged $all tracks from parts of $a and $b"
echo "slurm_test: --local: $a + $b = $all tracks"

# Options without their value, and unknown options: rc 2 and a message naming the option, before
# anything is made (not bash's "unbound variable", not the next option taken as the value).
refused() {  # refused OPTION ARGS...: slurm-dataset.sh ARGS exits 2, its error naming OPTION
  local option=$1 rc=0 msg
  shift
  msg=$("$script" "$@" 2>&1 > /dev/null) || rc=$?
  ((rc == 2)) || fail "slurm-dataset.sh $*: rc $rc, not 2: $msg"
  [[ $msg == "slurm-dataset: "*"$option"* ]] || fail "slurm-dataset.sh $*: the error names no $option: $msg"
}
refused --list --out o --stac "$stac" --local --list
refused --list --list --out o --stac "$stac" --local
refused --out --list list.txt --stac "$stac" --local --out
refused --out --list list.txt --out --local --stac "$stac"
refused --stac --list list.txt --out o --local --stac
refused --parallel --list list.txt --out o --dry-run --parallel
refused --parallel --list list.txt --out o --parallel --dry-run
refused --dataset-args --list list.txt --out o --dry-run --dataset-args
refused --dataset-arg --list list.txt --out o --dry-run --dataset-arg
refused --bogus --list list.txt --out o --dry-run --bogus
[[ ! -e o && ! -e --local && ! -e --dry-run ]] || fail "a refused command line made a folder"

# A value with spaces for every `stac dataset`: --dataset-arg words, in order with --dataset-args.
dry_args=$("$script" --list list.txt --out out --stac "$stac" --dry-run --dataset-args "--no-deskew" \
  --dataset-arg --config --dataset-arg "my config.yaml") || fail "dry run with --dataset-arg"
grep -qF -- "--no-deskew --config my\ config.yaml" <<< "$dry_args" ||
  fail "--dataset-arg: the value with a space is not one word: $dry_args"

# A list with CRLF line ends runs as the same list with LF ones.
printf '# two drives\r\nd1.pcap d1.truth.jsonl\r\n\r\nd2.pcap d2.truth.jsonl\r\n' > crlf.txt
dry_crlf=$("$script" --list crlf.txt --out out --stac "$stac" --parallel 3 --dry-run -- --time=10) ||
  fail "dry run of the CRLF list"
[[ $dry_crlf == "$dry" ]] || fail "the CRLF list's dry run differs from the LF list's: $dry_crlf"

# A list written on Windows (a byte order mark, CRLF), with comments, in a folder with a space,
# naming drives with spaces: TAB between capture and truth, the old space where no path has one.
mkdir "drives with space"
cp d1.pcap "drives with space/d 1.pcap"
cp d1.truth.jsonl "drives with space/d 1.truth.jsonl"
printf '\xef\xbb\xbf# two drives\r\n\r\nd 1.pcap\td 1.truth.jsonl\r\n  # the other\r\n../d2.pcap ../d2.truth.jsonl\r\n' \
  > "drives with space/my list.txt"
dry=$("$script" --list "drives with space/my list.txt" --out "out dir" --stac "$stac" --dry-run) ||
  fail "dry run of the Windows list with spaces"
echo "$dry"
q() { printf '%q' "$1"; }
grep -qxF "task 0: $stac dataset --in $(q "$work/drives with space/d 1.pcap") --truth $(q "$work/drives with space/d 1.truth.jsonl") --out $(q "$work/out dir/parts/00000")" <<< "$dry" ||
  fail "dry run of the Windows list: task 0's command"
grep -qxF "task 1: $stac dataset --in $(q "$work/drives with space/../d2.pcap") --truth $(q "$work/drives with space/../d2.truth.jsonl") --out $(q "$work/out dir/parts/00001")" <<< "$dry" ||
  fail "dry run of the Windows list: task 1's command"
"$script" --list "drives with space/my list.txt" --out "out dir" --stac "$stac" --local > spaced.log 2>&1 ||
  { cat spaced.log >&2; fail "--local on the Windows list with spaces"; }
spaced=$(tracks spaced.log)
[[ $spaced == "$all" ]] || fail "the Windows list with spaces merged ${spaced:-no} tracks, the plain list $all"
python3 - "out dir/manifest.json" "$work/drives with space/d 1.pcap" "$work/drives with space/d 1.truth.jsonl" <<'PY' ||
import json, sys
sources = json.load(open(sys.argv[1]))["sources"]
sys.exit(0 if {"capture": sys.argv[2], "truth": sys.argv[3]} in sources else 1)
PY
  fail "the merged manifest names no capture $work/drives with space/d 1.pcap with its truth"
echo "slurm_test: the Windows list with spaces: $spaced tracks, as the plain list"

# Without a TAB, a line of spaces that names no file, and splits into more than capture and truth,
# is ambiguous: refused, the line named.
printf 'd 1.pcap d 1.truth.jsonl\n' > "drives with space/ambiguous.txt"
if msg=$("$script" --list "drives with space/ambiguous.txt" --out bad --stac "$stac" --dry-run 2>&1); then
  fail "an ambiguous line was accepted: $msg"
fi
[[ $msg == *"ambiguous.txt:1: "*TAB* ]] || fail "ambiguous line: $msg"

# A KITTI raw drive folder is a capture (stac dataset --in takes one), beside a pcap whose name has
# a space, alone on its line (no TAB needed: the whole line names the file).
kitti=$src/../shared/data/kitti-raw-seq
if [[ -d $kitti/velodyne_points/data ]]; then
  ln -s "$(cd "$kitti" && pwd)" "drives with space/kitti-drive"
  printf 'kitti-drive\nd 1.pcap\n' > "drives with space/unlabeled.txt"
  "$script" --list "drives with space/unlabeled.txt" --out "unlabeled out" --stac "$stac" --local \
    > unlabeled.log 2>&1 || { cat unlabeled.log >&2; fail "--local on a KITTI drive folder"; }
  grep -qF "$work/drives with space/kitti-drive: 40 scans" "unlabeled out/parts/00000/log" ||
    fail "part 0 is not the KITTI drive: $(cat "unlabeled out/parts/00000/log")"
  unlabeled() { sed -n 's/^.*: \([0-9][0-9]*\) unlabeled tracks$/\1/p' "$1" | tail -1; }
  k=$(unlabeled "unlabeled out/parts/00000/log") p=$(unlabeled "unlabeled out/parts/00001/log")
  u=$(unlabeled unlabeled.log)
  [[ -n $k && -n $p && -n $u ]] || fail "no unlabeled track counts in the logs"
  ((k > 0 && u == k + p)) || fail "merged $u unlabeled tracks from the KITTI drive's $k and the pcap's $p"
  echo "slurm_test: a KITTI drive folder: $k + $p = $u unlabeled tracks"
else
  echo "slurm_test: no $kitti (../shared/data beside the source tree): the KITTI drive part is skipped"
fi

# A one-node Slurm cluster, if it can be started here.
for tool in munged slurmctld slurmd sbatch squeue scontrol; do
  command -v "$tool" > /dev/null || { echo "slurm_test: no $tool (slurm-wlm): the cluster part is skipped"; exit 0; }
done
if [[ $(id -u) -ne 0 ]]; then echo "slurm_test: not root: the cluster part is skipped"; exit 0; fi
cluster=$work/cluster
mkdir -p "$cluster"/{state,spool,munge}
chmod 700 "$cluster/munge"
head -c 1024 /dev/urandom > "$cluster/munge/munge.key"
chmod 400 "$cluster/munge/munge.key"
munged --force --key-file="$cluster/munge/munge.key" --socket="$cluster/munge/munge.socket" \
  --pid-file="$cluster/munge/munged.pid" --log-file="$cluster/munge/munged.log" \
  --seed-file="$cluster/munge/seed" || fail "munged did not start"
daemons+=("$(cat "$cluster/munge/munged.pid")")
ports=$(python3 -c 'import socket
s=[socket.socket() for _ in range(2)]
[x.bind(("127.0.0.1",0)) for x in s]
print(*[x.getsockname()[1] for x in s])')
read -r ctld_port slurmd_port <<< "$ports"
host=$(hostname -s)
cat > "$cluster/slurm.conf" <<CONF
ClusterName=stactest
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$cluster/munge/munge.socket
StateSaveLocation=$cluster/state
SlurmdSpoolDir=$cluster/spool
SlurmctldPidFile=$cluster/slurmctld.pid
SlurmdPidFile=$cluster/slurmd.pid
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmctldLogFile=$cluster/slurmctld.log
SlurmdLogFile=$cluster/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobCompType=jobcomp/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerType=sched/builtin
ReturnToService=2
MpiDefault=none
NodeName=$host NodeAddr=127.0.0.1 CPUs=$(nproc) RealMemory=1000 State=UNKNOWN
PartitionName=stac Nodes=ALL Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF=$cluster/slurm.conf
slurmctld || fail "slurmctld did not start (see $cluster/slurmctld.log)"
for _ in $(seq 1 50); do [[ -s $cluster/slurmctld.pid ]] && break; sleep 0.1; done
daemons+=("$(cat "$cluster/slurmctld.pid")")
slurmd -N "$host" || fail "slurmd did not start"
for _ in $(seq 1 50); do [[ -s $cluster/slurmd.pid ]] && break; sleep 0.1; done
daemons+=("$(cat "$cluster/slurmd.pid")")
for _ in $(seq 1 30); do
  [[ $(sinfo -h -o %t 2> /dev/null) == idle ]] && break
  sleep 1
done
[[ $(sinfo -h -o %t) == idle ]] || { tail -20 "$cluster/slurmctld.log" >&2; fail "the node never came up: $(sinfo)"; }
submitted=$("$script" --list "drives with space/my list.txt" --out "cluster out" --stac "$stac" -- --time=10)
echo "slurm_test: $submitted"
for _ in $(seq 1 180); do
  [[ -z $(squeue -h) ]] && break
  sleep 1
done
[[ -z $(squeue -h) ]] || fail "jobs still queued after 180 s: $(squeue)"
[[ -f "cluster out/tracks.bin" ]] ||
  { cat "cluster out/merge.out" "cluster out"/parts/*.out >&2 || true; fail "the cluster made no merged dataset"; }
cmp "cluster out/tracks.bin" "out dir/tracks.bin" || fail "the cluster's dataset differs from the local run's"
echo "slurm_test: the one-node cluster ran 2 tasks and the merge: the same $all tracks, byte for byte"
