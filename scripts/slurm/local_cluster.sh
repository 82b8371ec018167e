#!/usr/bin/env bash
# A one-node Slurm cluster on this machine, for trying the scripts and measuring latencies
# (docs/scale-out.md). As root, with Debian's slurm-wlm and munge (scripts/setup.sh).
#
#   scripts/slurm/local_cluster.sh start DIR   # prints "export SLURM_CONF=DIR/slurm.conf"
#   scripts/slurm/local_cluster.sh stop DIR
#
# Everything lives in DIR: munged with its own key and socket, slurmctld and slurmd with a
# slurm.conf for localhost (SlurmUser=root, proctrack/pgid, task/none, no cgroups, no
# accounting), state, spool, logs and pid files, on free ports. tests/slurm_cluster.rs
# starts the same cluster from Rust.
set -euo pipefail

usage="usage: local_cluster.sh start|stop DIR"
action="${1:?$usage}"
dir="${2:?$usage}"

free_port() {
  python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'
}

case "$action" in
  start)
    mkdir -p "$dir"/{munge,state,spool,log}
    dir="$(cd "$dir" && pwd)"
    chmod 700 "$dir/munge"
    rm -f "$dir/munge/munge.key"
    head -c 1024 /dev/urandom > "$dir/munge/munge.key"
    chmod 400 "$dir/munge/munge.key"
    cat > "$dir/slurm.conf" <<CONF
ClusterName=conetrace-local
SlurmctldHost=localhost
SlurmctldPort=$(free_port)
SlurmdPort=$(free_port)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$dir/munge/munge.socket
ProctrackType=proctrack/pgid
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
MpiDefault=none
ReturnToService=2
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
NodeName=localhost NodeAddr=127.0.0.1 CPUs=$(nproc) State=UNKNOWN
PartitionName=main Nodes=localhost Default=YES MaxTime=INFINITE State=UP
CONF
    # In a root without cgroup file systems (a chroot) slurmd's default cgroup plugin,
    # autodetect, fails; the v1 plugin loads without touching any hierarchy.
    if ! grep -q ' /sys/fs/cgroup' /proc/self/mountinfo; then
      echo "CgroupPlugin=cgroup/v1" > "$dir/cgroup.conf"
    fi
    munged -f --socket="$dir/munge/munge.socket" --key-file="$dir/munge/munge.key" \
      --log-file="$dir/log/munged.log" --pid-file="$dir/munge/munged.pid" \
      --seed-file="$dir/munge/munged.seed"
    export SLURM_CONF="$dir/slurm.conf"
    slurmctld -f "$SLURM_CONF"
    slurmd -N localhost -f "$SLURM_CONF"
    for _ in $(seq 100); do
      [ "$(sinfo -h -o %T 2>/dev/null)" = idle ] && break
      sleep 0.2
    done
    if [ "$(sinfo -h -o %T 2>/dev/null)" != idle ]; then
      echo "local_cluster.sh: the node did not come up; see $dir/log/" >&2
      exit 1
    fi
    echo "export SLURM_CONF=$SLURM_CONF"
    ;;
  stop)
    for pidfile in "$dir/slurmd.pid" "$dir/slurmctld.pid" "$dir/munge/munged.pid"; do
      if [ -f "$pidfile" ]; then
        kill "$(cat "$pidfile")" 2>/dev/null || true
      fi
    done
    ;;
  *)
    echo "$usage" >&2
    exit 2
    ;;
esac
