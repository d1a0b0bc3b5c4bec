#include "worker/worker_loop.hpp"

#include <string>
#include <vector>

#include "common/wire.hpp"

namespace softevo::worker {

WorkerOutcome run_worker_loop(const mpi::Communicator& comm, const Config& config,
                              std::uint64_t config_hash, const EvaluateOptions& options) {
  constexpr int kMaster = 0;
  WorkerOutcome outcome;
  const std::unique_ptr<tasks::Task> task = tasks::make_task(config);
  for (;;) {
    const mpi::Message message = comm.receive(kMaster);
    if (message.tag == mpi::Tag::stop) {
      outcome.exit_code = decode_shutdown(message.bytes);
      return outcome;
    }
    if (message.tag != mpi::Tag::request)
      throw mpi::Error("rank " + std::to_string(comm.rank()) + ": unexpected message with tag " +
                       mpi::tag_name(message.tag) + " (" +
                       std::to_string(static_cast<int>(message.tag)) + ", " +
                       std::to_string(message.bytes.size()) + " bytes) from the master");
    const EvalRequest request = decode_eval_request(message.bytes);
    EvalResult result;
    try {
      result = evaluate(config, *task, config_hash, request, options);
    } catch (const ConfigMismatch& e) {
      comm.send(kMaster, mpi::Tag::error,
                "rank " + std::to_string(comm.rank()) + " rejected a request: " + e.what());
      continue;  // the master ends the run; keep serving until it does
    }
    result.worker_rank = comm.rank();
    comm.send(kMaster, mpi::Tag::result, encode_eval_result(result));
    ++outcome.units_evaluated;
  }
}

}  // namespace softevo::worker
