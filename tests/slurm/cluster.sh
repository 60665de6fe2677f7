#!/usr/bin/env bash
# A real single-node Slurm for tests/slurm.rs, started without systemd and stopped by the
# PIDs it started (facts in ../shared/SLURM-NOTES.md): munged, slurmctld and slurmd in WORK,
# with one node of this machine's CPUs and four (counted, not bound) GPUs: lavapipe is on
# the CPU, so the four tasks of an array can run at once, as on four GPU nodes.
#   cluster.sh start WORK    prints nothing; fails if the node is not idle within 60 s
#   cluster.sh env WORK      the environment the Slurm commands need (SLURM_CONF)
#   cluster.sh stop WORK     cancels leftover jobs, then TERM (KILL after 10 s) by PID
set -euo pipefail
action=$1
work=$(realpath "$2")
host=$(hostname -s)
conf=$work/slurm.conf
case $action in
start)
    mkdir -p "$work"/{munge,state,spool,log}
    chmod 0755 "$work" "$work/munge"
    key=$work/munge-key/munge.key
    mkdir -p "$(dirname "$key")"
    chmod 0700 "$(dirname "$key")"
    head -c 1024 /dev/urandom >"$key"
    chmod 0600 "$key"
    munged -F --socket="$work/munge/munge.socket" --key-file="$key" \
        --pid-file="$work/munge/munged.pid" --seed-file="$work/munge/seed" \
        --log-file="$work/log/munged.log" >"$work/log/munged.out" 2>&1 &
    echo $! >"$work/munged.pid"
    for _ in $(seq 50); do
        [ -S "$work/munge/munge.socket" ] && break
        sleep 0.1
    done
    # Free ports for the controller and the node daemon.
    read -r ctld_port slurmd_port < <(python3 -c '
import socket
s = [socket.socket() for _ in range(2)]
for x in s: x.bind(("127.0.0.1", 0))
print(*[x.getsockname()[1] for x in s])')
    # One CPU slot per GPU: the four tasks run at once (lavapipe shares the real cores).
    cpus=4
    memory=$(( $(awk '/MemTotal/ {print $2}' /proc/meminfo) / 1024 / 2 ))
    cat >"$conf" <<CONF
ClusterName=chaoscope
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
AuthType=auth/munge
AuthInfo=socket=$work/munge/munge.socket
CryptoType=crypto/munge
SlurmUser=root
SlurmdUser=root
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pidfile
SlurmdPidFile=$work/slurmd.pidfile
SlurmctldLogFile=$work/log/slurmctld.log
SlurmdLogFile=$work/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
MpiDefault=none
ReturnToService=2
SlurmdParameters=config_overrides
MailProg=/bin/true
MinJobAge=300
SchedulerParameters=batch_sched_delay=0,sched_min_interval=100000
GresTypes=gpu
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$memory Gres=gpu:4 State=UNKNOWN
PartitionName=debug Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
    echo "CgroupPlugin=cgroup/v1" >"$work/cgroup.conf"
    # Counted GPUs for --gres=gpu:1 (stand-in device files: the tasks find theirs by wgpu).
    echo "NodeName=$host Name=gpu File=/dev/null,/dev/zero,/dev/full,/dev/urandom" >"$work/gres.conf"
    slurmctld -D -f "$conf" >"$work/log/slurmctld.out" 2>&1 &
    echo $! >"$work/slurmctld.pid"
    slurmd -D -N "$host" -f "$conf" >"$work/log/slurmd.out" 2>&1 &
    echo $! >"$work/slurmd.pid"
    export SLURM_CONF=$conf
    for _ in $(seq 300); do
        for d in slurmctld slurmd munged; do
            if ! kill -0 "$(cat "$work/$d.pid")" 2>/dev/null; then
                echo "$d died:" >&2
                tail -n 20 "$work"/log/"$d"* >&2 || true
                exit 1
            fi
        done
        if [ "$(sinfo -h -n "$host" -o %t 2>/dev/null)" = idle ]; then
            exit 0
        fi
        sleep 0.2
    done
    echo "the node did not become idle:" >&2
    tail -n 20 "$work"/log/* >&2 || true
    exit 1
    ;;
env)
    echo "SLURM_CONF=$conf"
    ;;
stop)
    export SLURM_CONF=$conf
    scancel --full --quiet -u root 2>/dev/null || true
    for d in slurmd slurmctld munged; do
        [ -f "$work/$d.pid" ] && kill -TERM "$(cat "$work/$d.pid")" 2>/dev/null || true
    done
    for d in slurmd slurmctld munged; do
        pid=$(cat "$work/$d.pid" 2>/dev/null || echo)
        for _ in $(seq 100); do
            [ -n "$pid" ] && kill -0 "$pid" 2>/dev/null || break
            sleep 0.1
        done
        [ -n "$pid" ] && kill -KILL "$pid" 2>/dev/null || true
    done
    ;;
esac
