// The command line of a run, shared by `softevo-mpi` (MPI ranks) and `softevo evolve` (worker
// threads): the same options, the same config resolution (--config, --set and the shorthands),
// the same archive names and the same start-up checks, so both programs start the same run from
// the same words. MPI-free.
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <string>
#include <vector>

#include "common/eval_types.hpp"
#include "master/run.hpp"
#include "worker/evaluate.hpp"

namespace softevo {

// A run without --config runs this file: from the working directory, else from the source tree
// the program was built from.
inline constexpr const char* kDefaultRunConfig = "configs/quickstart.toml";

struct RunCommandOptions {
  std::vector<std::string> config_paths;  // empty = kDefaultRunConfig; several only with --seeds
  std::vector<std::string> overrides;
  std::int64_t seed = -1;
  std::int64_t generations = -1;
  std::int64_t population = -1;
  std::string out_path;
  bool resume = false;
  bool overwrite = false;
  std::string progress = "auto";
  bool quiet = false;
  bool verbose = false;
  bool no_reuse = false;
  bool fixed_order = false;
  std::string seeds;          // "1-10", "1,3,5-7": several runs in one job (one per config x seed)
  std::string out_dir;        // their archives: <out-dir>/<config name>-<seed, 2 digits>.h5
  bool from_archive = false;  // set by prepare_runs: --resume without --config took /config
  std::string program = "softevo-mpi";  // recorded in the archive (io::RunInfo::program)
};

// "did you mean" lines for the mistyped options of a failed parse of `app` (its subcommands
// included): "unknown option --jsno, did you mean --json?\n" per option that is close to one
// the (sub)command has; "" when none is.
std::string option_suggestions(const CLI::App& app);

// Adds the run options to `app` (softevo-mpi's app, or the `evolve` subcommand).
void add_run_options(CLI::App& app, RunCommandOptions& o);

// "1-10", "2,5", "1-3,8" -> the seeds in order; throws ConfigError naming the option.
std::vector<std::int64_t> parse_seeds(const std::string& spec);

// The start-up of the runs: one, or one per config x seed with --seeds. Resolves the config
// paths in `o`; --resume of an existing --out without --config takes the archive's config
// (with the overrides given now) and sets o.from_archive. Throws ConfigError, master::StartupError;
// a failure releases the runs prepared before it and removes the lock files (and the --out-dir)
// it created. With --seeds the descriptors for every run's lock are checked (and the soft limit
// raised) before the first lock is taken.
std::vector<master::PreparedRun> prepare_runs(RunCommandOptions& o, int ranks);

// "configs/a.toml" or "configs/a.toml, configs/b.toml": the header's config.
std::string config_paths_text(const RunCommandOptions& o);

// The evaluation of a work unit of any of `runs` (the one whose config hash the request names;
// a hash of none is the first run's mismatch). Safe to call from several threads at once. The
// runs must outlive it.
EvalResult evaluate_unit(const std::vector<master::PreparedRun>& runs,
                         const std::vector<std::unique_ptr<tasks::Task>>& tasks,
                         const EvalRequest& request, const worker::EvaluateOptions& options);

// `options` with an abandon request that also holds on a stop-now (SIGTERM/SIGINT, or the
// launcher died): an evaluation in flight stops at its next control frame (its result is
// dropped, never archived).
worker::EvaluateOptions abandoning_on_stop(worker::EvaluateOptions options);

}  // namespace softevo
