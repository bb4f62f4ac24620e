#!/usr/bin/env bash
# Start or stop a one-node SLURM cluster (munged + slurmctld + slurmd) on this
# machine, without systemd, so the `slurm`-marked tests can submit real jobs.
#
#   slurm/ci_local_slurm.sh install # install if missing (only that: .ci/run does it early,
#                                   # in the background, while the tests run)
#   slurm/ci_local_slurm.sh start   # install if missing, configure, start, wait for idle
#   slurm/ci_local_slurm.sh stop    # kill exactly the daemons `start` recorded
#   slurm/ci_local_slurm.sh status  # sinfo, and whether the recorded PIDs live
#
# Must run as root. Installs Debian's slurm-wlm and munge when `slurmctld` or
# `munged` is missing (one `apt-get update`, then `apt-get install -y`).
# Writes /etc/slurm/slurm.conf only when it is absent or was written by this
# script (marker line); set IDEAS_SLURM_FORCE=1 to overwrite someone else's.
# PIDs go to $IDEAS_SLURM_STATE (default /run/ideas_hpc_slurm), one per line.
set -euo pipefail

STATE_DIR=${IDEAS_SLURM_STATE:-/run/ideas_hpc_slurm}
PIDFILE="$STATE_DIR/pids"
CONF=/etc/slurm/slurm.conf
MARKER="# written by ideas_hpc slurm/ci_local_slurm.sh"
WAIT_S=${IDEAS_SLURM_WAIT:-60}

log() { printf '[ci_local_slurm] %s\n' "$*" >&2; }
die() { log "error: $*"; exit 1; }
now() { date +%s.%N; }
elapsed() { awk -v a="$1" -v b="$(now)" 'BEGIN { printf "%.1f", b - a }'; }

need_root() { [ "$(id -u)" -eq 0 ] || die "must run as root (installs packages, starts daemons)"; }

install_if_missing() {
    if command -v slurmctld >/dev/null && command -v slurmd >/dev/null \
        && command -v munged >/dev/null && command -v sinfo >/dev/null; then
        log "slurm-wlm and munge already installed"
        return
    fi
    local t0; t0=$(now)
    log "installing slurm-wlm and munge (apt-get)"
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    apt-get install -y -qq --no-install-recommends slurm-wlm munge >/dev/null
    log "install took $(elapsed "$t0") s"
}

short_host() { hostname -s 2>/dev/null || hostname | cut -d. -f1; }

ensure_host_resolves() {
    local h; h=$(short_host)
    if ! getent hosts "$h" >/dev/null; then
        log "adding $h to /etc/hosts"
        printf '127.0.1.1\t%s\n' "$h" >> /etc/hosts
    fi
}

write_conf() {
    local h cpus mem_mb
    h=$(short_host)
    cpus=$(nproc --all)
    # Leave some memory to the OS; slurmd refuses to register a node that
    # claims more RealMemory than it has.
    mem_mb=$(awk '/MemTotal/ { printf "%d", $2 / 1024 * 0.9 }' /proc/meminfo)
    mkdir -p /etc/slurm /var/spool/slurmctld /var/spool/slurmd /var/log/slurm
    if [ -f "$CONF" ] && ! grep -qF "$MARKER" "$CONF" && [ "${IDEAS_SLURM_FORCE:-0}" != 1 ]; then
        die "$CONF exists and was not written by this script; set IDEAS_SLURM_FORCE=1 to overwrite"
    fi
    cat > "$CONF" <<EOF
$MARKER
ClusterName=ideas
SlurmctldHost=$h
AuthType=auth/munge
CryptoType=crypto/munge
MpiDefault=none
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
SlurmUser=root
SlurmdUser=root
SlurmctldPidFile=/run/slurmctld.pid
SlurmdPidFile=/run/slurmd.pid
SlurmdSpoolDir=/var/spool/slurmd
StateSaveLocation=/var/spool/slurmctld
SlurmctldLogFile=/var/log/slurm/slurmctld.log
SlurmdLogFile=/var/log/slurm/slurmd.log
SlurmctldTimeout=30
SlurmdTimeout=30
InactiveLimit=0
MinJobAge=60
KillWait=5
NodeName=$h CPUs=$cpus RealMemory=$mem_mb State=UNKNOWN
PartitionName=debug Nodes=$h Default=YES MaxTime=INFINITE State=UP
EOF
    log "wrote $CONF (node $h, CPUs=$cpus, RealMemory=${mem_mb} MB)"
}

start_munge() {
    mkdir -p /etc/munge /run/munge /var/lib/munge /var/log/munge
    if [ ! -s /etc/munge/munge.key ]; then
        log "creating munge key"
        if command -v mungekey >/dev/null; then
            mungekey --create --keyfile=/etc/munge/munge.key
        else
            dd if=/dev/urandom of=/etc/munge/munge.key bs=1 count=1024 status=none
        fi
    fi
    chown -R munge:munge /etc/munge /run/munge /var/lib/munge /var/log/munge
    chmod 0700 /etc/munge /var/lib/munge /var/log/munge
    chmod 0755 /run/munge
    chmod 0400 /etc/munge/munge.key
    if pgrep -u munge -x munged >/dev/null; then
        log "munged already running (not ours, not recorded)"
        return
    fi
    runuser -u munge -- /usr/sbin/munged
    local i
    for i in $(seq 50); do
        [ -s /run/munge/munged.pid ] && break
        sleep 0.1
    done
    [ -s /run/munge/munged.pid ] || die "munged did not start (see /var/log/munge/munged.log)"
    echo "munged $(cat /run/munge/munged.pid)" >> "$PIDFILE"
    munge -n | unmunge >/dev/null || die "munge round trip failed"
}

start_daemon() {  # name pidfile
    local name=$1 pidf=$2 i
    rm -f "$pidf"
    "/usr/sbin/$name"
    for i in $(seq 100); do
        [ -s "$pidf" ] && break
        sleep 0.1
    done
    [ -s "$pidf" ] || die "$name did not write $pidf (see /var/log/slurm/$name.log)"
    echo "$name $(cat "$pidf")" >> "$PIDFILE"
}

wait_idle() {
    local h t0 i state
    h=$(short_host)
    t0=$(now)
    for i in $(seq $((WAIT_S * 5))); do
        state=$(sinfo -h -N -n "$h" -o '%T' 2>/dev/null | head -1 || true)
        case "$state" in
            idle|mixed) log "node $h $state after $(elapsed "$t0") s"; return 0 ;;
            down*|drain*)
                scontrol update nodename="$h" state=resume >/dev/null 2>&1 || true ;;
        esac
        sleep 0.2
    done
    sinfo -N -l >&2 || true
    die "node $h not idle after ${WAIT_S} s (state: ${state:-?})"
}

cmd_start() {
    need_root
    local t0; t0=$(now)
    if [ -s "$PIDFILE" ]; then
        log "PID file $PIDFILE exists: stopping the previous daemons first"
        cmd_stop
    fi
    install_if_missing
    local t1; t1=$(now)
    ensure_host_resolves
    write_conf
    mkdir -p "$STATE_DIR"
    : > "$PIDFILE"
    start_munge
    start_daemon slurmctld /run/slurmctld.pid
    start_daemon slurmd /run/slurmd.pid
    wait_idle
    log "daemons up in $(elapsed "$t1") s (total with install $(elapsed "$t0") s); PIDs in $PIDFILE"
    sinfo
}

cmd_stop() {
    [ -s "$PIDFILE" ] || { log "no PID file $PIDFILE: nothing to stop"; return 0; }
    local name pid i
    # scancel our leftovers before the controller goes away; ignore failures.
    command -v scancel >/dev/null && scancel --quiet --state=PENDING,RUNNING -u root 2>/dev/null || true
    # Reverse order: slurmd, slurmctld, munged.
    tac "$PIDFILE" | while read -r name pid; do
        [ -n "$pid" ] || continue
        if kill -0 "$pid" 2>/dev/null; then
            kill "$pid" 2>/dev/null || true
            for i in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
            if kill -0 "$pid" 2>/dev/null; then
                log "$name ($pid) ignored SIGTERM: SIGKILL"
                kill -9 "$pid" 2>/dev/null || true
            fi
            log "stopped $name ($pid)"
        else
            log "$name ($pid) already gone"
        fi
    done
    rm -f "$PIDFILE"
}

cmd_status() {
    if [ -s "$PIDFILE" ]; then
        local name pid
        while read -r name pid; do
            if kill -0 "$pid" 2>/dev/null; then echo "$name $pid running"; else echo "$name $pid dead"; fi
        done < "$PIDFILE"
    else
        echo "no PID file $PIDFILE"
    fi
    command -v sinfo >/dev/null && sinfo || true
}

case "${1:-}" in
    install) need_root; install_if_missing ;;
    start) cmd_start ;;
    stop) cmd_stop ;;
    status) cmd_status ;;
    *) echo "usage: $0 install|start|stop|status" >&2; exit 2 ;;
esac
