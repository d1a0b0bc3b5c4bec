#include "master/run_driver.hpp"

#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "common/config.hpp"
#include "common/launcher_watch.hpp"
#include "common/version.hpp"
#include "master/run_state.hpp"
#include "master/signals.hpp"

namespace softevo::master {
namespace {

// CPU time of the calling thread, the master's (the worker threads of `softevo evolve` not
// counted: "master CPU" means the same as on softevo-mpi's rank 0).
double cpu_seconds() {
  rusage ru{};
  getrusage(RUSAGE_THREAD, &ru);
  return static_cast<double>(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
}

void print_header(const PreparedRun& r, const DriverOptions& o) {
  std::printf("%s %s (commit %s), %s\n", o.program.c_str(), kVersion, git_commit(),
              o.workers.c_str());
  // The resolved config is in the archive (/config, `softevo info`); -v prints it here too.
  std::printf("# config %s (config hash %s, experiment %s hash %s)%s\n", o.config_path.c_str(),
              hash_hex(r.config_hash).c_str(), r.info.experiment.c_str(),
              r.info.experiment_hash.c_str(),
              o.verbose ? "" : "; -v or `softevo info ARCHIVE` shows every resolved key");
  if (o.verbose) std::printf("%s", r.config_text.c_str());
  std::printf(
      "# archive %s (%s)\n", r.options.out_path.c_str(),
      r.already_complete ? (r.info.state == io::RunState::complete ? "complete: nothing to do"
                                                                   : "every generation archived: "
                                                                     "marking it complete")
      : r.resumed ? ("resuming at generation " + std::to_string(r.info.generations_done)).c_str()
                  : "new run");
  std::fflush(stdout);
  if (r.previous_run) {  // on stderr too: a requeued job's user reads that log first
    std::fprintf(stderr, "%s: %s: %s\n", o.program.c_str(), r.options.out_path.c_str(),
                 r.previous_run->c_str());
    std::fflush(stderr);
  }
}

// Several runs in one job: one line per run instead of the config (each archive holds its own).
void print_packed_header(const std::vector<PreparedRun*>& runs, const DriverOptions& o) {
  std::printf("%s %s (commit %s), %s, %zu runs in one pool (%s)\n", o.program.c_str(), kVersion,
              git_commit(), o.workers.c_str(), runs.size(), o.config_path.c_str());
  for (const PreparedRun* r : runs) {
    const std::string what =
        r->already_complete ? "every generation archived"
        : r->resumed        ? "resuming at generation " + std::to_string(r->info.generations_done)
                            : std::string("new run");
    std::printf("# archive %s (seed %lld, config hash %s, experiment %s hash %s): %s\n",
                r->options.out_path.c_str(), static_cast<long long>(r->config.run.seed),
                hash_hex(r->config_hash).c_str(), r->info.experiment.c_str(),
                r->info.experiment_hash.c_str(), what.c_str());
    if (r->previous_run)
      std::fprintf(stderr, "%s: %s: %s\n", o.program.c_str(), r->options.out_path.c_str(),
                   r->previous_run->c_str());
  }
  std::fflush(stdout);
  std::fflush(stderr);
}

void print_summary(const PreparedRun& r, RunOutcome outcome, const std::string& stop_reason,
                   int code, double wall, double cpu) {
  if (outcome == RunOutcome::interrupted)
    std::printf("# interrupted: %s; exit %d: %s (%s is consistent and marked interrupted)\n",
                stop_reason.c_str(), code, resume_note(r.info.generations_done).c_str(),
                r.options.out_path.c_str());
  else if (outcome == RunOutcome::complete)
    std::printf(
        "# complete: %lld generations, archive %s; master wall %.1f s, master CPU %.2f s "
        "(%.1f%%)\n",
        static_cast<long long>(r.info.generations_done), r.options.out_path.c_str(), wall, cpu,
        wall > 0 ? 100.0 * cpu / wall : 0.0);
  std::fflush(stdout);
}

}  // namespace

std::string no_robot_ok(const PreparedRun& run) {
  const auto& statuses = run.statuses_this_start;
  std::int64_t evaluated = 0;
  for (std::int64_t n : statuses) evaluated += n;
  if (evaluated == 0 || statuses[static_cast<std::size_t>(EvalStatus::ok)] > 0) return "";
  return run.options.out_path + ": no robot of the " + std::to_string(evaluated) +
         " evaluated was ok (" + status_counts_text(statuses) +
         "): the archive is complete, but the setup cannot work as configured (check the "
         "physics and pneumatics keys)";
}

std::string rank0_stop_cause() {
  if (launcher_gone()) return "rank 0: " + launcher_gone_reason();
  const std::string signal = stop_signal_name();
  return signal.empty() ? "rank 0: a stop request" : "rank 0 received " + signal;
}

int drive_runs(const std::vector<PreparedRun*>& runs, UnitExecutor& executor,
               const DriverOptions& options, const std::function<std::string()>& stop_reason) {
  const bool packed = runs.size() > 1;
  const bool chatty = !options.quiet && !options.terse;
  if (chatty) {
    if (packed)
      print_packed_header(runs, options);
    else
      print_header(*runs.front(), options);
  }
  std::vector<ProgressReporter> reporters;
  for (const PreparedRun* run : runs) {
    if (options.quiet)
      reporters.push_back(ProgressReporter::silent());
    else if (packed)  // no live line: the runs' lines interleave, each names its archive
      reporters.push_back(ProgressReporter(options.terse ? nullptr : stdout, nullptr, stderr,
                                           run->config.run.generations,
                                           run->options.out_path + ": "));
    else
      reporters.push_back(
          ProgressReporter::console(run->config.run.generations, options.progress, options.terse));
  }
  std::vector<ProgressReporter*> progress;
  for (ProgressReporter& r : reporters) {
    r.set_program(options.program);
    progress.push_back(&r);
  }
  const auto t0 = std::chrono::steady_clock::now();
  const double cpu0 = cpu_seconds();
  std::vector<RunOutcome> outcomes;
  try {
    outcomes = execute_runs(runs, executor, progress);
  } catch (const RunError& e) {
    // The caller ends the job with this message: say where --resume continues.
    std::string where;
    for (const PreparedRun* run : runs)
      where += (where.empty() ? "" : "; ") + run->options.out_path + ": " +
               resume_note(run->info.generations_done);
    throw RunError(std::string(e.what()) + " (" + where + ")");
  }
  RunOutcome overall = RunOutcome::complete;
  for (RunOutcome o : outcomes)
    if (o == RunOutcome::interrupted) overall = o;
  std::string reason = stop_reason ? stop_reason() : "";
  if (reason.empty() && overall == RunOutcome::interrupted) reason = rank0_stop_cause();
  int code = overall == RunOutcome::interrupted ? kExitRequeue : 0;
  for (std::size_t r = 0; r < runs.size(); ++r) {
    if (outcomes[r] != RunOutcome::complete) continue;
    const std::string none_ok = no_robot_ok(*runs[r]);
    if (none_ok.empty()) continue;
    std::fprintf(stderr, "%s: error: %s\n", options.program.c_str(), none_ok.c_str());
    std::fflush(stderr);
    if (code == 0) code = kExitNoRobotOk;
  }
  // -q keeps the one line that says how to continue an interrupted run.
  if (chatty || (!options.quiet && overall == RunOutcome::interrupted)) {
    const double wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    for (std::size_t r = 0; r < runs.size(); ++r)
      print_summary(*runs[r], outcomes[r], reason, code, wall, cpu_seconds() - cpu0);
  }
  return code;
}

}  // namespace softevo::master
