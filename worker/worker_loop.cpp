#include "worker/worker_loop.hpp"

#include <ctime>
#include <string>
#include <vector>

#include "common/wire.hpp"

namespace softevo::worker {
namespace {

void sleep_seconds(double s) {
  timespec ts;
  ts.tv_sec = static_cast<time_t>(s);
  ts.tv_nsec = static_cast<long>((s - static_cast<double>(ts.tv_sec)) * 1e9);
  nanosleep(&ts, nullptr);
}

}  // namespace

bool wait_for_message(MPI_Comm comm, int source, int tag, MPI_Status& status,
                      bool (*keep_waiting)(void*), void* user) {
  double pause = kPollMinSeconds;
  for (;;) {
    int flag = 0;
    MPI_Iprobe(source, tag, comm, &flag, &status);
    if (flag != 0) return true;
    if (keep_waiting != nullptr && !keep_waiting(user)) return false;
    sleep_seconds(pause);
    pause = pause * 1.5 < kPollMaxSeconds ? pause * 1.5 : kPollMaxSeconds;
  }
}

std::vector<std::uint8_t> receive_bytes(MPI_Comm comm, const MPI_Status& status) {
  int count = 0;
  MPI_Get_count(&status, MPI_BYTE, &count);
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(count));
  MPI_Recv(bytes.data(), count, MPI_BYTE, status.MPI_SOURCE, status.MPI_TAG, comm,
           MPI_STATUS_IGNORE);
  return bytes;
}

std::int64_t run_worker_loop(MPI_Comm comm, const Config& config, std::uint64_t config_hash,
                             const UnitOptions& options) {
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  std::int64_t evaluated = 0;
  for (;;) {
    MPI_Status status;
    wait_for_message(comm, 0, MPI_ANY_TAG, status);
    std::vector<std::uint8_t> bytes = receive_bytes(comm, status);
    if (status.MPI_TAG == kTagStop) return evaluated;
    if (status.MPI_TAG != kTagRequest)
      throw std::runtime_error("worker: unexpected message tag " + std::to_string(status.MPI_TAG));
    const EvalRequest request = decode_eval_request(bytes);
    EvalResult result;
    try {
      result = evaluate_unit(config, config_hash, request, options);
    } catch (const ConfigMismatch& e) {
      const std::string text = "rank " + std::to_string(rank) + " rejected a request: " + e.what();
      MPI_Send(text.data(), static_cast<int>(text.size()), MPI_BYTE, 0, kTagError, comm);
      continue;  // the master ends the run; keep serving until it does
    }
    result.worker_rank = rank;
    const std::vector<std::uint8_t> out = encode_eval_result(result);
    MPI_Send(out.data(), static_cast<int>(out.size()), MPI_BYTE, 0, kTagResult, comm);
    ++evaluated;
  }
}

}  // namespace softevo::worker
