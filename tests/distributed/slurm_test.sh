#!/usr/bin/env bash
# A real single-node Slurm (Debian's slurmctld, slurmd and munge, started
# here with a private configuration, state, ports and munge socket) runs
# scripts/slurm/'s job array and merge, and one MPI job, on Reach-v0; the
# merged files and the MPI job's must be the single run's, byte for byte
# (docs/distributed.md). Skipped (77) where Slurm is not installed or this
# is not root (slurmd must be). Usage: slurm_test.sh MANIBENCH SOURCE_DIR
set -euo pipefail
manibench=$1
source_dir=$2
for program in slurmctld slurmd munged sbatch squeue; do
  command -v "$program" >/dev/null || PATH=$PATH:/usr/sbin
  command -v "$program" >/dev/null || { echo "no $program: skipped"; exit 77; }
done
[[ $(id -u) -eq 0 ]] || { echo "slurmd needs root: skipped"; exit 77; }
[[ -r /etc/munge/munge.key ]] || { echo "no /etc/munge/munge.key: skipped"; exit 77; }

work=$(mktemp -d /tmp/manibench_slurm_XXXXXX)
pids=()
cleanup() {
  for pid in "${pids[@]}"; do kill "$pid" 2>/dev/null || true; done
  for pid in "${pids[@]}"; do wait "$pid" 2>/dev/null || true; done
  rm -rf "$work"
}
trap cleanup EXIT
mkdir -p "$work"/{state,spool,logs,runs}
chmod 700 "$work"

munged --foreground --force --socket="$work/munge.socket" --key-file=/etc/munge/munge.key \
  --pid-file="$work/munged.pid" --seed-file="$work/munge.seed" --log-file="$work/logs/munged.log" \
  >"$work/logs/munged.out" 2>&1 &
pids+=($!)
host=$(hostname -s)
# Ports of their own, away from a Slurm this machine may run already.
port=$((20000 + $$ % 20000))
cat > "$work/slurm.conf" <<EOF
ClusterName=manibenchtest
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$port
SlurmdPort=$((port + 1))
AuthType=auth/munge
AuthInfo=socket=$work/munge.socket
CredType=cred/munge
SlurmUser=root
SlurmdUser=root
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/logs/slurmctld.log
SlurmdLogFile=$work/logs/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
MpiDefault=none
NodeName=$host NodeAddr=127.0.0.1 CPUs=$(nproc) State=UNKNOWN
PartitionName=test Nodes=$host Default=YES MaxTime=INFINITE State=UP OverSubscribe=FORCE:8
EOF
export SLURM_CONF=$work/slurm.conf
for i in $(seq 50); do [[ -S $work/munge.socket ]] && break; sleep 0.1; done
slurmctld -D -i -f "$SLURM_CONF" >"$work/logs/slurmctld.out" 2>&1 &
pids+=($!)
slurmd -D -f "$SLURM_CONF" >"$work/logs/slurmd.out" 2>&1 &
pids+=($!)
for i in $(seq 300); do
  sinfo -h -o %t 2>/dev/null | grep -q idle && break
  sleep 0.2
done
sinfo -h -o %t | grep -q idle || { echo "Slurm did not come up"; tail -n 20 "$work"/logs/*.log; exit 1; }

# Waits for job $1 to leave the queue.
wait_for() {
  while squeue -h -j "$1" 2>/dev/null | grep -q .; do sleep 0.5; done
}

eval_args="Reach-v0 --policy random --objects 8,11 --levels 0-8 --set episode.max_steps=25"
cd "$work/runs"
# The variables the scripts read go through the environment (--export=ALL):
# sbatch's --export list would split EVAL_ARGS at its commas.
export MANIBENCH=$manibench EVAL_ARGS=$eval_args OUT=$work/runs/results
array=$(sbatch --parsable --export=ALL --array=1-3 --cpus-per-task=1 "$source_dir/scripts/slurm/eval-array.sbatch")
merge=$(sbatch --parsable --export=ALL --dependency=afterany:"$array" "$source_dir/scripts/slurm/eval-merge.sbatch")
mpi=""
if [[ -r "$(dirname "$manibench")/libmanibench_mpi.so" ]] && command -v mpirun >/dev/null; then
  mpi=$(OUT=$work/runs/mpi MPIRUN_ARGS="--allow-run-as-root --oversubscribe" \
    sbatch --parsable --export=ALL --nodes=1 --ntasks-per-node=2 --cpus-per-task=1 \
    "$source_dir/scripts/slurm/eval-mpi.sbatch")
fi
wait_for "$array"
wait_for "$merge"
[[ -n $mpi ]] && wait_for "$mpi"

# shellcheck disable=SC2086
"$manibench" eval $eval_args --no-progress --out "$work/runs/single" >/dev/null
status=0
compare() {  # the single run's files and $1's
  for f in episodes.csv summary.csv; do
    cmp "$work/runs/single/$f" "$1/$f" || { echo "$1/$f differs from the single run's"; status=1; }
  done
  diff <(grep -v '"timing"' "$work/runs/single/summary.json") <(grep -v '"timing"' "$1/summary.json") ||
    { echo "$1/summary.json differs from the single run's"; status=1; }
}
ls results >/dev/null
[[ $(ls -d results/shard* | wc -l) -eq 3 ]] || { echo "not 3 shards: $(ls results)"; status=1; }
compare "$work/runs/results/all"
if [[ -n $mpi ]]; then
  grep -q "2 MPI rank(s)" eval-mpi.log || { echo "the MPI job did not run 2 ranks:"; cat eval-mpi.log; status=1; }
  compare "$work/runs/mpi/all"
fi
if [[ $status -ne 0 ]]; then
  tail -n 30 ./*.log "$work"/logs/*.log
  exit 1
fi
echo "Slurm: array of 3 shards + merge${mpi:+, one MPI job of 2 ranks}: the single run's files"
