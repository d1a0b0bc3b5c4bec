#!/bin/bash
# Submit the 4x10 grid and its aggregation job (runs only if every array task succeeded).
#   slurm/submit.sh                      # the full grid: 40 tasks, 5 ranks each
#   SOFTEVO_ARRAY=0,10,20,30 SOFTEVO_NTASKS=2 SOFTEVO_ARGS="--generations 2" slurm/submit.sh
#   SOFTEVO_NODES=4 SOFTEVO_TASKS_PER_NODE=128 slurm/submit.sh
#                                        # packed: all 40 runs in one job on 4 nodes, one
#                                        # worker pool (slurm/packed.sbatch)
# Packed mode (SOFTEVO_NODES set): SOFTEVO_SEEDS (default 1-10, the seeds of every experiment)
# and SOFTEVO_TASKS_PER_NODE (ranks per node, default: Slurm's, one per core) replace
# SOFTEVO_ARRAY and SOFTEVO_NTASKS.
# Prints "ARRAY_JOB_ID AGGREGATION_JOB_ID". Environment: see slurm/grid.sbatch, plus
#   SOFTEVO_ARRAY (array spec, default 0-39), SOFTEVO_NTASKS (ranks per task, default 5),
#   SOFTEVO_TIME (time limit per task, default 7-00:00:00), SOFTEVO_BUILD (default build), and
#   the site settings of slurm/site.sh (partition, account, memory, modules, launcher).
#   slurm/submit.sh --experiments gait-rough-open,gait-rough-closed --seeds 1-10
#                                        # any experiments (configs/<name>.toml), seeds A-B each
#   slurm/submit.sh --experiments gait-open,gait-open-map-elites,gait-open-afpo --seeds 1-10
#                                        # search strategies x seeds (docs/guide.md, "Search
#                                        # strategies"): NEAT, MAP-Elites, AFPO, 10 seeds each
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
while [ $# -gt 0 ]; do
  case "$1" in
    --experiments) export SOFTEVO_EXPERIMENTS=${2:?--experiments needs a list}; shift 2 ;;
    --seeds)
      [[ ${2:-} =~ ^([0-9]+)-([0-9]+)$ ]] && (( BASH_REMATCH[1] <= BASH_REMATCH[2] )) ||
        { echo "submit.sh: --seeds wants A-B with A <= B, got '${2:-}'" >&2; exit 2; }
      export SOFTEVO_SEED_FIRST=${BASH_REMATCH[1]}
      export SOFTEVO_REPS=$(( BASH_REMATCH[2] - BASH_REMATCH[1] + 1 )); shift 2 ;;
    *) echo "submit.sh: unknown argument '$1' (--experiments LIST, --seeds A-B)" >&2; exit 2 ;;
  esac
done
IFS=, read -ra EXPS <<<"${SOFTEVO_EXPERIMENTS:-gait-open,gait-closed,dir-open,dir-closed}"
for e in "${EXPS[@]}"; do
  [ -f "$ROOT/configs/$e.toml" ] || { echo "submit.sh: no config configs/$e.toml" >&2; exit 2; }
done
export SOFTEVO_EXPERIMENTS=$(IFS=,; echo "${EXPS[*]}")
# shellcheck source=slurm/site.sh
. "$ROOT/slurm/site.sh"
SITE_ARGS=()
[ -z "${SOFTEVO_PARTITION:-}" ] || SITE_ARGS+=(--partition="$SOFTEVO_PARTITION")
[ -z "${SOFTEVO_ACCOUNT:-}" ] || SITE_ARGS+=(--account="$SOFTEVO_ACCOUNT")
[ -z "${SOFTEVO_MEM:-}" ] || SITE_ARGS+=(--mem-per-cpu="$SOFTEVO_MEM")
BUILD=${SOFTEVO_BUILD:-$ROOT/build}
export SOFTEVO_ROOT=$ROOT
export SOFTEVO_MPI=${SOFTEVO_MPI:-$BUILD/bin/softevo-mpi}
export SOFTEVO_CLI=${SOFTEVO_CLI:-$BUILD/bin/softevo}
export SOFTEVO_RUNS=${SOFTEVO_RUNS:-$ROOT/runs}
export SOFTEVO_REPS=${SOFTEVO_REPS:-10}
export SOFTEVO_SEED_FIRST=${SOFTEVO_SEED_FIRST:-1}
export SOFTEVO_ARRAY=${SOFTEVO_ARRAY:-0-$(( ${#EXPS[@]} * SOFTEVO_REPS - 1 ))}
for b in "$SOFTEVO_MPI" "$SOFTEVO_CLI"; do
  [ -x "$b" ] || { echo "submit.sh: $b not built (cmake --build $BUILD)" >&2; exit 2; }
done
mkdir -p "$SOFTEVO_RUNS"
if [ -n "${SOFTEVO_NODES:-}" ]; then
  export SOFTEVO_SEEDS=${SOFTEVO_SEEDS:-$SOFTEVO_SEED_FIRST-$(( SOFTEVO_SEED_FIRST + SOFTEVO_REPS - 1 ))}
  # The aggregation reads the archives of the array tasks these runs stand for
  # (t = REPS e + seed - SEED_FIRST).
  tasks=()
  IFS=, read -r -a items <<<"$SOFTEVO_SEEDS"
  for (( e = 0; e < ${#EXPS[@]}; e++ )); do
    for item in "${items[@]}"; do
      for (( s = ${item%-*}; s <= ${item#*-}; s++ )); do
        tasks+=($(( e * SOFTEVO_REPS + s - SOFTEVO_SEED_FIRST )))
      done
    done
  done
  export SOFTEVO_ARRAY=$(IFS=,; echo "${tasks[*]}")
  per_node=()
  [ -n "${SOFTEVO_TASKS_PER_NODE:-}" ] && per_node=(--ntasks-per-node="$SOFTEVO_TASKS_PER_NODE")
  JOB=$(sbatch --parsable "${SITE_ARGS[@]}" --nodes="$SOFTEVO_NODES" "${per_node[@]}" \
    --time="${SOFTEVO_TIME:-7-00:00:00}" --chdir="$SOFTEVO_RUNS" \
    --output="$SOFTEVO_RUNS/softevo-packed-%j.out" "$ROOT/slurm/packed.sbatch")
  JOB=${JOB%%;*}
  AGG=$(sbatch --parsable "${SITE_ARGS[@]}" --dependency="afterok:$JOB" --chdir="$SOFTEVO_RUNS" \
    --output="$SOFTEVO_RUNS/softevo-grid-aggregate-%j.out" "$ROOT/slurm/aggregate.sbatch")
  echo "$JOB ${AGG%%;*}"
  exit 0
fi
ARRAY=$(sbatch --parsable "${SITE_ARGS[@]}" --array="$SOFTEVO_ARRAY" --ntasks="${SOFTEVO_NTASKS:-5}" \
  --time="${SOFTEVO_TIME:-7-00:00:00}" --chdir="$SOFTEVO_RUNS" \
  --output="$SOFTEVO_RUNS/softevo-grid-%A_%a.out" "$ROOT/slurm/grid.sbatch")
ARRAY=${ARRAY%%;*}
AGG=$(sbatch --parsable "${SITE_ARGS[@]}" --dependency="afterok:$ARRAY" --chdir="$SOFTEVO_RUNS" \
  --output="$SOFTEVO_RUNS/softevo-grid-aggregate-%j.out" "$ROOT/slurm/aggregate.sbatch")
AGG=${AGG%%;*}
echo "$ARRAY $AGG"
