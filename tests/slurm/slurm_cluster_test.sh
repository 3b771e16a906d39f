#!/usr/bin/env bash
# A real one-node Slurm cluster on localhost runs `rths sweep --slurm` end to end: the sbatch array
# (one task per shard) and the merge job that depends on it; the merged CSV must equal the
# unsharded sweep byte for byte. Needs root, slurm-wlm and munge; exits 77 (ctest: skipped) with
# the reason printed when the daemons cannot start here.
#   usage: slurm_cluster_test.sh RTHS_EXECUTABLE STUDY_CONFIG
set -uo pipefail
rths="$1"
config="$2"
shards=3

skip() { echo "SKIPPED: $*"; exit 77; }
fail() { echo "FAILED: $*"; exit 1; }

[ "$(id -u)" -eq 0 ] || skip "the Slurm daemons run as root here (slurmd starts jobs as their user)"
for tool in munged slurmctld slurmd sbatch squeue sinfo scontrol; do
  command -v "$tool" >/dev/null || skip "$tool is not installed (apt-get install slurm-wlm munge)"
done

dir=$(mktemp -d /tmp/rths_slurm_test.XXXXXX)
chmod 711 "$dir"  # munged refuses a socket folder that others can write to
pids=()
cleanup() {
  for pid in "${pids[@]}"; do kill "$pid" 2>/dev/null; done
  for pid in "${pids[@]}"; do
    for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -9 "$pid" 2>/dev/null
  done
  rm -rf "$dir"
}
trap cleanup EXIT

# Two free TCP ports of our own, so parallel runs and a real cluster on this host do not clash.
read -r ctld_port slurmd_port < <(python3 -c '
import socket
socks = [socket.socket() for _ in range(2)]
for s in socks: s.bind(("127.0.0.1", 0))
print(*[s.getsockname()[1] for s in socks])')

echo "== munge in $dir/munge"
mkdir -m 711 "$dir/munge"
dd if=/dev/urandom of="$dir/munge/munge.key" bs=1024 count=1 status=none
chmod 400 "$dir/munge/munge.key"
munged --foreground --force --key-file="$dir/munge/munge.key" --socket="$dir/munge/munge.socket" \
  --pid-file="$dir/munge/munged.pid" --log-file="$dir/munge/munged.log" \
  --seed-file="$dir/munge/munged.seed" >/dev/null 2>&1 &
pids+=($!)
for _ in $(seq 50); do [ -S "$dir/munge/munge.socket" ] && break; sleep 0.1; done
[ -S "$dir/munge/munge.socket" ] || skip "munged did not start: $(tail -3 "$dir/munge/munged.log" 2>/dev/null)"

echo "== slurm.conf (slurmctld port $ctld_port, slurmd port $slurmd_port)"
mkdir -p "$dir/state" "$dir/spool"
node_line=$(slurmd -C | head -1)
cat > "$dir/slurm.conf" <<CONF
ClusterName=rthstest
SlurmctldHost=localhost
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$dir/munge/munge.socket
CredType=cred/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
MpiDefault=none
ReturnToService=2
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
$node_line NodeAddr=127.0.0.1 State=UNKNOWN
PartitionName=rths Nodes=ALL Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF="$dir/slurm.conf"

echo "== starting slurmctld and slurmd"
started=$(date +%s.%N)
slurmctld -D -i >/dev/null 2>&1 &
pids+=($!)
slurmd -D >/dev/null 2>&1 &
pids+=($!)
ready=""
for _ in $(seq 100); do
  state=$(sinfo -h -o %T 2>/dev/null | head -1)
  if [ "$state" = idle ]; then ready=1; break; fi
  sleep 0.2
done
if [ -z "$ready" ]; then
  echo "--- slurmctld.log"; tail -5 "$dir/slurmctld.log" 2>/dev/null
  echo "--- slurmd.log"; tail -5 "$dir/slurmd.log" 2>/dev/null
  skip "the one-node cluster did not come up within 20 s (node state '${state:-none}')"
fi
echo "cluster ready in $(python3 -c "print(f'{$(date +%s.%N) - $started:.1f}')") s: $(sinfo -h -o '%P %D %c %m %T')"

echo "== rths sweep --slurm: $shards shards and a merge job"
"$rths" sweep "$config" --slurm "$dir/job" --shards "$shards" --partition rths --time 00:05:00 --mem 256M \
  --threads 1 || fail "rths sweep --slurm exited $?"
for file in sweep_array.sbatch sweep_merge.sbatch submit.sh; do
  [ -f "$dir/job/$file" ] || fail "$file was not written"
done
grep -q -- "--array=0-$((shards - 1))" "$dir/job/sweep_array.sbatch" || fail "no array of $shards tasks"
ids=$(bash "$dir/job/submit.sh") || fail "submit.sh failed: $ids"
array_id=$(echo "$ids" | sed -n 1p)
merge_id=$(echo "$ids" | sed -n 2p)
echo "array job $array_id, merge job $merge_id"
[ -n "$merge_id" ] || fail "submit.sh did not print two job ids"

deadline=$(( $(date +%s) + 180 ))
while [ -n "$(squeue -h -j "$array_id,$merge_id" 2>/dev/null)" ]; do
  [ "$(date +%s)" -lt "$deadline" ] || fail "jobs still queued after 180 s: $(squeue -h)"
  sleep 0.5
done
merge_state=$(scontrol show job "$merge_id" 2>/dev/null | grep -o 'JobState=[A-Z_]*')
echo "merge job: $merge_state"
for log in "$dir"/job/logs/*; do echo "--- $(basename "$log")"; tail -2 "$log"; done
[ "$merge_state" = JobState=COMPLETED ] || fail "the merge job ended $merge_state"
for ((i = 0; i < shards; ++i)); do
  [ -f "$dir/job/shards/sweep.shard-$i-of-$shards.csv" ] || fail "shard $i missing"
done

echo "== the same sweep unsharded"
"$rths" sweep "$config" --out "$dir/whole" --no-plots --threads 1 >/dev/null 2>&1 || fail "unsharded sweep failed"
cmp "$dir/whole/sweep.csv" "$dir/job/sweep.csv" || fail "the merged CSV differs from the unsharded sweep"
echo "PASSED: merged CSV of $shards Slurm array tasks equals the unsharded sweep ($(($(wc -l < "$dir/job/sweep.csv") - 2)) points)"
