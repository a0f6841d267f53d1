# SPDX-License-Identifier: Apache-2.0
# A one-node Slurm cluster on localhost for the farm tests, in a scratch folder; sourced.
#
#   source tests/farm/slurm_cluster.sh
#   cluster_start DIR      # munged, slurmctld and slurmd; SLURM_CONF exported
#   ...sbatch, squeue, scontrol...
#   cluster_stop           # kills the three daemons (also when the caller's trap runs it)
#
# Everything lives in DIR: the munge key and socket, slurm.conf, the state and spool
# folders, the logs; free TCP ports are picked so that the machine's own Slurm (if any)
# and a second run are not disturbed. Runs as root (CI: a fresh Debian 12 as root), with
# Debian's munge and slurm-wlm (scripts/install_deps.sh). No accounting daemon: the tasks'
# states come from `scontrol show job` (kept MinJobAge seconds) and the completion log
# (jobcomp/filetxt, DIR/jobcomp.txt).

_cluster_pids=()

_free_port() {
  python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'
}

cluster_stop() {
  local pid
  # The jobs first (their processes belong to slurmstepd, which outlives slurmd).
  if ((${#_cluster_pids[@]})) && [[ -n ${SLURM_CONF:-} ]]; then
    scancel --quiet --user=root 2>/dev/null || true
    for _ in $(seq 100); do
      squeue -h 2>/dev/null | grep -q . || break
      sleep 0.2
    done
  fi
  for pid in "${_cluster_pids[@]}"; do
    kill "$pid" 2>/dev/null || true
  done
  for pid in "${_cluster_pids[@]}"; do
    for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -9 "$pid" 2>/dev/null || true
  done
  _cluster_pids=()
}

cluster_start() {
  local dir=$1 node cpus port_ctl port_d
  mkdir -p "$dir"/state "$dir"/spool "$dir"/munge
  chmod 700 "$dir"/munge
  node=$(hostname -s)
  cpus=$(nproc)
  port_ctl=$(_free_port)
  port_d=$(_free_port)
  head -c 1024 /dev/urandom >"$dir/munge/munge.key"
  chmod 600 "$dir/munge/munge.key"
  # munged refuses to run as root without --force (CI runs as root).
  /usr/sbin/munged --force --foreground --key-file="$dir/munge/munge.key" \
    --socket="$dir/munge/socket" --pid-file="$dir/munge/munged.pid" \
    --log-file="$dir/munge/munged.log" --seed-file="$dir/munge/seed" \
    >"$dir/munged.out" 2>&1 &
  _cluster_pids+=($!)
  for _ in $(seq 50); do [[ -S $dir/munge/socket ]] && break; sleep 0.1; done
  [[ -S $dir/munge/socket ]] || { echo "slurm_cluster: munged did not start" >&2; cat "$dir"/munged.out "$dir"/munge/munged.log >&2; return 1; }
  cat >"$dir/slurm.conf" <<CONF
ClusterName=welkintest
SlurmctldHost=$node(127.0.0.1)
SlurmctldPort=$port_ctl
SlurmdPort=$port_d
AuthType=auth/munge
AuthInfo=socket=$dir/munge/socket
CredType=cred/munge
SlurmUser=root
SlurmdUser=root
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
ProctrackType=proctrack/pgid
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/filetxt
JobCompLoc=$dir/jobcomp.txt
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
MpiDefault=none
SwitchType=switch/none
ReturnToService=2
MinJobAge=3600
SchedulerParameters=sched_interval=1
NodeName=$node NodeAddr=127.0.0.1 CPUs=$cpus State=UNKNOWN
PartitionName=welkin Nodes=$node Default=YES MaxTime=30 State=UP
CONF
  export SLURM_CONF=$dir/slurm.conf
  /usr/sbin/slurmctld -D -i -f "$SLURM_CONF" >"$dir/slurmctld.out" 2>&1 &
  _cluster_pids+=($!)
  /usr/sbin/slurmd -D -N "$node" -f "$SLURM_CONF" >"$dir/slurmd.out" 2>&1 &
  _cluster_pids+=($!)
  local state=
  for _ in $(seq 120); do
    state=$(sinfo -h -n "$node" -o %t 2>/dev/null || true)
    [[ $state == idle ]] && break
    sleep 0.5
  done
  if [[ $state != idle ]]; then
    echo "slurm_cluster: the node is not idle after 60 s (state '$state')" >&2
    tail -n 20 "$dir"/slurmctld.log "$dir"/slurmd.log "$dir"/*.out >&2 || true
    return 1
  fi
  echo "slurm_cluster: $node idle ($cpus CPUs), slurmctld on port $port_ctl"
}
