#!/usr/bin/env bash
# A single-node Slurm cluster on this machine, for trying scripts/slurm/render-array.sh
# and for its test (scripts/slurm/test-array.sh): munged, slurmctld and slurmd from
# Debian's packages, configured for this host, with their configuration, state and logs
# in one folder (LUMAGRAPH_SLURM_DIR, default /tmp/lumagraph-slurm) and nothing written
# under /etc but the munge key the package makes. Needs root (slurmd starts jobs as their
# users) and no other Slurm running here.
#
#   scripts/slurm/local-cluster.sh install   # apt-get install the packages (Debian/Ubuntu)
#   scripts/slurm/local-cluster.sh start     # start munged, slurmctld, slurmd; wait for the node
#   scripts/slurm/local-cluster.sh env       # the line that points Slurm's commands at it
#   scripts/slurm/local-cluster.sh stop      # stop the daemons this script started
#
# Slurm's commands (sbatch, squeue, sinfo) find the cluster through SLURM_CONF: after
# `start`, run `eval "$(scripts/slurm/local-cluster.sh env)"` in the shell that submits.
set -euo pipefail

dir="${LUMAGRAPH_SLURM_DIR:-/tmp/lumagraph-slurm}"
conf="$dir/slurm.conf"
node="$(hostname -s)"

need() {
    for c in munged slurmctld slurmd sbatch; do
        command -v "$c" >/dev/null 2>&1 || {
            echo "local-cluster: $c is not installed (run: $0 install)" >&2
            exit 1
        }
    done
    [ "$(id -u)" -eq 0 ] || {
        echo "local-cluster: slurmd must run as root to start jobs" >&2
        exit 1
    }
}

write_conf() {
    mkdir -p "$dir/state" "$dir/spool" "$dir/munge" "$dir/log"
    cat >"$conf" <<EOF
# Written by scripts/slurm/local-cluster.sh: one node, this host.
ClusterName=lumagraph-local
SlurmctldHost=$node
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$dir/munge/munge.socket
CryptoType=crypto/munge
SlurmctldPort=${LUMAGRAPH_SLURM_PORT:-6817}
SlurmdPort=$(( ${LUMAGRAPH_SLURM_PORT:-6817} + 1 ))
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
MpiDefault=none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
JobCompType=jobcomp/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
NodeName=$node NodeAddr=127.0.0.1 CPUs=$(nproc) State=UNKNOWN
PartitionName=local Nodes=$node Default=YES MaxTime=INFINITE State=UP
EOF
}

case "${1:-}" in
install)
    sudo=""
    [ "$(id -u)" -ne 0 ] && sudo="sudo"
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends \
        munge slurmctld slurmd slurm-client
    ;;
start)
    need
    running() { [ -f "$1" ] && kill -0 "$(cat "$1")" 2>/dev/null; }
    if running "$dir/slurmctld.pid" || running "$dir/munge/munged.pid"; then
        echo "local-cluster: already running (stop it first: $0 stop)" >&2
        exit 1
    fi
    write_conf
    [ -f /etc/munge/munge.key ] || {
        echo "local-cluster: /etc/munge/munge.key is missing (reinstall munge)" >&2
        exit 1
    }
    socket="$dir/munge/munge.socket"
    munged --force --socket="$socket" --pid-file="$dir/munge/munged.pid" \
        --log-file="$dir/log/munged.log" --seed-file="$dir/munge/munged.seed"
    export SLURM_CONF="$conf"
    slurmctld -f "$conf"
    slurmd -f "$conf" -N "$node"
    for _ in $(seq 60); do
        if sinfo -h -N -o '%T' 2>/dev/null | grep -qE '^(idle|mixed|allocated)'; then
            echo "local-cluster: up ($node, $(nproc) CPUs); Slurm's commands need SLURM_CONF=$conf"
            exit 0
        fi
        sleep 1
    done
    echo "local-cluster: the node did not come up; logs in $dir/log:" >&2
    tail -n 20 "$dir"/log/*.log >&2 || true
    exit 1
    ;;
env)
    echo "export SLURM_CONF=$conf"
    ;;
stop)
    for pid in "$dir/slurmd.pid" "$dir/slurmctld.pid" "$dir/munge/munged.pid"; do
        if [ -f "$pid" ]; then
            kill "$(cat "$pid")" 2>/dev/null || true
            rm -f "$pid"
        fi
    done
    echo "local-cluster: stopped"
    ;;
*)
    sed -n '2,16p' "$0" | sed 's/^# \{0,1\}//'
    exit 2
    ;;
esac
