# Site settings of the Slurm scripts, sourced by submit.sh, grid.sbatch and aggregate.sbatch
# (documented in docs/cluster.md). Each setting is an environment variable; a site file (shell
# assignments, default slurm/site.env, or the file $SOFTEVO_SITE names) sets those not already
# set in the environment:
#   SOFTEVO_PARTITION  sbatch --partition        (default: the cluster's default)
#   SOFTEVO_ACCOUNT    sbatch --account          (default: the user's default)
#   SOFTEVO_MEM        sbatch --mem-per-cpu, e.g. 2G (default: the cluster's default)
#   SOFTEVO_MODULES    modules to load before a run, e.g. "gcc/12 openmpi/4.1 hdf5/1.10"
#   SOFTEVO_LAUNCHER   mpirun (default) or srun
#   SOFTEVO_LAUNCHER_ARGS  extra launcher arguments, e.g. "--mpi=pmix" for srun
site_file=${SOFTEVO_SITE:-$(dirname "${BASH_SOURCE[0]}")/site.env}
if [ -n "${SOFTEVO_SITE:-}" ] && [ ! -r "$site_file" ]; then
  echo "softevo: error: SOFTEVO_SITE=$site_file: no such readable file" >&2
  exit 2
fi
if [ -r "$site_file" ]; then
  # The environment wins over the file: a one-off SOFTEVO_PARTITION=debug slurm/submit.sh works.
  while IFS='=' read -r key value; do
    case "$key" in
      SOFTEVO_PARTITION | SOFTEVO_ACCOUNT | SOFTEVO_MEM | SOFTEVO_MODULES | SOFTEVO_LAUNCHER | \
        SOFTEVO_LAUNCHER_ARGS)
        value=${value%\"}
        value=${value#\"}
        [ -n "${!key:-}" ] || export "$key=$value"
        ;;
      '' | \#*) ;;
      *)
        echo "softevo: error: $site_file: unknown setting '$key' (see docs/cluster.md)" >&2
        exit 2
        ;;
    esac
  done <"$site_file"
fi
export SOFTEVO_LAUNCHER=${SOFTEVO_LAUNCHER:-mpirun}
case "$SOFTEVO_LAUNCHER" in
  mpirun | srun) ;;
  *)
    echo "softevo: error: SOFTEVO_LAUNCHER=$SOFTEVO_LAUNCHER: expected mpirun or srun" >&2
    exit 2
    ;;
esac

# softevo_load_modules: `module load $SOFTEVO_MODULES` when modules are asked for.
softevo_load_modules() {
  [ -n "${SOFTEVO_MODULES:-}" ] || return 0
  if ! command -v module >/dev/null 2>&1; then
    echo "softevo: error: SOFTEVO_MODULES is set but this node has no 'module' command" >&2
    exit 2
  fi
  # shellcheck disable=SC2086  # a word list of module names
  module load $SOFTEVO_MODULES
}
