// The MPI worker loop (ranks 1..N-1 of softevo-mpi): a thin driver around worker::evaluate() that
// speaks the protocol of mpi/protocol.hpp. A worker rejects a request whose config hash differs
// from its own with Tag::error (the master then ends the run); a failing evaluation is a result
// with a status, never an error.
#pragma once

#include <cstdint>

#include "common/config.hpp"
#include "mpi/communicator.hpp"
#include "worker/evaluate.hpp"

namespace softevo::worker {

struct WorkerOutcome {
  std::int64_t units_evaluated = 0;
  int exit_code = 0;  // carried by the master's stop message: what this rank's process returns
};

// Serves requests from rank 0 until Tag::stop. Throws mpi::Error or WireError on a message that
// breaks the protocol (the program prints rank + message and aborts the job).
WorkerOutcome run_worker_loop(const mpi::Communicator& comm, const Config& config,
                              std::uint64_t config_hash, const EvaluateOptions& options = {});

}  // namespace softevo::worker
