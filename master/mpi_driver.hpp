// Rank 0 of softevo-mpi: the generation loop (master/run.hpp) with an executor that
// self-schedules work units over ranks 1..N-1 (or evaluates by itself with one rank), the
// console report, and the end of the workers. The program that joins this with the worker loop
// is tools/softevo_mpi.cpp.
//
// Exit code: 0 complete (or nothing to resume), 75 (kExitRequeue) stopped by
// SIGTERM/SIGINT/SIGUSR1 after a checkpoint. run_master sends it to every worker in the stop
// message (mpi/protocol.hpp), the one way a worker learns it.
#pragma once

#include <string>

#include "master/run.hpp"
#include "mpi/communicator.hpp"

namespace softevo::master {

struct MasterOptions {
  std::string config_path;                   // shown in the console header
  LocalExecutor::EvaluateFn evaluate_alone;  // evaluates a unit when there is no worker rank
  bool quiet = false;                        // no console output (tests)
};

// Runs `run` (prepared by prepare_run) on rank 0 of `comm` and returns the exit code. Throws on
// an unrecoverable error (the workers are then still waiting: the caller aborts the job).
int run_master(const mpi::Communicator& comm, PreparedRun& run, const MasterOptions& options);

}  // namespace softevo::master
