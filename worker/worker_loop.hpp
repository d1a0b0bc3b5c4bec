// The MPI worker loop (ranks 1..N-1 of softevo-mpi): a thin driver around evaluate_unit().
// Protocol on the communicator (all payloads are framed wire messages, common/wire.hpp):
//   master -> worker  kTagRequest  eval request        worker -> master  kTagResult  eval result
//   master -> worker  kTagStop     (empty): return     worker -> master  kTagError   UTF-8 text
// A worker rejects a request whose config hash differs from its own with kTagError (the master
// then ends the run); a failing evaluation is a result with a status, never an error.
// Waiting never spins a core: Open MPI's blocking calls busy-poll, so we poll with MPI_Iprobe
// and sleep between polls (1 ms growing to 10 ms).
#pragma once

#include <mpi.h>

#include <cstdint>

#include "common/config.hpp"
#include "worker/evaluate_unit.hpp"

namespace softevo::worker {

inline constexpr int kTagRequest = 101;
inline constexpr int kTagResult = 102;
inline constexpr int kTagStop = 103;
inline constexpr int kTagError = 104;

// Polling back-off while waiting for a message [s]: starts at kPollMin, x1.5 per empty poll,
// capped at kPollMax. 10 ms of added latency is nothing next to a robot evaluation (seconds),
// and a sleeping rank costs ~0% CPU instead of 100%.
inline constexpr double kPollMinSeconds = 0.001;
inline constexpr double kPollMaxSeconds = 0.010;

// Sleep-polls until a message from `source` (or MPI_ANY_SOURCE) with `tag` (or MPI_ANY_TAG)
// is pending; returns its status. `keep_waiting` (optional) is called between polls and can
// end the wait by returning false (then the function returns false).
bool wait_for_message(MPI_Comm comm, int source, int tag, MPI_Status& status,
                      bool (*keep_waiting)(void*) = nullptr, void* user = nullptr);
// Receives the pending message described by `status` as bytes.
std::vector<std::uint8_t> receive_bytes(MPI_Comm comm, const MPI_Status& status);

// Serves requests from rank 0 until kTagStop. Returns the number of units evaluated. Throws on
// communication or decoding errors (the driver prints rank + message and calls MPI_Abort).
std::int64_t run_worker_loop(MPI_Comm comm, const Config& config, std::uint64_t config_hash,
                             const UnitOptions& options = {});

}  // namespace softevo::worker
