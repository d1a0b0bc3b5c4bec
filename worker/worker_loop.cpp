#include "worker/worker_loop.hpp"

#include <chrono>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/launcher_watch.hpp"
#include "common/wire.hpp"

namespace softevo::worker {

namespace {

// A config of the job and its task.
struct RunConfig {
  Config config;
  std::uint64_t hash = 0;
  std::unique_ptr<tasks::Task> task;
};

WorkerOutcome serve(const mpi::Communicator& comm, const std::vector<RunConfig>& runs,
                    const EvaluateOptions& options,
                    const std::function<std::string()>& stop_signal) {
  constexpr int kMaster = 0;
  WorkerOutcome outcome;
  const std::string rank = "rank " + std::to_string(comm.rank());

  // Why this worker must stop; "" while it serves. Asked once per control frame: a getppid()
  // and an atomic load.
  const auto stop_reason = [&stop_signal]() -> std::string {
    if (launcher_gone()) return launcher_gone_reason();
    const std::string signal = stop_signal ? stop_signal() : std::string();
    return signal.empty() ? signal : "stopped by " + signal;
  };
  EvaluateOptions unit_options = options;
  unit_options.abandon = [&stop_reason, earlier = options.abandon] {
    return (earlier && earlier()) || !stop_reason().empty();
  };

  std::optional<std::chrono::steady_clock::time_point> left;  // when Tag::leaving was sent
  const auto leave_if_stopping = [&] {
    if (left) return;
    const std::string reason = stop_reason();
    if (reason.empty()) return;
    comm.send(kMaster, mpi::Tag::leaving, rank + ": " + reason);
    left = std::chrono::steady_clock::now();
  };

  for (;;) {
    std::optional<mpi::Envelope> pending;
    mpi::PollBackoff backoff;
    while (!(pending = comm.poll(kMaster))) {
      leave_if_stopping();
      if (left && (launcher_gone() || std::chrono::steady_clock::now() - *left >
                                          std::chrono::duration<double>(kStopWaitSeconds))) {
        outcome.left_on_its_own = true;
        return outcome;
      }
      backoff.sleep();
    }
    const mpi::Message message = comm.receive(*pending);
    if (message.tag == mpi::Tag::stop) {
      outcome.exit_code = decode_shutdown(message.bytes);
      return outcome;
    }
    if (message.tag != mpi::Tag::request)
      throw mpi::Error(rank + ": unexpected message with tag " + mpi::tag_name(message.tag) + " (" +
                       std::to_string(static_cast<int>(message.tag)) + ", " +
                       std::to_string(message.bytes.size()) + " bytes) from the master");
    leave_if_stopping();
    if (left) continue;  // sent before the master read Tag::leaving: it is dropped there too
    const EvalRequest request = decode_eval_request(message.bytes);
    // The run of the request; a hash of none of them is the first one's mismatch (rejected).
    const RunConfig* run = &runs.front();
    for (const RunConfig& r : runs)
      if (r.hash == request.config_hash) run = &r;
    EvalResult result;
    try {
      result = evaluate(run->config, *run->task, run->hash, request, unit_options);
    } catch (const ConfigMismatch& e) {
      comm.send(kMaster, mpi::Tag::error, rank + " rejected a request: " + e.what());
      continue;  // the master ends the run; keep serving until it does
    }
    leave_if_stopping();
    if (left) continue;  // abandoned or finished as the stop came: never archived
    result.worker_rank = comm.rank();
    comm.send(kMaster, mpi::Tag::result, encode_eval_result(result));
    ++outcome.units_evaluated;
  }
}

}  // namespace

WorkerOutcome run_worker_loop(const mpi::Communicator& comm, const Config& config,
                              std::uint64_t config_hash, const EvaluateOptions& options,
                              const std::function<std::string()>& stop_signal) {
  std::vector<RunConfig> runs;
  runs.push_back(RunConfig{config, config_hash, tasks::make_task(config)});
  return serve(comm, runs, options, stop_signal);
}

WorkerOutcome run_worker_loop(const mpi::Communicator& comm, const std::vector<Config>& configs,
                              const EvaluateOptions& options,
                              const std::function<std::string()>& stop_signal) {
  if (configs.empty()) throw std::invalid_argument("run_worker_loop: no config");
  std::vector<RunConfig> runs;
  for (const Config& c : configs) runs.push_back(RunConfig{c, config_hash(c), tasks::make_task(c)});
  return serve(comm, runs, options, stop_signal);
}

}  // namespace softevo::worker
