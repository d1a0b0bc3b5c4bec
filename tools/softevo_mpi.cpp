#include "tools/softevo_mpi.hpp"

#include <CLI/CLI.hpp>
#include <csignal>
#include <cstdio>
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
#include "tools/run_command.hpp"
#include "worker/worker_loop.hpp"

namespace softevo {
namespace {

[[noreturn]] void abort_run(const mpi::Communicator& comm, const std::string& message) {
  std::fprintf(stderr, "softevo-mpi: error: rank %d: %s\n", comm.rank(), message.c_str());
  std::fflush(stderr);
  comm.abort(1);
}

// The stop signal this rank has received, for the worker loop ("" while there is none). Only a
// stop-now counts: on SIGUSR1 the workers finish their units (the master ends the generation).
std::string stop_now_signal() {
  if (master::stop_requested() != master::StopRequest::now) return "";
  const std::string name = master::stop_signal_name();
  return name.empty() ? "a stop request" : name;
}

}  // namespace

int softevo_mpi_main(int argc, char** argv, MPI_Comm parent, const MpiMainHooks& hooks) {
  watch_launcher();
  const mpi::Communicator comm(parent);

  RunCommandOptions o;
  CLI::App app{"softevo-mpi: distributed co-evolution of soft robot bodies and brains"};
  add_run_options(app, o);
  app.set_version_flag("--version",
                       std::string("softevo-mpi ") + kVersion + " (commit " + git_commit() + ")");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // Only rank 0 prints help or the usage error; every rank exits with the same code.
    if (e.get_exit_code() == 0) return comm.rank() == 0 ? app.exit(e) : 0;
    if (comm.rank() == 0)
      std::fprintf(stderr,
                   "softevo-mpi: error: %s\n%srun with --help for more information (softevo-mpi "
                   "--help)\n",
                   e.what(), option_suggestions(app).c_str());
    return 2;
  }
  master::install_stop_handlers();
  // A rank whose launcher died writes its output into a pipe nobody reads: that must fail with
  // EPIPE, not kill the rank before it has marked the archive and left (launcher_watch.hpp).
  std::signal(SIGPIPE, SIG_IGN);

  // Rank 0 resolves the configs and prepares the runs; status 0 = ok, else text is the message.
  std::int32_t status = 0;
  std::string text;
  std::vector<master::PreparedRun> runs;
  if (comm.rank() == 0) {
    try {
      runs = prepare_runs(o, comm.size());
    } catch (const ConfigError& e) {
      status = 1;
      text = std::string("config: ") + e.what();
    } catch (const std::exception& e) {
      status = 1;
      text = e.what();
    }
  }
  std::vector<std::string> config_texts;
  try {
    status = comm.broadcast(status);
    text = comm.broadcast(text);
    if (status == 0) {
      const auto count = comm.broadcast(static_cast<std::int32_t>(runs.size()));
      for (std::int32_t i = 0; i < count; ++i)
        config_texts.push_back(comm.broadcast(comm.rank() == 0 ? runs[i].config_text : ""));
    }
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
      std::vector<Config> configs;
      for (const std::string& t : config_texts)
        configs.push_back(parse_config(t, "config from rank 0"));
      const worker::WorkerOutcome outcome =
          configs.size() == 1
              ? worker::run_worker_loop(comm, configs.front(), config_hash(configs.front()),
                                        hooks.unit_options, stop_now_signal)
              : worker::run_worker_loop(comm, configs, hooks.unit_options, stop_now_signal);
      return outcome.left_on_its_own ? master::kExitRequeue : outcome.exit_code;
    }
    master::MasterOptions mo;
    mo.config_path = config_paths_text(o);
    mo.quiet = hooks.quiet;
    mo.terse = o.quiet;
    mo.verbose = o.verbose;
    mo.progress = master::parse_progress_mode(o.progress).value();  // checked by IsMember
    for (const std::string& p : processes) mo.processes.push_back(master::parse_rank_process(p));
    std::vector<std::unique_ptr<tasks::Task>> tasks;
    std::vector<master::PreparedRun*> run_pointers;
    for (master::PreparedRun& r : runs) {
      tasks.push_back(tasks::make_task(r.config));
      run_pointers.push_back(&r);
    }
    const worker::EvaluateOptions alone = abandoning_on_stop(hooks.unit_options);
    mo.evaluate_alone = [&runs, &alone, &tasks](const EvalRequest& request) {
      return evaluate_unit(runs, tasks, request, alone);
    };
    return master::run_master(comm, run_pointers, mo);
  } catch (const std::exception& e) {
    abort_run(comm, e.what());
  }
}

}  // namespace softevo
