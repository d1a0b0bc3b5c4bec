// The SPMD program softevo-mpi as a function of a communicator, so the MPI integration tests can
// run it in-process on the world or on a sub-communicator (np = 1, 2, 3 in one test binary).
//
// Rank 0: parses options, resolves the config, prepares the run (start-up errors are broadcast:
// every rank exits 2 with one message from rank 0, nothing touched), then runs the generation
// loop (master/run.hpp) with an executor that self-schedules work units over ranks 1..N-1
// (or evaluates by itself with one rank). Ranks 1..N-1 run the worker loop. An unrecoverable
// error on any rank prints "softevo-mpi: rank R: error: ..." and calls MPI_Abort: no rank hangs.
//
// Exit codes (the same on every rank): 0 complete (or nothing to resume), 2 usage / config /
// start-up error, 75 (kExitRequeue) stopped by SIGTERM/SIGINT/SIGUSR1 after a checkpoint.
#pragma once

#include <mpi.h>

#include "worker/evaluate_unit.hpp"

namespace softevo::master {

struct MpiMainHooks {
  worker::UnitOptions unit_options;  // tests: stand-in simulator
  bool quiet = false;                // tests: no progress output
};

int softevo_mpi_main(int argc, char** argv, MPI_Comm comm, const MpiMainHooks& hooks = {});

}  // namespace softevo::master
