#!/usr/bin/env bash
# slurm_local.sh - a throw-away single-node Slurm cluster on this host.
#
#   slurm_local.sh start DIR   create DIR, a private munged, a slurm.conf for
#                              this host only, start slurmctld + slurmd, wait
#                              until the node is idle, print the environment
#                              a caller must use (also written to DIR/env.sh)
#   slurm_local.sh stop DIR    cancel remaining jobs, stop slurmd, slurmctld
#                              and munged started from DIR (idempotent)
#   slurm_local.sh status DIR  exit 0 if all three daemons of DIR are alive
#
# Requirements: root, Debian packages slurm-wlm and munge (nothing is
# installed here; exit 3 if a program is missing). No systemd, no cgroups,
# no system-wide config: everything lives under DIR, the daemons listen on
# free TCP ports chosen at start, so several clusters can coexist.
#
# Layout of DIR:
#   slurm.conf env.sh
#   munge/  munge.key munged.socket munged.pid munged.log munged.seed
#   state/  (StateSaveLocation)     spool/ (SlurmdSpoolDir)
#   log/    slurmctld.log slurmd.log    run/ slurmctld.pid slurmd.pid
#
# Exit codes: 0 ok, 1 failure (logs printed), 2 usage, 3 missing prerequisite.
set -euo pipefail

PROG=${0##*/}
START_TIMEOUT=${SLURM_LOCAL_START_TIMEOUT:-30}   # seconds until node idle
STOP_TIMEOUT=${SLURM_LOCAL_STOP_TIMEOUT:-15}     # seconds per daemon on stop

usage() {
    echo "usage: $PROG start|stop|status DIR" >&2
    exit 2
}

log() { echo "$PROG: $*" >&2; }

# --- helpers ---------------------------------------------------------------

# pid_alive PIDFILE NAME: print the pid if PIDFILE names a live process whose
# command name is NAME (guards against a recycled pid).
pid_alive() {
    local pidfile=$1 name=$2 pid comm
    [[ -r $pidfile ]] || return 1
    pid=$(head -n 1 "$pidfile" 2>/dev/null | tr -dc '0-9')
    [[ -n $pid ]] || return 1
    comm=$(cat "/proc/$pid/comm" 2>/dev/null) || return 1
    [[ $comm == "$name" ]] || return 1
    alive "$pid" || return 1
    echo "$pid"
}

# alive PID: the process exists and is not a zombie.
alive() {
    local stat
    stat=$(cat "/proc/$1/stat" 2>/dev/null) || return 1
    stat=${stat##*) }
    [[ ${stat%% *} != Z ]]
}

# stop_pids SECONDS PID...: SIGTERM all, wait up to SECONDS for all of them,
# then SIGKILL the survivors and wait up to 5 s more.
stop_pids() {
    local secs=$1 pid i left=()
    shift
    (($#)) || return 0
    kill -TERM "$@" 2>/dev/null || true
    for ((i = 0; i < secs * 10 + 50; i++)); do
        left=()
        for pid in "$@"; do
            if alive "$pid"; then left+=("$pid"); fi
        done
        ((${#left[@]})) || return 0
        if ((i == secs * 10)); then
            log "pid(s) ${left[*]} did not exit after SIGTERM, sending SIGKILL"
            kill -KILL "${left[@]}" 2>/dev/null || true
        fi
        sleep 0.1
    done
    log "pid(s) ${left[*]} still alive"
    return 1
}

# stop_daemons PIDFILE NAME [PIDFILE NAME]...: stop those daemons together.
stop_daemons() {
    local pids=() pid rc=0 files=()
    while (($# >= 2)); do
        files+=("$1")
        if pid=$(pid_alive "$1" "$2"); then pids+=("$pid"); fi
        shift 2
    done
    stop_pids "$STOP_TIMEOUT" "${pids[@]}" || rc=1
    ((rc)) || rm -f "${files[@]}"
    return "$rc"
}

# Pids of processes spawned by this cluster's slurmd that are still alive:
# slurmstepd, or a job process (SLURM_JOB_ID set), whose environment carries
# SLURM_CONF=CONF. The calling process and its ancestors are never listed.
cluster_pids() {
    local conf=$1 p pid n=0 env comm self=" " q=$$
    for ((n = 0; n < 64; n++)); do
        [[ $q =~ ^[0-9]+$ && $q -gt 1 ]] || break
        self+="$q "
        q=$(awk '/^PPid:/ { print $2 }' "/proc/$q/status" 2>/dev/null || echo 0)
    done
    n=0
    for p in /proc/[0-9]*; do
        ((n++ < 100000)) || break
        pid=${p#/proc/}
        [[ $self == *" $pid "* ]] && continue
        env=$({ tr '\0' '\n' <"$p/environ"; } 2>/dev/null) || continue
        grep -qxF "SLURM_CONF=$conf" <<<"$env" || continue
        comm=$(cat "$p/comm" 2>/dev/null) || continue
        if [[ $comm == slurmstepd ]] || grep -q '^SLURM_JOB_ID=' <<<"$env"; then
            echo "$pid"
        fi
    done
}

# Listening/bound local TCP ports, upper-case hex, one per line.
used_ports_hex() {
    awk 'FNR > 1 { n = split($2, a, ":"); print a[n] }' \
        /proc/net/tcp /proc/net/tcp6 2>/dev/null | sort -u
}

# free_port_pair: print P such that P and P+1 are not in use (20000-59999).
free_port_pair() {
    local used p i
    used=$(used_ports_hex)
    for ((i = 0; i < 200; i++)); do
        p=$((20000 + (RANDOM * 32768 + RANDOM) % 40000))
        if ! grep -qx "$(printf '%04X' "$p")" <<<"$used" &&
           ! grep -qx "$(printf '%04X' $((p + 1)))" <<<"$used"; then
            echo "$p"
            return 0
        fi
    done
    return 1
}

tail_logs() {
    local f
    for f in "$DIR/munge/munged.log" "$DIR/log/slurmctld.log" "$DIR/log/slurmd.log"; do
        [[ -s $f ]] || continue
        echo "----- last lines of $f -----" >&2
        tail -n 25 "$f" >&2
    done
}

do_stop() {
    local conf=$DIR/slurm.conf rc=0 pid i stray
    # Cancel what is still queued/running so no slurmstepd outlives slurmd.
    if pid_alive "$DIR/run/slurmctld.pid" slurmctld >/dev/null; then
        SLURM_CONF=$conf timeout 10 scancel --quiet \
            --user="$(id -un)" 2>/dev/null || true
        for ((i = 0; i < 50; i++)); do
            [[ -z $(SLURM_CONF=$conf timeout 5 squeue -h -o %i 2>/dev/null) ]] && break
            sleep 0.2
        done
    fi
    stop_daemons "$DIR/run/slurmd.pid" slurmd \
        "$DIR/run/slurmctld.pid" slurmctld || rc=1
    # Anything this cluster spawned that is still around (slurmstepd, jobs).
    if [[ -f $conf ]]; then
        stray=$(cluster_pids "$conf")
        if [[ -n $stray ]]; then
            log "stopping leftover processes: ${stray//$'\n'/ }"
            # shellcheck disable=SC2086
            stop_pids 2 $stray || rc=1
        fi
    fi
    stop_daemons "$DIR/munge/munged.pid" munged || rc=1
    return "$rc"
}

fail() {
    FAILING=1
    echo "$PROG: FAILED: $*" >&2
    tail_logs
    do_stop || true
    echo "$PROG: FAILED: $*" >&2
    exit 1
}

# --- start -----------------------------------------------------------------

do_start() {
    local prog missing=() conf=$DIR/slurm.conf
    for prog in slurmctld slurmd sbatch sinfo squeue scontrol scancel munged; do
        command -v "$prog" >/dev/null 2>&1 || missing+=("$prog")
    done
    if ((${#missing[@]})); then
        echo "$PROG: missing program(s): ${missing[*]} (install Debian packages slurm-wlm and munge)" >&2
        exit 3
    fi
    if [[ $(id -u) -ne 0 ]]; then
        echo "$PROG: must run as root (slurmd runs jobs as the submitting user)" >&2
        exit 3
    fi

    if pid_alive "$DIR/run/slurmctld.pid" slurmctld >/dev/null ||
       pid_alive "$DIR/run/slurmd.pid" slurmd >/dev/null ||
       pid_alive "$DIR/munge/munged.pid" munged >/dev/null; then
        echo "$PROG: a cluster from $DIR is already running; run '$PROG stop $DIR' first" >&2
        exit 1
    fi

    # slurm.conf paths cannot contain blanks; unix socket paths are limited
    # to 107 bytes.
    if [[ $DIR =~ [[:space:]] ]]; then
        echo "$PROG: DIR must not contain whitespace: $DIR" >&2
        exit 2
    fi
    if ((${#DIR} > 80)); then
        echo "$PROG: DIR path too long for a unix socket (${#DIR} > 80 chars): $DIR" >&2
        exit 2
    fi

    # From here on, any unexpected exit also stops what was started.
    FAILING=""
    trap 'rc=$?; if ((rc)) && [[ -z $FAILING ]]; then fail "unexpected error (exit $rc) during start"; fi' EXIT

    mkdir -p "$DIR/munge" "$DIR/state" "$DIR/spool" "$DIR/log" "$DIR/run"
    chmod 0755 "$DIR"
    chmod 0755 "$DIR/munge"
    chmod 0700 "$DIR/state" "$DIR/spool"
    rm -f "$DIR"/log/*.log "$DIR"/munge/munged.log "$DIR/env.sh"
    rm -rf "${DIR:?}"/state/* "${DIR:?}"/spool/*

    # munge: private key, socket, pid, log and seed files.
    local key=$DIR/munge/munge.key sock=$DIR/munge/munged.socket
    rm -f "$key"
    if command -v mungekey >/dev/null 2>&1; then
        mungekey --create --keyfile="$key" >/dev/null 2>&1 ||
            dd if=/dev/urandom of="$key" bs=1024 count=1 status=none
    else
        dd if=/dev/urandom of="$key" bs=1024 count=1 status=none
    fi
    chmod 0400 "$key"
    rm -f "$sock" "$sock.lock"
    munged --force --origin=127.0.0.1 --socket="$sock" --key-file="$key" \
        --pid-file="$DIR/munge/munged.pid" --log-file="$DIR/munge/munged.log" \
        --seed-file="$DIR/munge/munged.seed" >"$DIR/log/munged.out" 2>&1 ||
        { cat "$DIR/log/munged.out" >&2; fail "munged did not start"; }
    local i
    for ((i = 0; i < 50; i++)); do
        [[ -S $sock ]] && pid_alive "$DIR/munge/munged.pid" munged >/dev/null && break
        sleep 0.1
    done
    [[ -S $sock ]] || fail "munged socket $sock did not appear"
    if command -v munge >/dev/null 2>&1 && command -v unmunge >/dev/null 2>&1; then
        munge -n --socket="$sock" | unmunge --socket="$sock" >/dev/null 2>&1 ||
            fail "munge self-test (munge -n | unmunge) failed on $sock"
    fi

    # This host only: the node is reached on 127.0.0.1, so no DNS is needed.
    local host cpus mem_kb mem port
    host=$(hostname -s 2>/dev/null || uname -n)
    host=${host%%.*}
    [[ -n $host ]] || fail "cannot determine the short hostname"
    cpus=$(nproc 2>/dev/null || getconf _NPROCESSORS_ONLN)
    mem_kb=$(awk '/^MemTotal:/ { print $2 }' /proc/meminfo)
    mem=$((mem_kb / 1024))
    ((mem > 1)) || mem=1
    port=$(free_port_pair) || fail "no free TCP port pair found"

    cat >"$conf" <<EOF
# Single-node test cluster generated by $PROG for $DIR.
ClusterName=local$port
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$port
SlurmdPort=$((port + 1))
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$sock
CredType=cred/munge
StateSaveLocation=$DIR/state
SlurmdSpoolDir=$DIR/spool
SlurmctldPidFile=$DIR/run/slurmctld.pid
SlurmdPidFile=$DIR/run/slurmd.pid
SlurmctldLogFile=$DIR/log/slurmctld.log
SlurmdLogFile=$DIR/log/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
SwitchType=switch/none
SchedulerType=sched/builtin
SchedulerParameters=batch_sched_delay=0
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
SlurmctldTimeout=30
SlurmdTimeout=30
MessageTimeout=10
InactiveLimit=0
KillWait=5
MinJobAge=${SLURM_LOCAL_MIN_JOB_AGE:-5}
MailProg=/bin/true
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=local Nodes=$host Default=YES MaxTime=INFINITE State=UP OverSubscribe=NO
EOF

    export SLURM_CONF=$conf
    # -c: start with empty job state (DIR may be reused).
    slurmctld -c -f "$conf" >"$DIR/log/slurmctld.out" 2>&1 ||
        { cat "$DIR/log/slurmctld.out" >&2; fail "slurmctld did not start"; }
    slurmd -N "$host" -f "$conf" >"$DIR/log/slurmd.out" 2>&1 ||
        { cat "$DIR/log/slurmd.out" >&2; fail "slurmd did not start"; }

    local state="" reason
    for ((i = 0; i < START_TIMEOUT * 2; i++)); do
        pid_alive "$DIR/run/slurmctld.pid" slurmctld >/dev/null || { ((i < 4)) || fail "slurmctld exited"; }
        pid_alive "$DIR/run/slurmd.pid" slurmd >/dev/null || { ((i < 4)) || fail "slurmd exited"; }
        state=$(timeout 5 sinfo -h -n "$host" -o %T 2>/dev/null | head -n 1) || state=""
        case $state in
            idle) break ;;
            drain* | invalid* | fail*)
                reason=$(timeout 5 scontrol show node "$host" 2>/dev/null | grep -o 'Reason=.*' || true)
                fail "node $host is $state ${reason:-}" ;;
        esac
        sleep 0.5
    done
    [[ $state == idle ]] || fail "node $host not idle after ${START_TIMEOUT}s (state: ${state:-unknown})"

    echo "export SLURM_CONF=$conf" >"$DIR/env.sh"
    log "cluster up: node $host idle, CPUs=$cpus, ports $port/$((port + 1))"
    echo "export SLURM_CONF=$conf"
    trap - EXIT
}

# --- main ------------------------------------------------------------------

[[ $# -eq 2 ]] || usage
ACTION=$1
[[ -n $2 ]] || usage
case $2 in
    /*) DIR=$2 ;;
    *) DIR=$PWD/$2 ;;
esac
DIR=${DIR%/}

case $ACTION in
    start)
        mkdir -p "$DIR"
        DIR=$(cd "$DIR" && pwd -P)
        do_start
        ;;
    stop)
        [[ -d $DIR ]] || exit 0
        DIR=$(cd "$DIR" && pwd -P)
        do_stop || { echo "$PROG: FAILED: some processes from $DIR could not be stopped" >&2; exit 1; }
        ;;
    status)
        [[ -d $DIR ]] || exit 1
        DIR=$(cd "$DIR" && pwd -P)
        pid_alive "$DIR/munge/munged.pid" munged >/dev/null &&
            pid_alive "$DIR/run/slurmctld.pid" slurmctld >/dev/null &&
            pid_alive "$DIR/run/slurmd.pid" slurmd >/dev/null
        ;;
    *) usage ;;
esac
