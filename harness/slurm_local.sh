#!/usr/bin/env bash
# A single-node Slurm cluster from Debian's packages (slurmctld, slurmd, slurm-client, munge),
# started by hand without systemd (ProctrackType=proctrack/linuxproc, TaskPlugin=task/none), to
# run issue 36's recipe for real: a job array of shards (--shard-from-env), a merge job that
# depends on it (--dependency=afterok), and a check of the merge against the single render
# (the linear EXRs byte for byte; see harness/parallel_shards.sh for why that holds).
#
# usage (as root): harness/slurm_local.sh   (PTUI=binary; SHARDS=8; SLURM_PORT=6817)
# Installs the packages if missing (apt-get), stops every daemon it started on exit.
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$(pwd)
PTUI=$(realpath "${PTUI:-target/release/ptui}")
SHARDS=${SHARDS:-8}
PORT=${SLURM_PORT:-6817}
[ "$(id -u)" = 0 ] || { echo "run as root (munged and slurmd need it)"; exit 1; }
[ -x "$PTUI" ] || { echo "$PTUI: build it first (cargo build --release)"; exit 1; }
if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq slurmctld slurmd slurm-client munge >/dev/null
fi
work=$(mktemp -d /tmp/ptui-slurm.XXXXXX)
munge_pid=/nonexistent
chmod 755 "$work"
pids=()
cleanup() {
    for f in "$work"/slurmd.pid "$work"/slurmctld.pid "$munge_pid"; do
        [ -f "$f" ] && kill "$(cat "$f")" 2>/dev/null || true
    done
    rm -f "$munge_pid" 2>/dev/null || true
    sleep 1
    rm -rf "$work"
}
trap cleanup EXIT
t0=$(date +%s)

# munge: a key, its directories, and the daemon (pid and socket in $work).
mkdir -p /etc/munge /var/lib/munge /var/log/munge /run/munge
[ -s /etc/munge/munge.key ] || dd if=/dev/urandom of=/etc/munge/munge.key bs=1024 count=1 status=none
chown -R munge:munge /etc/munge /var/lib/munge /var/log/munge /run/munge
chmod 700 /etc/munge; chmod 400 /etc/munge/munge.key
# Our own munged unless one is running (then it is left alone).
munge_pid=/run/munge/ptui-harness.$$.pid
if ! munge -n 2>/dev/null | unmunge >/dev/null 2>&1; then
    runuser -u munge -- munged --pid-file="$munge_pid"
fi
sleep 0.5
munge -n | unmunge >/dev/null || { echo "munge does not work"; exit 1; }

host=$(hostname -s)
cpus=$(nproc)
mkdir -p "$work/state" "$work/spool"
export SLURM_CONF="$work/slurm.conf"
cat >"$SLURM_CONF" <<CONF
ClusterName=ptui
SlurmctldHost=$host
SlurmctldPort=$PORT
SlurmdPort=$((PORT + 1))
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/slurmctld.log
SlurmdLogFile=$work/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
MpiDefault=none
NodeName=$host CPUs=$cpus State=UNKNOWN
PartitionName=main Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
slurmctld -i
slurmd
for _ in $(seq 1 60); do
    sinfo -h -o %t 2>/dev/null | grep -qE '^(idle|mix|alloc)' && break
    sleep 1
done
sinfo

# The single render, then the array and the dependent merge.
args=(cornell --size 64x48 --spp 40 --threads 1 -q)
"$PTUI" render "${args[@]}" -o "$work/single.exr" >/dev/null
array=$(sbatch --parsable --array=0-$((SHARDS - 1)) --cpus-per-task=1 \
    --output="$work/shard-%a.out" --chdir="$work" \
    --wrap "$PTUI render ${args[*]} --shard-from-env -o $work/part-\$SLURM_ARRAY_TASK_ID.film")
merge=$(sbatch --parsable --dependency=afterok:"$array" --output="$work/merge.out" --chdir="$work" \
    --wrap "$PTUI merge $work/part-*.film -o $work/merged.exr --require-complete")
echo "submitted array job $array ($SHARDS shards) and merge job $merge (afterok:$array)"
for _ in $(seq 1 600); do
    [ -z "$(squeue -h -j "$array,$merge" 2>/dev/null)" ] && break
    sleep 1
done
for i in $(seq 0 $((SHARDS - 1))); do
    echo "--- shard $i: $(grep -h '^shard' "$work/shard-$i.out" || cat "$work/shard-$i.out")"
done
echo "--- merge job:"
cat "$work/merge.out"
cmp "$work/single.exr" "$work/merged.exr"
echo "slurm: $SHARDS shards merged by a dependent job equal the single render (EXR byte for byte), $(( $(date +%s) - t0 )) s in all"
