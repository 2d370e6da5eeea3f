#!/usr/bin/env bash
# Brings up a single-node Slurm cluster on this machine, to try
# examples/slurm on: installs Debian's slurm-wlm and munge, writes a
# slurm.conf for this host (its CPUs and memory as slurmd detects them,
# cons_tres, proctrack/linuxproc, no cgroups), and starts munged,
# slurmctld and slurmd directly (no systemd, so it works in a container).
# Run it as root on Debian or Ubuntu; running it again does no harm.
#   examples/slurm/local-cluster.sh         install, configure, start
#   examples/slurm/local-cluster.sh stop    stop the three daemons
# Not for a real cluster: one node, jobs run as their users with no limits.
set -euo pipefail

CONF=/etc/slurm/slurm.conf
LOGS=/var/log/slurm
die() { echo "local-cluster.sh: $*" >&2; exit 1; }

# pid_of NAME PIDFILE: the pid in PIDFILE when that process is alive and NAME.
pid_of() {
  local p; p=$(cat "$2" 2>/dev/null) && [ "$(cat "/proc/$p/comm" 2>/dev/null)" = "$1" ] && echo "$p"
}
stop() { # stop NAME PIDFILE
  local p; p=$(pid_of "$1" "$2") || return 0
  kill "$p"
  for _ in $(seq 50); do kill -0 "$p" 2>/dev/null || { echo "stopped $1"; return 0; }; sleep 0.2; done
  die "$1 (pid $p) did not stop"
}
stop_all() {
  stop slurmd /run/slurmd.pid
  stop slurmctld /run/slurmctld.pid
  stop munged /run/munge/munged.pid
}

[ "$(id -u)" = 0 ] || die "run this as root"
case "${1:-start}" in
  stop) stop_all; exit 0 ;;
  start) ;;
  *) die "usage: $0 [stop]" ;;
esac

# 1. Packages.
missing=
for c in slurmctld slurmd sbatch munged; do command -v $c >/dev/null || missing=1; done
if [ -n "$missing" ]; then
  command -v apt-get >/dev/null || die "apt-get not found: this script is for Debian or Ubuntu"
  echo "installing slurm-wlm and munge"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq || die "apt-get update failed"
  apt-get install -y -qq --no-install-recommends slurm-wlm munge >/dev/null ||
    die "apt-get install slurm-wlm munge failed"
fi
for u in slurm munge; do id $u >/dev/null 2>&1 || die "no user $u (its package makes it)"; done

# 2. Munge: a key, then the daemon.
if [ ! -s /etc/munge/munge.key ]; then
  # mungekey comes with munge 0.5.14 and later; before, any 1024 random bytes.
  { mungekey --create --keyfile=/etc/munge/munge.key 2>/dev/null ||
    dd if=/dev/urandom of=/etc/munge/munge.key bs=1024 count=1 status=none; } ||
    die "could not create /etc/munge/munge.key"
fi
chown munge:munge /etc/munge/munge.key && chmod 400 /etc/munge/munge.key
install -d -o munge -g munge -m 755 /run/munge
install -d -o munge -g munge -m 700 /var/lib/munge /var/log/munge
if ! pid_of munged /run/munge/munged.pid >/dev/null; then
  runuser -u munge -- munged || die "munged did not start (see /var/log/munge/munged.log)"
fi
munge -n | unmunge >/dev/null || die "munge does not work (see /var/log/munge/munged.log)"

# 3. slurm.conf for this host, as slurmd detects it (a node configured with
# more CPUs or memory than it has would be drained).
host=$(hostname -s)
hw=$(slurmd -C | head -n 1) || die "slurmd -C could not detect this machine"
case "$hw" in NodeName=*) ;; *) die "slurmd -C printed no NodeName line: $hw" ;; esac
node="NodeName=$host ${hw#NodeName=* } State=UNKNOWN"
install -d -o slurm -g slurm /var/spool/slurmctld "$LOGS"
install -d /var/spool/slurmd /etc/slurm
new=$(cat <<EOF
# Written by rayterm's examples/slurm/local-cluster.sh: one node, no cgroups.
ClusterName=local
SlurmctldHost=$host
SlurmUser=slurm
AuthType=auth/munge
StateSaveLocation=/var/spool/slurmctld
SlurmdSpoolDir=/var/spool/slurmd
SlurmctldPidFile=/run/slurmctld.pid
SlurmdPidFile=/run/slurmd.pid
SlurmctldLogFile=$LOGS/slurmctld.log
SlurmdLogFile=$LOGS/slurmd.log
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
DefMemPerCPU=512
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
MpiDefault=none
MailProg=/bin/true
JobCompType=jobcomp/filetxt
JobCompLoc=$LOGS/jobs.log
ReturnToService=2
$node
PartitionName=local Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
)
if [ "$(cat "$CONF" 2>/dev/null)" != "$new" ]; then
  [ -f "$CONF" ] && cp "$CONF" "$CONF.bak" && echo "kept the old $CONF as $CONF.bak"
  echo "$new" > "$CONF"
  echo "wrote $CONF"
  # Daemons running with another configuration start again with this one.
  stop slurmd /run/slurmd.pid
  stop slurmctld /run/slurmctld.pid
fi

# 4. The daemons.
if ! pid_of slurmctld /run/slurmctld.pid >/dev/null; then
  slurmctld || die "slurmctld did not start (see $LOGS/slurmctld.log)"
fi
if ! pid_of slurmd /run/slurmd.pid >/dev/null; then
  slurmd || die "slurmd did not start (see $LOGS/slurmd.log)"
fi

# 5. Wait for the node.
state=
for _ in $(seq 60); do
  state=$(sinfo -h -n "$host" -o %t 2>/dev/null || true)
  case "$state" in idle | mix | alloc) break ;; esac
  sleep 1
done
case "$state" in
  idle | mix | alloc) ;;
  *) sinfo -R >&2 || true
     die "node $host is '${state:-unknown}', not idle, after 60 s (see $LOGS/slurmctld.log and slurmd.log)" ;;
esac

example=$(cd "$(dirname "$0")" && pwd)
cat <<EOF
Slurm is up: node $host ($(sinfo -h -n "$host" -o '%c CPUs, %m MB'), partition local, $state).
See it with sinfo and squeue. Run the example in the folder its parts should go to:
  RAYTERM=${example%/examples/slurm}/target/release/rayterm CPUS=1 $example/submit.sh 4
Logs: $LOGS/jobs.log (ended jobs), $LOGS/slurmctld.log, $LOGS/slurmd.log, /var/log/munge/munged.log
Stop the daemons with: $0 stop
EOF
