// Rank 0 of softevo-mpi: the generation loop (master/run.hpp) with an executor that
// self-schedules work units over ranks 1..N-1 (or evaluates by itself with one rank), the
// console report, and the end of the workers. The program that joins this with the worker loop
// is tools/softevo_mpi.cpp.
//
// Exit code: 0 complete (or nothing to resume), 75 (kExitRequeue) stopped after a checkpoint:
// by SIGTERM/SIGINT/SIGUSR1, by a worker that left (its own stop signal, its launcher died),
// or because rank 0's launcher died. run_master sends it to every worker in the stop message
// (mpi/protocol.hpp), the one way a worker learns it.
//
// A stop-now (SIGTERM, a worker's Tag::leaving, the launcher gone) never waits for the units in
// flight: mpirun kills every rank 1 s after its SIGTERM (Open MPI's odls_base_sigkill_timeout),
// and an evaluation may take minutes. The master hands out nothing more, waits at most
// kRollCallSeconds for the other workers' Tag::leaving (a worker that neither leaves nor
// answers, or whose process on this host is gone, is named as lost), prints one line saying
// why it stops and where --resume continues, and only then records the state "interrupted".
#pragma once

#include <string>
#include <vector>

#include "master/progress.hpp"
#include "master/run.hpp"
#include "mpi/communicator.hpp"

namespace softevo::master {

// How long a stopping master waits for the workers' Tag::leaving [s]: long enough for every rank
// that got mpirun's SIGTERM to answer (they poll every <= 10 ms), short next to mpirun's 1 s.
inline constexpr double kRollCallSeconds = 0.3;

// The process of one rank, as gathered at start-up (pid and host): a rank whose process on the
// master's host is gone is named as lost.
struct RankProcess {
  long pid = 0;
  std::string host;
};
// "4242 node17" -> {4242, "node17"}; {0, ""} for anything else.
RankProcess parse_rank_process(const std::string& text);
std::string format_rank_process(long pid, const std::string& host);

struct MasterOptions {
  std::string config_path;                   // shown in the console header
  LocalExecutor::EvaluateFn evaluate_alone;  // evaluates a unit when there is no worker rank
  bool quiet = false;                        // no console output (tests)
  // -q: warnings and errors only; -v: the resolved config in the header too.
  bool terse = false;
  bool verbose = false;
  ProgressMode progress = ProgressMode::automatic;  // --progress: the live line
  std::vector<RankProcess> processes;               // by rank (empty: unknown)
};

// Runs `run` (prepared by prepare_run) on rank 0 of `comm` and returns the exit code. Throws on
// an unrecoverable error (the workers are then still waiting: the caller aborts the job).
int run_master(const mpi::Communicator& comm, PreparedRun& run, const MasterOptions& options);
// Several runs in one worker pool (master/run.hpp execute_runs): the exit code is 75 if any run
// was interrupted, else 0.
int run_master(const mpi::Communicator& comm, const std::vector<PreparedRun*>& runs,
               const MasterOptions& options);

}  // namespace softevo::master
