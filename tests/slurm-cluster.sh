#!/usr/bin/env bash
# A one-node Slurm cluster on this machine, for the render farm's test
# (facts it rests on: ../shared/design/slurm.md).
#   tests/slurm-cluster.sh start DIR   munged, slurmctld and slurmd with
#                                      their key, config, state and logs in
#                                      DIR; prints SLURM_CONF=DIR/slurm.conf
#   tests/slurm-cluster.sh stop DIR    cancels every job, waits for an empty
#                                      queue, stops the daemons by their pids
# `start` exits 77 with the reason on stderr where a cluster cannot start
# here (not root, Slurm or munge missing, no free ports): the test skips.
set -uo pipefail
action=${1:-} dir=${2:-}
[ -n "$action" ] && [ -n "$dir" ] || { echo "usage: $0 start|stop DIR" >&2; exit 2; }
skip() { echo "$*" >&2; exit 77; }
host=$(hostname -s)
export SLURM_CONF=$dir/slurm.conf

port_free() { ! (exec 3<>"/dev/tcp/127.0.0.1/$1") 2>/dev/null; }

stop() {
  [ -e "$SLURM_CONF" ] || return 0
  scancel --full --quiet $(squeue -h -o %A 2>/dev/null) 2>/dev/null
  for _ in $(seq 1 40); do
    [ -z "$(squeue -h 2>/dev/null)" ] && break
    sleep 0.25
  done
  # an orphaned step ignores SIGTERM once slurmd is gone: kill them first
  for pid in $(scontrol listpids 2>/dev/null | awk 'NR > 1 {print $1}'); do kill -9 "$pid" 2>/dev/null; done
  for d in slurmd slurmctld munged; do
    [ -e "$dir/$d.pid" ] && kill "$(cat "$dir/$d.pid")" 2>/dev/null
  done
  for _ in $(seq 1 40); do
    alive=0
    for d in slurmd slurmctld munged; do
      pid=$(cat "$dir/$d.pid" 2>/dev/null) || continue
      state=$(awk '{print $3}' "/proc/$pid/stat" 2>/dev/null) || continue
      [ "$state" = Z ] || alive=1 # a zombie is gone
    done
    [ $alive = 0 ] && break
    sleep 0.1
  done
  return 0
}

case $action in
  stop) stop; exit 0 ;;
  start) ;;
  *) echo "usage: $0 start|stop DIR" >&2; exit 2 ;;
esac

[ "$(id -u)" = 0 ] || skip "not root: slurmd runs jobs as root here"
for c in munged slurmctld slurmd sbatch squeue scontrol; do
  command -v "$c" >/dev/null 2>&1 || skip "$c not installed (Debian's slurm-wlm and munge: scripts/install-deps.sh)"
done
mkdir -p "$dir/spool" "$dir/state" || skip "$dir: cannot create it"
dir=$(cd "$dir" && pwd)
export SLURM_CONF=$dir/slurm.conf

ctld_port= d_port=
for p in $(seq 16817 2 16899); do
  if port_free "$p" && port_free "$((p + 1))"; then ctld_port=$p d_port=$((p + 1)); break; fi
done
[ -n "$ctld_port" ] || skip "no two free ports in 16817-16900"

head -c 1024 /dev/urandom >"$dir/munge.key" && chmod 600 "$dir/munge.key"
munged --force --socket="$dir/munge.socket" --key-file="$dir/munge.key" --pid-file="$dir/munged.pid" \
  --log-file="$dir/munged.log" --seed-file="$dir/munged.seed" || skip "munged did not start ($dir/munged.log)"

cat >"$SLURM_CONF" <<EOF
ClusterName=sgtest
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$d_port
SlurmUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$dir/munge.socket
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
MpiDefault=none
ReturnToService=2
SchedulerParameters=sched_min_interval=0,batch_sched_delay=0,sched_interval=1
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/filetxt
JobCompLoc=$dir/jobcomp.txt
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
MinJobAge=600
KillWait=5
NodeName=$host NodeAddr=127.0.0.1 CPUs=$(nproc) State=UNKNOWN
PartitionName=test Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF

slurmctld -f "$SLURM_CONF" -c || { stop; skip "slurmctld did not start ($dir/slurmctld.log)"; }
slurmd -f "$SLURM_CONF" -N "$host" || { stop; skip "slurmd did not start ($dir/slurmd.log)"; }
for _ in $(seq 1 60); do
  state=$(sinfo -h -o %t 2>/dev/null | head -1)
  case $state in idle|mix|alloc) echo "SLURM_CONF=$SLURM_CONF"; exit 0 ;; esac
  sleep 0.25
done
stop
skip "the node did not come up (state '${state:-none}'; $dir/slurmd.log)"
