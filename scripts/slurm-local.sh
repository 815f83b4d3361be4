#!/usr/bin/env bash
# Runs deploy/slurm/render-units.sbatch as a job array of N units, then its dependent
# deploy/slurm/assemble.sbatch, under a real single-node Slurm started just for this run
# (munged, slurmctld and slurmd on this host, all files in a scratch directory), and checks
# that the assembled PNG is byte-identical to one render of the whole scene. Prints PASS
# or FAIL with timings; exits non-zero on failure. Everything it starts is stopped and the
# scratch directory removed on exit, failure included. Run from the repository root:
#
#   scripts/slurm-local.sh [SCENE] [N]      # defaults: scenes/full-set.toml 4
#   DEEPFIELD=target/release/deepfield scripts/slurm-local.sh scenes/douady-rabbit.toml 8
#
# Needs deepfield on PATH (or DEEPFIELD=path). Installs slurm-wlm and munge with apt-get
# (Debian/Ubuntu) when they are missing, which needs root; the daemons and jobs then run as
# the invoking user (root here). Tested with Slurm 22.05 (Debian 12) in a container without
# systemd or cgroups. Env: CPUS_PER_TASK (default 1), TIMEOUT seconds (default 300),
# KEEP=1 keeps the scratch directory.
set -euo pipefail
[[ -f deploy/slurm/render-units.sbatch ]] || { echo "run from the repository root" >&2; exit 2; }
scene=$(realpath "${1:-scenes/full-set.toml}") n=${2:-4}
cpt=${CPUS_PER_TASK:-1} timeout=${TIMEOUT:-300}
repo=$PWD

# 1. Packages: the daemons, the client tools and munge (Slurm's authentication).
if ! command -v slurmctld > /dev/null || ! command -v slurmd > /dev/null ||
    ! command -v sbatch > /dev/null || ! command -v munged > /dev/null; then
    echo "installing slurm-wlm and munge (apt-get)..."
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq && apt-get install -y -qq --no-install-recommends slurm-wlm munge > /dev/null
fi

# Scratch directory and teardown. Daemons run in the foreground (-D/-F) as background jobs
# of this shell, so $! is their pid and the trap can stop exactly what this script started.
tmp=$(mktemp -d "${TMPDIR:-/tmp}/slurm-local.XXXXXX")
pids=()
cleanup() {
    local rc=$?
    if [[ ${SLURM_CONF:-} == "$tmp/slurm.conf" ]]; then scancel --quiet --user="$(id -un)" 2> /dev/null || true; fi
    for ((i = ${#pids[@]} - 1; i >= 0; i--)); do kill "${pids[i]}" 2> /dev/null || true; done
    wait 2> /dev/null || true
    if [[ ${KEEP:-0} == 1 ]]; then echo "kept $tmp"; else rm -rf "$tmp"; fi
    exit "$rc"
}
trap cleanup EXIT
trap 'exit 130' INT TERM
mkdir -p "$tmp"/{bin,state,spool,log,work/units}

# deepfield for the jobs: they inherit this PATH (sbatch --export=ALL).
bin=$(command -v "${DEEPFIELD:-deepfield}") || { echo "deepfield not found (set DEEPFIELD)" >&2; exit 2; }
ln -s "$(realpath "$bin")" "$tmp/bin/deepfield"
export PATH="$tmp/bin:$PATH"

# 2. munged with its own key and socket, so nothing under /etc or /run is touched.
dd if=/dev/urandom of="$tmp/munge.key" bs=1024 count=1 status=none
chmod 600 "$tmp/munge.key"
sock="$tmp/munge.socket"
munged -F --force --socket="$sock" --key-file="$tmp/munge.key" --pid-file="$tmp/munged.pid" \
    --seed-file="$tmp/munged.seed" --log-file="$tmp/log/munged.log" > /dev/null 2>&1 &
pids+=($!)

# A minimal slurm.conf: this host as controller and only node, no cgroups (linuxproc
# process tracking, no task plugin), no accounting database. Random ports avoid clashing
# with a Slurm already running here or another run of this script.
host=$(hostname -s) user=$(id -un) port=$((20000 + RANDOM % 20000))
mem=$(free -m | awk '/^Mem:/ { print $2 }')
export SLURM_CONF="$tmp/slurm.conf"
cat > "$SLURM_CONF" << EOF
ClusterName=local
SlurmctldHost=$host(127.0.0.1)
SlurmUser=$user
SlurmdUser=$user
SlurmctldPort=$port
SlurmdPort=$((port + 1))
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$sock
StateSaveLocation=$tmp/state
SlurmdSpoolDir=$tmp/spool
SlurmctldPidFile=$tmp/slurmctld.pid
SlurmdPidFile=$tmp/slurmd.pid
SlurmctldLogFile=$tmp/log/slurmctld.log
SlurmdLogFile=$tmp/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SlurmdParameters=config_overrides
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
MpiDefault=none
MailProg=/bin/true
ReturnToService=2
MinJobAge=3600
SchedulerParameters=sched_interval=1
NodeName=$host NodeAddr=127.0.0.1 CPUs=$(nproc) RealMemory=$mem State=UNKNOWN
PartitionName=local Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
for ((i = 0; i < 50; i++)); do [[ -S $sock ]] && break; sleep 0.1; done
# -D: foreground, logging to stderr too (kept out of the way); -c: ignore any saved state.
slurmctld -D -c -i -f "$SLURM_CONF" 2> "$tmp/log/slurmctld.err" &
pids+=($!)
slurmd -D -f "$SLURM_CONF" 2> "$tmp/log/slurmd.err" &
pids+=($!)
# Wait until the node is up and idle.
for ((i = 0; ; i++)); do
    state=$(sinfo -h -n "$host" -o %T 2> /dev/null || true)
    [[ $state == idle ]] && break
    ((i < 300)) || { echo "node not up (state '$state'); see $tmp/log" >&2; tail -n 20 "$tmp"/log/*.log >&2; exit 1; }
    sleep 0.2
done
echo "Slurm $(sinfo --version | awk '{ print $2 }') up: node $host, $(nproc) CPUs, ${mem} MiB; scratch $tmp"

# 3. The job array and its dependent assemble job, submitted as the README shows.
cd "$tmp/work"
t0=$(date +%s.%N)
jid=$(sbatch --parsable --array=0-$((n - 1)) --cpus-per-task="$cpt" \
    --export=ALL,SCENE="$scene",UNITS="$n" "$repo/deploy/slurm/render-units.sbatch")
jid=${jid%%;*}
aid=$(sbatch --parsable --dependency=afterok:"$jid" --kill-on-invalid-dep=yes \
    --export=ALL,UNITS="$n",OUT=slurm.png "$repo/deploy/slurm/assemble.sbatch")
aid=${aid%%;*}
echo "submitted array job $jid (units 0-$((n - 1))) and assemble job $aid"
# Poll until neither job has a task left pending or running, then read their final states.
for ((i = 0; ; i++)); do
    [[ -z $(squeue -h -j "$jid,$aid" -o %i) ]] && break
    ((i < timeout * 5)) || { echo "timed out after ${timeout}s" >&2; squeue -j "$jid,$aid" >&2; exit 1; }
    sleep 0.2
done
t1=$(date +%s.%N)
states=$( (scontrol show job -o "$jid"; scontrol show job -o "$aid") | grep -o 'JobState=[A-Z_]*' | sort | uniq -c | xargs)
echo "job states: $states"

# 4. The same scene in one piece, and the byte comparison.
fail() {
    echo "FAIL: $*; last log lines:" >&2
    tail -n 5 units/*.log "$tmp"/log/slurm*.log >&2 || true
    exit 1
}
[[ $states == "$((n + 1)) JobState=COMPLETED" ]] || fail "jobs did not all complete"
deepfield render "$scene" --quiet -o whole.png || fail "the one-piece render failed"
t2=$(date +%s.%N)
secs() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.2fs", b - a }'; }
cmp slurm.png whole.png || fail "the assembled image differs from the one-piece render"
echo "PASS: $n Slurm units + assemble ($(secs "$t0" "$t1")) == one render ($(secs "$t1" "$t2")), $(stat -c %s whole.png) bytes"
