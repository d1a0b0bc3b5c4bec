#!/bin/bash
# Real-Slurm test of the grid scripts, for CI (as root, Debian 12, no systemd needed):
#   1. brings up a throwaway single-node cluster (munge + slurmctld + slurmd) whose state lives
#      in a temporary directory, installing the Debian packages if they are missing;
#   2. submits the grid at tiny scale with slurm/submit.sh: 4 array tasks (seed 1 of each
#      experiment), 2 ranks each, 2 generations of a tiny problem, plus the afterok aggregation;
#   3. waits (1 s polling, hard timeout), then checks every task and the aggregation job
#      (COMPLETED, exit 0), every archive (`softevo info --json`: complete, 2 generations) and
#      the aggregation table (4 runs, 4 experiments);
#   4. submits the same 4 runs packed into one job (slurm/packed.sbatch, 2 ranks, one worker
#      pool) and checks that each archive equals the array task's (fitness and content digest);
#   5. tears the cluster down (trap: also on failure or timeout).
# Usage: slurm/ci-slurm-test.sh [BUILD_DIR]   (default: build; softevo and softevo-mpi built)
# Exit 0 = pass. Debian's Open MPI launches under Slurm with pmix, not pmi2; an afterok
# dependency on a failed array needs DependencyParameters=kill_invalid_depend; root needs the
# OMPI_ALLOW_RUN_AS_ROOT pair.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=$(cd "${1:-$ROOT/build}" && pwd)
TIMEOUT=${SOFTEVO_SLURM_TIMEOUT:-600}     # [s] hard limit for the jobs
STATE=$(mktemp -d /tmp/softevo-slurm-ci.XXXXXX)
RUNS=$STATE/runs
CONF=/etc/slurm/slurm.conf
STARTED_MUNGE=0
log() { echo "[slurm-ci] $*"; }

for b in softevo softevo-mpi; do
  [ -x "$BUILD/bin/$b" ] || { log "missing $BUILD/bin/$b (build first)"; exit 2; }
done
[ "$(id -u)" = 0 ] || { log "needs root (starts daemons, writes $CONF)"; exit 2; }

install_packages() {
  local need=0 c
  for c in slurmctld slurmd sbatch munged mpirun; do command -v "$c" >/dev/null || need=1; done
  [ "$need" = 0 ] && return
  log "installing slurmctld slurmd slurm-client munge"
  # The postinst scripts try to start services; without systemd they just do not run, so the
  # daemons are started by hand below.
  apt-get -o DPkg::Lock::Timeout=600 update -qq >/dev/null || true
  DEBIAN_FRONTEND=noninteractive apt-get -o DPkg::Lock::Timeout=600 install -y -qq \
    --no-install-recommends slurmctld slurmd slurm-client munge openmpi-bin >/dev/null
}

cluster_up() {
  [ -e "$CONF" ] && { log "$CONF exists (a real cluster?): refusing to replace it"; exit 2; }
  mkdir -p "$STATE"/{state,spool,log} "$RUNS"
  # munge: reuse a running munged, else start one as user munge (it insists on owning its
  # key and run directory).
  if ! munge -n >/dev/null 2>&1; then
    install -d -o munge -g munge -m 0755 /run/munge
    [ -s /etc/munge/munge.key ] || runuser -u munge -- mungekey --create --keyfile=/etc/munge/munge.key
    runuser -u munge -- /usr/sbin/munged
    STARTED_MUNGE=1
    for _ in $(seq 50); do munge -n >/dev/null 2>&1 && break; sleep 0.1; done
  fi
  munge -n | unmunge >/dev/null
  local node nodeline
  node=$(hostname -s)
  nodeline=$(slurmd -C | head -n 1)   # real sockets/cores/memory: no "reconfigured" drain
  mkdir -p /etc/slurm
  cat > "$CONF" <<CONFEOF
# throwaway test cluster of softevo slurm/ci-slurm-test.sh (removed on exit)
ClusterName=softevo-ci
SlurmctldHost=${node}(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/filetxt
JobCompLoc=${STATE}/jobcomp.txt
MpiDefault=none
MailProg=/usr/bin/true
ReturnToService=2
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerParameters=batch_sched_delay=0,sched_min_interval=0
DependencyParameters=kill_invalid_depend
SlurmctldPidFile=${STATE}/slurmctld.pid
SlurmdPidFile=${STATE}/slurmd.pid
StateSaveLocation=${STATE}/state
SlurmdSpoolDir=${STATE}/spool
SlurmctldLogFile=${STATE}/log/slurmctld.log
SlurmdLogFile=${STATE}/log/slurmd.log
${nodeline} NodeAddr=127.0.0.1 State=UNKNOWN
PartitionName=ci Nodes=${node} Default=YES MaxTime=INFINITE State=UP OverSubscribe=NO
CONFEOF
  /usr/sbin/slurmctld
  /usr/sbin/slurmd -N "$node"
  for _ in $(seq 120); do
    [ "$(sinfo -h -N -o '%t' 2>/dev/null)" = idle ] && return 0
    sleep 0.5
  done
  log "node never became idle"; sinfo -N || true; tail -n 30 "$STATE"/log/*.log || true
  return 1
}

cluster_down() {
  local pids=() f
  for f in slurmctld slurmd; do [ -f "$STATE/$f.pid" ] && pids+=("$(cat "$STATE/$f.pid")"); done
  if [ -e "$CONF" ] && grep -qs 'softevo slurm/ci-slurm-test.sh' "$CONF"; then
    squeue -h -o %A 2>/dev/null | sort -u | xargs -r scancel 2>/dev/null || true
    for _ in $(seq 30); do [ -z "$(squeue -h 2>/dev/null)" ] && break; sleep 0.5; done
    scontrol shutdown >/dev/null 2>&1 || true
  fi
  for p in "${pids[@]}"; do
    for _ in $(seq 100); do kill -0 "$p" 2>/dev/null || break; sleep 0.1; done
    kill -KILL "$p" 2>/dev/null || true
  done
  if [ "$STARTED_MUNGE" = 1 ] && [ -f /run/munge/munged.pid ]; then
    kill -TERM "$(cat /run/munge/munged.pid)" 2>/dev/null || true
  fi
  grep -qs 'softevo slurm/ci-slurm-test.sh' "$CONF" && rm -f "$CONF"
  rm -rf "$STATE"
}

# One line per job record; true if every record (all array tasks) COMPLETED with 0:0. An unknown
# id fails too.
jobs_ok() {
  local s
  s=$(scontrol show job -o "$1" 2>/dev/null) && [ -n "$s" ] &&
    ! grep -v 'JobState=COMPLETED' <<<"$s" | grep -q . &&
    ! grep -v 'ExitCode=0:0' <<<"$s" | grep -q .
}

install_packages
trap 'rc=$?; log "tearing down"; cluster_down; exit $rc' EXIT
t0=$(date +%s)
cluster_up
log "cluster up in $(( $(date +%s) - t0 )) s"

export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1   # jobs inherit the env
export OMPI_MCA_rmaps_base_oversubscribe=1
read -r ARRAY AGG < <(SOFTEVO_BUILD=$BUILD SOFTEVO_RUNS=$RUNS SOFTEVO_ARRAY=0,10,20,30 \
  SOFTEVO_NTASKS=2 SOFTEVO_TIME=00:30:00 \
  SOFTEVO_ARGS="--generations 2 --population 4 --set body.lattice=[5,5,5] --set task.eval_seconds=0.1" \
  "$ROOT/slurm/submit.sh")
log "submitted array $ARRAY, aggregation $AGG"
deadline=$(( $(date +%s) + TIMEOUT ))
while [ -n "$(squeue -h -j "$ARRAY,$AGG" 2>/dev/null)" ]; do
  if [ "$(date +%s)" -gt "$deadline" ]; then
    log "TIMEOUT after $TIMEOUT s"; squeue || true; exit 1
  fi
  sleep 1
done
log "jobs done in $(( $(date +%s) - t0 )) s"

fail=0
check() { if "$@"; then :; else log "FAIL: $*"; fail=1; fi; }
show_logs() { for f in "$RUNS"/*.out; do echo "--- $f"; tail -n 20 "$f"; done; }
check jobs_ok "$ARRAY"
check jobs_ok "$AGG"
for exp in gait-open gait-closed dir-open dir-closed; do
  h5=$RUNS/$exp-01.h5
  if ! info=$("$BUILD/bin/softevo" info "$h5" --json); then log "FAIL: $h5 unreadable"; fail=1; continue; fi
  state=$(python3 -c 'import json,sys; d=json.load(sys.stdin); print(d["state"], d["generations_done"], d["experiment"], len(d["generations"]))' <<<"$info")
  [ "$state" = "complete 2 $exp 2" ] && log "ok: $h5 ($state)" || { log "FAIL: $h5: $state"; fail=1; }
done
summary=$RUNS/grid-summary.tsv
if [ -f "$summary" ]; then
  rows=$(tail -n +2 "$summary" | wc -l)
  exps=$(tail -n +2 "$summary" | cut -f1 | sort -u | wc -l)
  [ "$rows" = 4 ] && [ "$exps" = 4 ] && log "ok: aggregation table with $rows runs, $exps experiments" ||
    { log "FAIL: aggregation table: $rows rows, $exps experiments"; fail=1; }
  cat "$RUNS"/softevo-grid-aggregate-*.out
else
  log "FAIL: no $summary"; fail=1
fi
# The same four runs packed into one job: the archives of the array tasks, bit for bit.
PACKED=$STATE/packed
read -r JOB PAGG < <(SOFTEVO_BUILD=$BUILD SOFTEVO_RUNS=$PACKED SOFTEVO_NODES=1 \
  SOFTEVO_TASKS_PER_NODE=2 SOFTEVO_SEEDS=1 SOFTEVO_TIME=00:30:00 \
  SOFTEVO_ARGS="--generations 2 --population 4 --set body.lattice=[5,5,5] --set task.eval_seconds=0.1" \
  "$ROOT/slurm/submit.sh")
log "submitted packed job $JOB, aggregation $PAGG"
while [ -n "$(squeue -h -j "$JOB,$PAGG" 2>/dev/null)" ]; do
  if [ "$(date +%s)" -gt "$deadline" ]; then
    log "TIMEOUT after $TIMEOUT s"; squeue || true; exit 1
  fi
  sleep 1
done
check jobs_ok "$JOB"
check jobs_ok "$PAGG"
digests() { "$BUILD/bin/softevo" info "$1" --json |
  python3 -c 'import json,sys; d=json.load(sys.stdin); print(d["fitness_digest"], d["content_digest"])'; }
for exp in gait-open gait-closed dir-open dir-closed; do
  a=$(digests "$RUNS/$exp-01.h5" || echo "unreadable array archive")
  p=$(digests "$PACKED/$exp-01.h5" || echo "unreadable packed archive")
  [ "$a" = "$p" ] && log "ok: packed $exp-01.h5 = array task ($p)" ||
    { log "FAIL: packed $exp-01.h5: $p, array task: $a"; fail=1; }
done
[ "$fail" = 0 ] || { show_logs; for f in "$PACKED"/*.out; do echo "--- $f"; tail -n 20 "$f"; done; }
if [ "$fail" = 0 ]; then log "1 passed, 0 failed"; else log "0 passed, 1 failed"; fi
exit "$fail"
