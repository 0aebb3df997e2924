#!/bin/bash
# A throwaway one-node Slurm cluster for tests/it/slurm.rs (and for trying deploy/slurm-array.sbatch by hand).
#
#   tests/slurm/cluster.sh start DIR   # prints `export SLURM_CONF=DIR/slurm.conf`; clients need that variable
#   tests/slurm/cluster.sh stop DIR    # stops exactly the daemons `start` started, by their PIDs
#
# Everything lives in DIR (config, state, spool, logs) with its own ports, so it never touches /etc/slurm or a
# cluster already running here. There is no init system on these machines: munged, slurmctld and slurmd are
# started directly. munged is shared (its socket is fixed): an already running one is used and left alone.
# Needs root, and Debian's slurm-wlm and munge (.ci/run installs them).
set -euo pipefail
cmd="${1:-}"
dir="${2:-}"
[ -n "$cmd" ] && [ -n "$dir" ] || { echo "usage: $0 start|stop DIR" >&2; exit 2; }
log() { echo "cluster.sh: $*" >&2; }
conf="$dir/slurm.conf"

alive() { kill -0 "$1" 2>/dev/null; }

if [ "$cmd" = stop ]; then
    # Newest first: slurmd, slurmctld, then munged if this script started it.
    if [ -f "$dir/started" ]; then
        tac "$dir/started" | while read -r name pid; do
            alive "$pid" || continue
            kill "$pid" 2>/dev/null || true
            for _ in $(seq 1 50); do alive "$pid" || break; sleep 0.1; done
            alive "$pid" && { log "$name ($pid) ignored SIGTERM: SIGKILL"; kill -9 "$pid" 2>/dev/null || true; }
            log "stopped $name ($pid)"
        done
        rm -f "$dir/started"
    fi
    exit 0
fi
[ "$cmd" = start ] || { echo "usage: $0 start|stop DIR" >&2; exit 2; }
[ "$(id -u)" = 0 ] || { log "needs root"; exit 2; }
for tool in munged slurmctld slurmd sbatch; do
    command -v "$tool" >/dev/null || { log "$tool is not installed (apt-get install slurm-wlm munge)"; exit 2; }
done
mkdir -p "$dir/state" "$dir/spool"
: > "$dir/started"

# munge: Debian's postinst makes the key; the runtime directory is missing without an init system.
if ! munge -n 2>/dev/null | unmunge >/dev/null 2>&1; then
    [ -s /etc/munge/munge.key ] || runuser -u munge -- mungekey --create --keyfile=/etc/munge/munge.key
    install -d -o munge -g munge -m 0755 /run/munge
    install -d -o munge -g munge -m 0700 /var/lib/munge /var/log/munge
    rm -f /run/munge/munged.pid /run/munge/munge.socket.2 /run/munge/munge.socket.2.lock
    runuser -u munge -- /usr/sbin/munged
    for _ in $(seq 1 50); do munge -n 2>/dev/null | unmunge >/dev/null 2>&1 && break; sleep 0.1; done
    echo "munged $(cat /run/munge/munged.pid)" >> "$dir/started"
fi
munge -n | unmunge >/dev/null || { log "munge does not work"; exit 1; }

host="$(hostname -s)"
cpus="$(nproc)"
# Why these settings: no init system and no cgroups (linuxproc, task/none), no mail program, no accounting
# daemon; CR_Core so a job without --mem does not take the node's whole memory; SlurmUser=root so the state
# directories need no service account.
cat > "$conf" <<EOF
ClusterName=vvgentest
SlurmctldHost=$host
SlurmUser=root
AuthType=auth/munge
MpiDefault=none
MailProg=/bin/true
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
ReturnToService=2
SlurmctldPort=16817
SlurmdPort=16818
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
JobCompType=jobcomp/none
NodeName=$host CPUs=$cpus RealMemory=1000 State=UNKNOWN
PartitionName=test Nodes=ALL Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF="$conf"

setsid /usr/sbin/slurmctld -D -i -f "$conf" </dev/null >>"$dir/slurmctld.out" 2>&1 &
echo "slurmctld $!" >> "$dir/started"
for _ in $(seq 1 100); do scontrol ping 2>/dev/null | grep -q UP && break; sleep 0.1; done
scontrol ping | grep -q UP || { log "slurmctld did not come up: $dir/slurmctld.log"; exit 1; }
setsid /usr/sbin/slurmd -D -f "$conf" </dev/null >>"$dir/slurmd.out" 2>&1 &
echo "slurmd $!" >> "$dir/started"
for _ in $(seq 1 100); do
    case "$(sinfo -h -N -o %T 2>/dev/null | head -1)" in
        idle | mixed | allocated) break ;;
        down* | drain*) scontrol update nodename="$host" state=resume 2>/dev/null || true ;;
    esac
    sleep 0.2
done
state="$(sinfo -h -N -o %T | head -1)"
case "$state" in
    idle | mixed | allocated) ;;
    *) log "node $host is '$state': $dir/slurmd.log"; exit 1 ;;
esac
log "up: $(tr '\n' ' ' < "$dir/started")"
echo "export SLURM_CONF=$conf"
