#include "master/mpi_driver.hpp"

#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "common/config.hpp"
#include "common/version.hpp"
#include "common/wire.hpp"
#include "master/signals.hpp"

namespace softevo::master {
namespace {

double cpu_seconds() {
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  return static_cast<double>(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
}

// Self-scheduling over ranks 1..N-1: every idle worker gets the next unit; each result frees its
// worker for the next one. Waiting = poll + sleep back-off (never a spinning core).
class MpiExecutor : public UnitExecutor {
 public:
  explicit MpiExecutor(const mpi::Communicator& comm) : comm_(comm) {
    for (int r = comm_.size() - 1; r >= 1; --r) idle_.push_back(r);
  }
  int ranks() const override { return comm_.size(); }

  bool evaluate(GenerationScheduler& scheduler,
                const std::function<EvalRequest(const WorkUnit&)>& make_request,
                ProgressReporter& progress) override {
    mpi::PollBackoff backoff;
    bool stopping = false;
    for (;;) {
      if (!stopping && stop_requested() == StopRequest::now) stopping = true;
      while (!stopping && !idle_.empty() && scheduler.has_next()) {
        const WorkUnit unit = *scheduler.next();
        const int dest = idle_.back();
        idle_.pop_back();
        comm_.send(dest, mpi::Tag::request, encode_eval_request(make_request(unit)));
        ++in_flight_;
      }
      if (in_flight_ == 0 && (stopping || !scheduler.has_next())) return !stopping;
      const std::optional<mpi::Envelope> pending = comm_.poll();
      if (!pending) {
        backoff.sleep();
        continue;
      }
      backoff.reset();
      const mpi::Message message = comm_.receive(*pending);
      if (message.tag == mpi::Tag::error)
        throw RunError(std::string(message.bytes.begin(), message.bytes.end()));
      if (message.tag != mpi::Tag::result)
        throw RunError("master: unexpected message with tag " +
                       std::string(mpi::tag_name(message.tag)) + " from rank " +
                       std::to_string(message.source));
      EvalResult result = decode_eval_result(message.bytes);
      result.worker_rank = message.source;
      --in_flight_;
      idle_.push_back(message.source);
      if (!stopping) {  // after a stop-now request the partial generation is discarded
        scheduler.complete(result);
        progress.unit_done(scheduler.units_done(), scheduler.units_total());
      }
    }
  }

 private:
  const mpi::Communicator& comm_;
  std::vector<int> idle_;
  int in_flight_ = 0;
};

void print_header(const PreparedRun& r, const std::string& config_path, int ranks) {
  std::printf("softevo-mpi %s (commit %s), %d rank%s\n", kVersion, kGitCommit, ranks,
              ranks == 1 ? "" : "s");
  std::printf("# config %s (hash %s)\n%s", config_path.c_str(), hash_hex(r.config_hash).c_str(),
              r.config_text.c_str());
  std::printf("# archive %s (%s)\n", r.options.out_path.c_str(),
              r.already_complete ? "complete: nothing to do"
              : r.resumed
                  ? ("resuming at generation " + std::to_string(r.info.generations_done)).c_str()
                  : "new run");
  std::fflush(stdout);
}

void print_summary(const PreparedRun& r, RunOutcome outcome, int code, double wall, double cpu) {
  if (outcome == RunOutcome::interrupted)
    std::printf(
        "# interrupted by a signal after generation %lld; archive %s is consistent; "
        "exit %d (rerun with --resume)\n",
        static_cast<long long>(r.info.generations_done) - 1, r.options.out_path.c_str(), code);
  else if (outcome == RunOutcome::complete)
    std::printf(
        "# complete: %lld generations, archive %s; master wall %.1f s, master CPU %.2f s "
        "(%.1f%%)\n",
        static_cast<long long>(r.info.generations_done), r.options.out_path.c_str(), wall, cpu,
        wall > 0 ? 100.0 * cpu / wall : 0.0);
  std::fflush(stdout);
}

// Tells every worker to return `exit_code`: the one way a worker learns it (mpi/protocol.hpp).
void stop_workers(const mpi::Communicator& comm, int exit_code) {
  const std::vector<std::uint8_t> bytes = encode_shutdown(exit_code);
  for (int r = 1; r < comm.size(); ++r) comm.send(r, mpi::Tag::stop, bytes);
}

int exit_code_of(RunOutcome outcome) {
  return outcome == RunOutcome::interrupted ? kExitRequeue : 0;
}

}  // namespace

int run_master(const mpi::Communicator& comm, PreparedRun& run, const MasterOptions& options) {
  if (!options.quiet) print_header(run, options.config_path, comm.size());
  ProgressReporter progress = options.quiet ? ProgressReporter::silent()
                                            : ProgressReporter::console(run.config.run.generations);
  const auto t0 = std::chrono::steady_clock::now();
  const double cpu0 = cpu_seconds();
  RunOutcome outcome = RunOutcome::complete;
  if (comm.size() == 1) {
    LocalExecutor local(options.evaluate_alone);
    outcome = execute_run(run, local, progress);
  } else {
    MpiExecutor executor(comm);
    outcome = execute_run(run, executor, progress);
  }
  const int code = exit_code_of(outcome);
  if (!options.quiet) {
    const double wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    print_summary(run, outcome, code, wall, cpu_seconds() - cpu0);
  }
  // Last: a worker exits as soon as it has the code, and mpirun may then end the whole job.
  stop_workers(comm, code);
  return code;
}

}  // namespace softevo::master
