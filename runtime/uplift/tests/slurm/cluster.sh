#!/usr/bin/env bash
# A single-host Slurm cluster for the job-array test (runtime/uplift/tests/integration/slurm_cluster.rs):
# munged, slurmctld and slurmd from Debian's munge, slurmctld, slurmd and slurm-client packages,
# run by this user with every file (key, sockets, state, spool, logs, slurm.conf) under DIR —
# nothing in /etc or /run, no systemd. Clients find it through SLURM_CONF=DIR/slurm.conf.
#   cluster.sh start DIR   start the three daemons; wait until the node is idle
#   cluster.sh stop DIR    stop them
set -euo pipefail
cmd=${1:?start|stop}; dir=${2:?DIR}
mkdir -p "$dir"; dir=$(cd "$dir" && pwd)
case "$cmd" in
start)
    for tool in munged slurmctld slurmd sbatch squeue scancel sinfo; do
        command -v "$tool" >/dev/null || { echo "cluster.sh: $tool is not installed (Debian: apt install munge slurmctld slurmd slurm-client)" >&2; exit 3; }
    done
    mkdir -p "$dir/munge" "$dir/state" "$dir/spool" "$dir/log"
    chmod 700 "$dir/munge"
    head -c 1024 /dev/urandom > "$dir/munge/key"; chmod 600 "$dir/munge/key"
    munged --force --socket="$dir/munge/sock" --key-file="$dir/munge/key" --pid-file="$dir/munge/pid" \
        --log-file="$dir/munge/log" --seed-file="$dir/munge/seed"
    host=$(hostname -s)
    # Ports from this shell's pid: two clusters on one machine do not collide.
    port=$((20000 + ($$ % 20000) * 2))
    cat > "$dir/slurm.conf" <<CONF
ClusterName=uplift-test
SlurmctldHost=$host
SlurmctldPort=$port
SlurmdPort=$((port + 1))
AuthType=auth/munge
AuthInfo=socket=$dir/munge/sock
CredType=cred/munge
SlurmUser=$(id -un)
SlurmdUser=$(id -un)
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
ReturnToService=2
SchedulerType=sched/backfill
NodeName=$host CPUs=$(nproc) RealMemory=$(( $(awk '/MemTotal/ {print int($2 / 1024)}' /proc/meminfo) / 2 )) State=UNKNOWN
PartitionName=test Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
    export SLURM_CONF="$dir/slurm.conf"
    slurmctld -c
    slurmd
    for _ in $(seq 1 100); do
        state=$(sinfo -h -o %T 2>/dev/null || true)
        [ "$state" = idle ] && exit 0
        sleep 0.2
    done
    echo "cluster.sh: the node did not become idle (state: ${state:-none}); logs in $dir/log" >&2
    tail -n 20 "$dir/log/"*.log >&2 || true
    exit 1
    ;;
stop)
    for pid in "$dir/slurmd.pid" "$dir/slurmctld.pid" "$dir/munge/pid"; do
        [ -f "$pid" ] && kill "$(cat "$pid")" 2>/dev/null || true
    done
    ;;
*) echo "cluster.sh: start|stop DIR" >&2; exit 2 ;;
esac
