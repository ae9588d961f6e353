#!/usr/bin/env bash
# A single-node Slurm cluster on this machine, for tests: Debian's slurm-wlm and munge run as root
# without systemd, every file under STATE_DIR, on ports of its own.
#   tools/slurm_single_node.sh start STATE_DIR   starts munged, slurmctld and slurmd, waits until
#                                                 the node is idle; prints `export SLURM_CONF=…`
#   tools/slurm_single_node.sh stop STATE_DIR    stops the three daemons by the pids it recorded
set -euo pipefail
action=${1:?usage: slurm_single_node.sh start|stop STATE_DIR}
state=$(realpath -m "${2:?usage: slurm_single_node.sh start|stop STATE_DIR}")

stop() {
  for daemon in slurmd slurmctld munged; do
    pidfile="$state/$daemon.pid"
    [[ -s "$pidfile" ]] || continue
    pid=$(cat "$pidfile")
    kill "$pid" 2> /dev/null || true
    for _ in $(seq 50); do kill -0 "$pid" 2> /dev/null || break; sleep 0.1; done
    kill -9 "$pid" 2> /dev/null || true
    rm -f "$pidfile"
  done
}

start() {
  [[ $(id -u) -eq 0 ]] || { echo "slurm_single_node: run as root" >&2; exit 1; }
  for tool in munged mungekey slurmctld slurmd sinfo; do
    command -v "$tool" > /dev/null || { echo "slurm_single_node: $tool missing (tools/setup.sh installs slurm-wlm and munge)" >&2; exit 1; }
  done
  mkdir -p "$state"/{munge,ctld,spool}
  chmod 700 "$state/munge"
  [[ -s "$state/munge/munge.key" ]] || mungekey --create --keyfile="$state/munge/munge.key" --bits=1024
  chmod 600 "$state/munge/munge.key"
  munged --force --key-file="$state/munge/munge.key" --socket="$state/munge/munge.socket" \
    --pid-file="$state/munged.pid" --log-file="$state/munged.log" --seed-file="$state/munge/munge.seed"
  host=$(hostname -s)
  memory_mb=$(($(awk '/MemTotal/ {print $2}' /proc/meminfo) / 1024 / 2))
  cat > "$state/slurm.conf" <<CONF
ClusterName=spall-test
SlurmctldHost=$host
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$state/munge/munge.socket
SlurmctldPort=16817
SlurmdPort=16818
StateSaveLocation=$state/ctld
SlurmdSpoolDir=$state/spool
SlurmctldPidFile=$state/slurmctld.pid
SlurmdPidFile=$state/slurmd.pid
SlurmctldLogFile=$state/slurmctld.log
SlurmdLogFile=$state/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
MpiDefault=none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
JobCompType=jobcomp/none
AccountingStorageType=accounting_storage/none
NodeName=$host CPUs=$(nproc) RealMemory=$memory_mb State=UNKNOWN
PartitionName=debug Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
  export SLURM_CONF="$state/slurm.conf"
  slurmctld
  slurmd
  for _ in $(seq 150); do
    if sinfo -h -o %t 2> /dev/null | grep -q idle; then
      echo "export SLURM_CONF=$SLURM_CONF"
      return 0
    fi
    sleep 0.2
  done
  echo "slurm_single_node: the node did not become idle; logs in $state" >&2
  sinfo >&2 || true
  stop
  exit 1
}

case $action in
start) start ;;
stop) stop ;;
*) echo "usage: slurm_single_node.sh start|stop STATE_DIR" >&2; exit 2 ;;
esac
