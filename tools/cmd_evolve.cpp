// `softevo evolve`: the whole evolution in this process, its work units evaluated by worker
// threads (master/thread_executor.hpp) instead of MPI ranks. The options, config resolution,
// archive, checkpoints, --resume and signals are softevo-mpi's (tools/run_command.hpp,
// master/run_driver.hpp): `softevo evolve --workers W` writes the archive that
// `mpirun -np W+1 softevo-mpi` writes, bit for bit (docs/archive.md, "One process").
//
// Exit codes as softevo-mpi: 0 complete (or nothing to resume), 2 usage / config / start-up
// error, 75 stopped by SIGTERM/SIGINT/SIGUSR1 after a checkpoint (rerun with --resume), 1 an
// unrecoverable error during the run (the archive keeps its last consistent generation).
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "common/config.hpp"
#include "master/run_driver.hpp"
#include "master/signals.hpp"
#include "master/thread_executor.hpp"
#include "tools/commands.hpp"
#include "tools/run_command.hpp"

namespace softevo::cli {
namespace {

int run_evolve(RunCommandOptions& o, int workers) {
  if (workers <= 0) workers = master::available_cores();
  o.program = "softevo evolve";
  master::install_stop_handlers();
  std::vector<master::PreparedRun> runs;
  try {
    runs = prepare_runs(o, workers + 1);
  } catch (const ConfigError& e) {
    std::fprintf(stderr, "softevo: error: config: %s\n", e.what());
    return kExitUsage;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "softevo: error: %s\n", e.what());
    return kExitUsage;
  }
  std::vector<std::unique_ptr<tasks::Task>> tasks;
  std::vector<master::PreparedRun*> run_pointers;
  for (master::PreparedRun& r : runs) {
    tasks.push_back(tasks::make_task(r.config));
    run_pointers.push_back(&r);
  }
  const worker::EvaluateOptions options = abandoning_on_stop({});
  master::DriverOptions driver;
  driver.program = "softevo evolve";
  driver.workers = std::to_string(workers) + (workers == 1 ? " worker thread" : " worker threads");
  driver.config_path = config_paths_text(o);
  driver.terse = o.quiet;
  driver.verbose = o.verbose;
  driver.progress = master::parse_progress_mode(o.progress).value();  // checked by IsMember
  try {
    master::ThreadExecutor executor(workers, [&](const EvalRequest& request) {
      return evaluate_unit(runs, tasks, request, options);
    });
    return master::drive_runs(run_pointers, executor, driver, [] {
      const std::string signal = master::stop_signal_name();
      return signal.empty() ? std::string("a stop request") : "received " + signal;
    });
  } catch (const std::exception& e) {
    std::fprintf(stderr, "softevo: error: %s\n", e.what());
    return 1;
  }
}

}  // namespace

void register_evolve(CLI::App& app, int& exit_code) {
  auto options = std::make_shared<RunCommandOptions>();
  auto workers = std::make_shared<int>(0);
  CLI::App* sub = app.add_subcommand(
      "evolve",
      "evolve robots in this process on all its cores (worker threads; the options, archive and "
      "results of softevo-mpi, which runs the same on a cluster)");
  add_run_options(*sub, *options);
  sub->add_option("-j,--workers", *workers,
                  "worker threads (default: the cores this process may run on, " +
                      std::to_string(master::available_cores()) + " here)")
      ->check(CLI::Range(1, master::kMaxWorkerThreads));
  sub->callback([&exit_code, options, workers] { exit_code = run_evolve(*options, *workers); });
}

}  // namespace softevo::cli
