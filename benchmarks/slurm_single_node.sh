#!/usr/bin/env bash
# The workflow through SLURM on this one machine, checked against a local run.
#
#   sudo bash benchmarks/slurm_single_node.sh          (as root, from any directory)
#
# Installs Debian's slurm-wlm and munge, writes a one-node /etc/slurm/slurm.conf, starts munged,
# slurmctld and slurmd in the foreground of this script (no systemd), installs the SLURM executor
# plugin into the project's virtualenv, runs benchmarks/reduced.yaml once locally in the default
# grain and once through profiles/slurm in the cluster grain (config/variants/per_condition.yaml:
# one estimate job per condition and estimator) in two fresh copies of the workflow, compares the
# collected results value for value and prints both wall times. Every daemon it started is stopped on exit, and the
# slurm.conf it wrote is removed. Nothing else on the machine is touched: an existing slurm.conf
# or running SLURM daemon stops the script before it changes anything.
#
# Environment: JOINTBENCH_VENV (default: .venv in the work tree, created if missing),
# SLURM_CHECK_DIR (default: a new temporary folder; kept afterwards for inspection).
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
VENV=${JOINTBENCH_VENV:-$ROOT/.venv}
WORK=${SLURM_CHECK_DIR:-$(mktemp -d /tmp/jointbench-slurm.XXXXXX)}
CONFIGFILE=$ROOT/benchmarks/reduced.yaml
# The grain meant for a cluster: many small jobs rather than one per study and estimator.
CLUSTER_GRAIN=$ROOT/config/variants/per_condition.yaml
SLURM_CONF=/etc/slurm/slurm.conf
# The daemons' state, spool and logs: a folder of their own, not one of the runs' workflow copies.
STATE=$WORK/daemons
NODE=$(hostname -s)

STARTED_PIDS=()
WROTE_CONF=0

log() { printf '[slurm-check %(%H:%M:%S)T] %s\n' -1 "$*" >&2; }
die() {
    log "ERROR: $*"
    exit 1
}

# ---- refuse to disturb anything already there ---------------------------------------------------

preflight() {
    [[ $EUID -eq 0 ]] || die "run as root: it installs packages and starts system daemons"
    [[ -f $CONFIGFILE ]] || die "missing $CONFIGFILE"
    [[ -f $CLUSTER_GRAIN ]] || die "missing $CLUSTER_GRAIN"
    if [[ -e $SLURM_CONF ]]; then
        die "$SLURM_CONF already exists: this script writes its own one-node configuration" \
            "there and will not overwrite a real one; move it away first"
    fi
    local daemon
    for daemon in slurmctld slurmd munged; do
        if pgrep -x "$daemon" >/dev/null; then
            die "a $daemon is already running; stop it first (this script starts its own)"
        fi
    done
}

# ---- software -----------------------------------------------------------------------------------

install_packages() {
    if command -v slurmctld >/dev/null && command -v slurmd >/dev/null \
        && command -v munged >/dev/null && command -v sbatch >/dev/null; then
        log "slurm-wlm and munge already installed"
        return
    fi
    log "installing slurm-wlm and munge"
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
        slurm-wlm munge >"$WORK/apt.log" 2>&1 || die "apt-get install failed, see $WORK/apt.log"
}

install_python() {
    if [[ ! -x $VENV/bin/python ]]; then
        log "creating $VENV"
        python3 -m venv "$VENV"
    fi
    log "installing jointbench with the cluster extra into $VENV"
    "$VENV/bin/pip" install -q -e "${ROOT}[cluster]" >"$WORK/pip.log" 2>&1 \
        || die "pip install failed, see $WORK/pip.log"
}

# ---- daemons ------------------------------------------------------------------------------------

# Started in the foreground mode of each daemon and put in the background here, so that $! is the
# daemon itself and the exit trap can stop exactly the processes this script started.
start_munge() {
    install -d -o munge -g munge -m 0755 /run/munge
    if [[ ! -s /etc/munge/munge.key ]]; then
        log "creating a munge key"
        setpriv --reuid=munge --regid=munge --init-groups mungekey --create
    fi
    setpriv --reuid=munge --regid=munge --init-groups \
        munged --foreground >"$STATE/munged.log" 2>&1 &
    STARTED_PIDS+=($!)
    wait_for "munge credentials" 20 munge_works
}

munge_works() { munge -n </dev/null | unmunge >/dev/null 2>&1; }

write_slurm_conf() {
    # Memory the node offers: what slurmd detects, less 1 GB for the daemons and Snakemake itself.
    local detected
    detected=$(slurmd -C | sed -n 's/.*RealMemory=\([0-9]*\).*/\1/p')
    [[ -n $detected ]] || die "slurmd -C did not report the node's memory"
    local memory=$((detected - 1024))
    local cpus
    cpus=$(nproc)
    log "writing $SLURM_CONF: node $NODE, $cpus CPUs, $memory MB"
    mkdir -p "$STATE/state" "$STATE/spool" /etc/slurm
    # The job step daemon reads slurm.conf from its default place whatever SLURM_CONF says, so the
    # file must be there. No accounting daemon: the executor reads job states from squeue, which
    # keeps a finished job for MinJobAge seconds (comfortably longer than one status interval).
    cat >"$SLURM_CONF" <<EOF
# Written by jointbench benchmarks/slurm_single_node.sh; removed when it exits.
ClusterName=jointbench
SlurmctldHost=$NODE(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
MpiDefault=none
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SwitchType=switch/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
JobCompType=jobcomp/none
MinJobAge=600
ReturnToService=2
SlurmctldTimeout=30
SlurmdTimeout=30
StateSaveLocation=$STATE/state
SlurmdSpoolDir=$STATE/spool
SlurmctldPidFile=$STATE/slurmctld.pid
SlurmdPidFile=$STATE/slurmd.pid
SlurmctldLogFile=$STATE/slurmctld.log
SlurmdLogFile=$STATE/slurmd.log
NodeName=$NODE NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$memory State=UNKNOWN
PartitionName=main Nodes=$NODE Default=YES MaxTime=INFINITE State=UP
EOF
    WROTE_CONF=1
}

start_slurm() {
    slurmctld -D -c >"$STATE/slurmctld.out" 2>&1 &
    STARTED_PIDS+=($!)
    wait_for "slurmctld" 30 scontrol ping
    slurmd -D -N "$NODE" >"$STATE/slurmd.out" 2>&1 &
    STARTED_PIDS+=($!)
    wait_for "node $NODE idle" 60 node_idle
}

node_idle() { [[ $(sinfo -h -n "$NODE" -o %T 2>/dev/null) == idle ]]; }

# wait_for WHAT SECONDS COMMAND...: poll until COMMAND succeeds, or fail naming WHAT.
wait_for() {
    local what=$1 seconds=$2
    shift 2
    local deadline=$((SECONDS + seconds))
    until "$@" >/dev/null 2>&1; do
        if ((SECONDS >= deadline)); then
            die "no $what after ${seconds}s; logs in $STATE"
        fi
        sleep 0.5
    done
    log "$what: ready"
}

stop_everything() {
    local status=$?
    set +e
    if ((${#STARTED_PIDS[@]})); then
        # Jobs left by a failed run: only this cluster's, which this script started.
        if scontrol ping >/dev/null 2>&1; then
            squeue -h -o %i | xargs -r scancel
        fi
        local pid index
        # Stop in reverse order of starting: slurmd, slurmctld, then munged.
        for ((index = ${#STARTED_PIDS[@]} - 1; index >= 0; index--)); do
            pid=${STARTED_PIDS[index]}
            kill "$pid" 2>/dev/null && wait "$pid" 2>/dev/null
        done
        log "stopped the daemons this script started (pids ${STARTED_PIDS[*]})"
    fi
    if ((WROTE_CONF)); then
        rm -f "$SLURM_CONF"
    fi
    log "work folder kept: $WORK"
    exit "$status"
}

# ---- the two runs -------------------------------------------------------------------------------

# A fresh copy of what a user clones, so both runs start from an empty results/. profiles/ too:
# Snakemake applies profiles/default (keep-going) beside --profile profiles/slurm.
copy_workflow() {
    local destination=$1
    mkdir -p "$destination"
    cp -r "$ROOT/Snakefile" "$ROOT/workflow" "$ROOT/config" "$ROOT/profiles" "$destination/"
}

run_local() {
    copy_workflow "$WORK/local"
    log "local run: snakemake -j2"
    (cd "$WORK/local" && "$VENV/bin/snakemake" -j2 --configfile "$CONFIGFILE") \
        >"$WORK/local.log" 2>&1 || die "local run failed, see $WORK/local.log"
}

# Options that only this test cluster needs, on top of the profile: no accounting (squeue for job
# states, no account to guess) and short jobs (first status check after 2 s, not 40 s).
run_slurm() {
    copy_workflow "$WORK/slurm"
    log "SLURM run: snakemake --profile profiles/slurm, one estimate job per condition"
    (cd "$WORK/slurm" && "$VENV/bin/snakemake" --profile "$ROOT/profiles/slurm" \
        --configfile "$CONFIGFILE" "$CLUSTER_GRAIN" \
        --slurm-status-command squeue \
        --slurm-no-account \
        --slurm-init-seconds-before-status-checks 2 \
        --latency-wait 5) \
        >"$WORK/slurm.log" 2>&1 || die "SLURM run failed, see $WORK/slurm.log"
    local submitted
    submitted=$(grep -c "has been submitted with SLURM jobid" "$WORK/slurm.log" || true)
    log "SLURM run: $submitted jobs submitted"
}

# A job that fails must stop the run with an error, not leave Snakemake waiting: the way the
# executor learns about failures (squeue, no accounting) is the part most likely to go wrong.
check_failure_is_noticed() {
    local folder=$WORK/failing
    mkdir -p "$folder"
    cat >"$folder/Snakefile" <<'EOF'
rule fail:
    output:
        "never.txt",
    shell:
        "echo 'a deliberate failure' >&2; exit 3"
EOF
    log "a failing job through SLURM (must stop the run within 5 minutes)"
    local status=0
    (cd "$folder" && timeout 300 "$VENV/bin/snakemake" --profile "$ROOT/profiles/slurm" \
        --slurm-status-command squeue \
        --slurm-no-account \
        --slurm-init-seconds-before-status-checks 2 \
        --latency-wait 5) >"$WORK/failing.log" 2>&1 || status=$?
    if ((status == 124)); then
        die "a failed SLURM job went unnoticed: Snakemake still waiting after 300 s" \
            "(see $WORK/failing.log)"
    fi
    ((status != 0)) || die "the deliberately failing job succeeded (see $WORK/failing.log)"
    log "the failed job was reported (snakemake exit status $status)"
}

# timed NAME COMMAND...: run COMMAND here (not in a subshell, so its failure stops the script)
# and store its wall time in seconds in the variable NAME.
timed() {
    local -n seconds=$1
    shift
    local start=$EPOCHREALTIME
    "$@"
    seconds=$(awk -v a="$start" -v b="$EPOCHREALTIME" 'BEGIN { printf "%.1f", b - a }')
}

main() {
    preflight
    mkdir -p "$WORK" "$STATE"
    trap stop_everything EXIT
    trap 'exit 130' INT TERM
    log "work folder: $WORK"
    install_packages
    install_python
    start_munge
    write_slurm_conf
    start_slurm
    local local_seconds slurm_seconds
    timed local_seconds run_local
    timed slurm_seconds run_slurm
    log "comparing collected results"
    "$VENV/bin/python" "$ROOT/benchmarks/compare_collected.py" "$WORK/local" "$WORK/slurm" \
        || die "the SLURM run's results differ from the local run's"
    log "wall time: local -j2 ${local_seconds}s, SLURM per condition ${slurm_seconds}s" \
        "(same results)"
    check_failure_is_noticed
}

# Run when executed; sourcing only defines the functions (to run one step by hand).
if [[ ${BASH_SOURCE[0]} == "$0" ]]; then
    main "$@"
fi
