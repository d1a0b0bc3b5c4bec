// The SPMD program softevo-mpi as a function of a communicator, so the MPI integration tests can
// run it in-process on the world or on a sub-communicator (np = 1, 2, 3 in one test binary). It
// joins the two sides, which know nothing of each other: rank 0 runs the master driver
// (master/mpi_driver.hpp), ranks 1..N-1 the worker loop (worker/worker_loop.hpp); both talk
// through softevo's duplicate of `comm` (mpi/communicator.hpp).
//
// Rank 0 parses options, resolves the config and prepares the run; the start-up status and the
// config text are broadcast, so a start-up error ends every rank with exit 2 and one message
// from rank 0, nothing touched. An unrecoverable error on any rank prints
// "softevo-mpi: error: rank R: ..." and aborts the job: no rank hangs.
//
// Exit codes (the same on every rank): 0 complete (or nothing to resume), 2 usage / config /
// start-up error, 75 (kExitRequeue) stopped after a checkpoint by SIGTERM/SIGINT/SIGUSR1, a
// worker that left or a dead launcher (master/mpi_driver.hpp).
#pragma once

#include "mpi/communicator.hpp"
#include "worker/evaluate.hpp"

namespace softevo {

struct MpiMainHooks {
  worker::EvaluateOptions unit_options;  // tests: stand-in evaluation, injected faults
  bool quiet = false;                    // tests: no progress output
};

int softevo_mpi_main(int argc, char** argv, MPI_Comm comm, const MpiMainHooks& hooks = {});

}  // namespace softevo
