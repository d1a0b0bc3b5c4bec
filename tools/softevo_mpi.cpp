#include "tools/softevo_mpi.hpp"

#include <CLI/CLI.hpp>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <unistd.h>

#include "common/config.hpp"
#include "common/launcher_watch.hpp"
#include "common/version.hpp"
#include "master/mpi_driver.hpp"
#include "master/run.hpp"
#include "master/signals.hpp"
#include "worker/worker_loop.hpp"

#ifndef SOFTEVO_DEFAULT_SOURCE_DIR
#define SOFTEVO_DEFAULT_SOURCE_DIR "."
#endif

namespace softevo {
namespace {

namespace fs = std::filesystem;

constexpr const char* kDefaultConfig = "configs/quickstart.toml";

struct Options {
  std::string config_path = kDefaultConfig;
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
};

[[noreturn]] void abort_run(const mpi::Communicator& comm, const std::string& message) {
  std::fprintf(stderr, "softevo-mpi: error: rank %d: %s\n", comm.rank(), message.c_str());
  std::fflush(stderr);
  comm.abort(1);
}

std::string resolve_config_path(const std::string& path) {
  if (path != kDefaultConfig || fs::exists(path)) return path;
  const std::string baked = std::string(SOFTEVO_DEFAULT_SOURCE_DIR) + "/" + kDefaultConfig;
  return fs::exists(baked) ? baked : path;
}

// The one archive naming scheme (configs' comments, slurm/grid.sbatch, the README):
// runs/<config name>-<seed, at least 2 digits>.h5.
std::string default_out_path(const std::string& config_path, std::int64_t seed) {
  char seed_text[32];
  std::snprintf(seed_text, sizeof seed_text, "%02lld", static_cast<long long>(seed));
  return "runs/" + fs::path(config_path).stem().string() + "-" + seed_text + ".h5";
}

// Rank 0's start-up: the resolved config and the prepared run. Throws ConfigError, StartupError.
master::PreparedRun prepare(Options& o, int ranks) {
  o.config_path = resolve_config_path(o.config_path);
  std::vector<std::string> overrides = o.overrides;
  if (o.seed >= 0) overrides.push_back("run.seed=" + std::to_string(o.seed));
  if (o.generations >= 0) overrides.push_back("run.generations=" + std::to_string(o.generations));
  if (o.population >= 0) overrides.push_back("neat.pop_size=" + std::to_string(o.population));
  const Config config = load_config(o.config_path, overrides);
  master::RunOptions ro;
  ro.out_path = o.out_path.empty() ? default_out_path(o.config_path, config.run.seed) : o.out_path;
  // The archive's folder is created, whether the default runs/ or the one --out names (the
  // output checks then say why, should that fail).
  const fs::path parent = fs::path(ro.out_path).parent_path();
  if (!parent.empty()) {
    std::error_code ec;
    fs::create_directories(parent, ec);
  }
  ro.resume = o.resume;
  ro.overwrite = o.overwrite;
  return master::prepare_run(config, ro, ranks);
}

// The stop signal this rank has received, for the worker loop ("" while there is none). Only a
// stop-now counts: on SIGUSR1 the workers finish their units (the master ends the generation).
std::string stop_now_signal() {
  if (master::stop_requested() != master::StopRequest::now) return "";
  const std::string name = master::stop_signal_name();
  return name.empty() ? "a stop request" : name;
}

// Evaluation options of rank 0 evaluating alone: an evaluation is abandoned on a stop-now or
// when the launcher died (which also stops the run loop).
worker::EvaluateOptions abandoning_on_stop(worker::EvaluateOptions options) {
  options.abandon = [earlier = options.abandon] {
    if (launcher_gone()) master::request_stop(master::StopRequest::now);
    return (earlier && earlier()) || master::stop_requested() == master::StopRequest::now;
  };
  return options;
}

}  // namespace

int softevo_mpi_main(int argc, char** argv, MPI_Comm parent, const MpiMainHooks& hooks) {
  watch_launcher();
  const mpi::Communicator comm(parent);

  Options o;
  CLI::App app{"softevo-mpi: distributed co-evolution of soft robot bodies and brains"};
  app.add_option("--config", o.config_path, "TOML config file")->capture_default_str();
  app.add_option("--seed", o.seed, "run seed (sets run.seed)");
  app.set_version_flag("--version",
                       std::string("softevo-mpi ") + kVersion + " (commit " + kGitCommit + ")");
  app.add_option("-o,--output,--out", o.out_path,
                 "run archive (default runs/<config>-<seed, 2 digits>.h5; its folder is created)");
  app.add_option("--generations", o.generations, "generations to evaluate (run.generations)");
  app.add_option("--population", o.population, "population size (neat.pop_size)");
  app.add_option("--set", o.overrides, "override a key: section.key=value (repeatable)");
  app.add_flag("--resume", o.resume,
               "continue the archive from its newest checkpoint (a new run if it does not exist)");
  app.add_flag("--overwrite", o.overwrite, "replace an existing archive");
  app.add_option("--progress", o.progress,
                 "the live line within a generation: auto (a terminal, or an interactive "
                 "mpirun/srun), always or never")
      ->check(CLI::IsMember({"auto", "always", "never"}))
      ->capture_default_str();
  auto* quiet = app.add_flag("-q,--quiet", o.quiet, "warnings and errors only");
  app.add_flag("-v,--verbose", o.verbose, "print the resolved config at the start too")
      ->excludes(quiet);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // Only rank 0 prints help or the usage error; every rank exits with the same code.
    if (e.get_exit_code() == 0) return comm.rank() == 0 ? app.exit(e) : 0;
    if (comm.rank() == 0)
      std::fprintf(stderr,
                   "softevo-mpi: error: %s\nrun with --help for more information (softevo-mpi "
                   "--help)\n",
                   e.what());
    return 2;
  }
  master::install_stop_handlers();
  // A rank whose launcher died writes its output into a pipe nobody reads: that must fail with
  // EPIPE, not kill the rank before it has marked the archive and left (launcher_watch.hpp).
  std::signal(SIGPIPE, SIG_IGN);

  // Rank 0 resolves the config and prepares the run; status 0 = ok, else text is the message.
  std::int32_t status = 0;
  std::string text;
  std::optional<master::PreparedRun> run;
  if (comm.rank() == 0) {
    try {
      run.emplace(prepare(o, comm.size()));
      text = run->config_text;
    } catch (const ConfigError& e) {
      status = 1;
      text = std::string("config: ") + e.what();
    } catch (const std::exception& e) {
      status = 1;
      text = e.what();
    }
  }
  try {
    status = comm.broadcast(status);
    text = comm.broadcast(text);
  } catch (const std::exception& e) {
    abort_run(comm, e.what());
  }
  if (status != 0) {
    if (comm.rank() == 0) std::fprintf(stderr, "softevo-mpi: error: %s\n", text.c_str());
    return 2;
  }

  try {
    // Every rank's process, so the master can name a rank that died (master/mpi_driver.hpp).
    const std::vector<std::string> processes =
        comm.gather(master::format_rank_process(::getpid(), master::host_name()));
    if (comm.rank() != 0) {
      const Config config = parse_config(text, "config from rank 0");
      const worker::WorkerOutcome outcome = worker::run_worker_loop(
          comm, config, config_hash(config), hooks.unit_options, stop_now_signal);
      return outcome.left_on_its_own ? master::kExitRequeue : outcome.exit_code;
    }
    master::PreparedRun& r = *run;
    master::MasterOptions mo;
    mo.config_path = o.config_path;
    mo.quiet = hooks.quiet;
    mo.terse = o.quiet;
    mo.verbose = o.verbose;
    mo.progress = master::parse_progress_mode(o.progress).value();  // checked by IsMember
    for (const std::string& p : processes) mo.processes.push_back(master::parse_rank_process(p));
    const std::unique_ptr<tasks::Task> task = tasks::make_task(r.config);
    const worker::EvaluateOptions alone = abandoning_on_stop(hooks.unit_options);
    mo.evaluate_alone = [&r, &alone, &task](const EvalRequest& request) {
      return worker::evaluate(r.config, *task, r.config_hash, request, alone);
    };
    return master::run_master(comm, r, mo);
  } catch (const std::exception& e) {
    abort_run(comm, e.what());
  }
}

}  // namespace softevo
