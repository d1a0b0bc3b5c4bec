// The MPI worker loop (ranks 1..N-1 of softevo-mpi): a thin driver around worker::evaluate() that
// speaks the protocol of mpi/protocol.hpp. A worker rejects a request whose config hash differs
// from its own with Tag::error (the master then ends the run); a failing evaluation is a result
// with a status, never an error.
//
// A worker that is told to stop (a stop signal: mpirun forwards SIGTERM to every rank, Slurm
// signals every task) or whose launcher died (common/launcher_watch.hpp) abandons the
// evaluation in progress within one control frame, drops its result (the master drops the
// partial generation anyway, and an abandoned unit must never be archived), tells the master
// with Tag::leaving, and serves no more requests. It then waits for the master's stop message
// and returns its code; an orphan (launcher gone) or a worker whose master does not answer
// within kStopWaitSeconds leaves on its own.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "common/config.hpp"
#include "mpi/communicator.hpp"
#include "worker/evaluate.hpp"

namespace softevo::worker {

// How long a leaving worker waits for the master's stop message [s]. The master answers within
// a fraction of a second (it stops at once); mpirun kills a job 1 s after its SIGTERM anyway.
inline constexpr double kStopWaitSeconds = 30.0;

struct WorkerOutcome {
  std::int64_t units_evaluated = 0;
  int exit_code = 0;  // carried by the master's stop message: what this rank's process returns
  // True if the worker left without the master's stop message (launcher gone, or no answer
  // within kStopWaitSeconds); exit_code is then meaningless and the caller picks one.
  bool left_on_its_own = false;
};

// Serves requests from rank 0 until Tag::stop. `stop_signal` names the stop signal this process
// has received ("SIGTERM"), "" while there is none; empty = never stopped by a signal. Throws
// mpi::Error or WireError on a message that breaks the protocol (the program prints rank +
// message and aborts the job).
WorkerOutcome run_worker_loop(const mpi::Communicator& comm, const Config& config,
                              std::uint64_t config_hash, const EvaluateOptions& options = {},
                              const std::function<std::string()>& stop_signal = {});
// The worker of several runs in one job (softevo-mpi --seeds): each request is evaluated with
// the config whose hash it carries; a hash none of `configs` has is rejected as above.
WorkerOutcome run_worker_loop(const mpi::Communicator& comm, const std::vector<Config>& configs,
                              const EvaluateOptions& options = {},
                              const std::function<std::string()>& stop_signal = {});

}  // namespace softevo::worker
