#!/bin/bash
# A one-node Slurm cluster on this machine for as long as a command runs:
#   tests/survey/local_slurm_cluster.sh WORKDIR COMMAND [ARGS...]
# Generates a munge key, writes a minimal slurm.conf for localhost (select/cons_tres,
# proctrack/linuxproc, no cgroups, state and logs under WORKDIR), starts munged, slurmctld and
# slurmd in the foreground (-F/-D, so their pids are ours), waits for the node to be idle, runs
# COMMAND with SLURM_CONF set, and stops the three daemons by their pids on any exit.
# Needs root (SlurmUser=root) and the Debian packages slurm-wlm and munge.
set -euo pipefail
work=$(realpath "$1")
shift
mkdir -p "$work"/{munge,state,spool,log}
chmod 755 "$work/munge"

pids=()
stop_daemons() {
  local status=$?
  for ((i = ${#pids[@]} - 1; i >= 0; i--)); do kill "${pids[$i]}" 2>/dev/null || true; done
  for pid in "${pids[@]}"; do
    for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -9 "$pid" 2>/dev/null || true
  done
  exit "$status"
}
trap stop_daemons EXIT
trap 'exit 143' TERM INT

dd if=/dev/urandom of="$work/munge/munge.key" bs=1024 count=1 status=none
chmod 400 "$work/munge/munge.key"
socket="$work/munge/munge.socket"
munged --foreground --force --socket="$socket" --key-file="$work/munge/munge.key" --pid-file="$work/munge/munged.pid" \
  --log-file="$work/log/munged.log" --seed-file="$work/munge/munge.seed" >"$work/log/munged.out" 2>&1 &
pids+=($!)
for _ in $(seq 100); do [ -S "$socket" ] && break; sleep 0.1; done
[ -S "$socket" ] || { echo "local_slurm_cluster: munged did not start (log: $work/log/munged.log)" >&2; exit 1; }

host=$(hostname -s)
port=$((20000 + RANDOM % 20000))
node=$(slurmd -C | head -n 1)  # NodeName=<host> CPUs=... RealMemory=... as slurmd sees this machine
cat > "$work/slurm.conf" <<CONF
ClusterName=treelobes
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$socket
SlurmctldPort=$port
SlurmdPort=$((port + 1))
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/log/slurmctld.log
SlurmdLogFile=$work/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
MpiDefault=none
$node NodeAddr=127.0.0.1 State=UNKNOWN
PartitionName=local Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF="$work/slurm.conf"
slurmctld -D -i -f "$SLURM_CONF" >"$work/log/slurmctld.out" 2>&1 &
pids+=($!)
slurmd -D -f "$SLURM_CONF" -N "$host" >"$work/log/slurmd.out" 2>&1 &
pids+=($!)
for _ in $(seq 300); do
  state=$(sinfo -h -N -o %T 2>/dev/null | head -n 1 || true)
  [ "$state" = idle ] && break
  sleep 0.2
done
[ "$state" = idle ] || { echo "local_slurm_cluster: the node is '$state', not idle (logs: $work/log)" >&2; exit 1; }

"$@"
