// The MPI worker loop (worker/worker_loop.hpp), at np = 2 and 3: rank 0 plays the master by
// hand. A worker answers each request with a result, returns the exit code of the stop message,
// rejects a request of another config, and reports a message that breaks the protocol.
#include "worker/worker_loop.hpp"

#include <gtest/gtest.h>
#include <mpi.h>

#include <string>
#include <vector>

#include "common/wire.hpp"

namespace softevo::worker {
namespace {

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// Ends every worker rank from `first` on with `exit_code`.
void stop_workers(const mpi::Communicator& comm, int first, int exit_code) {
  for (int r = first; r < comm.size(); ++r)
    comm.send(r, mpi::Tag::stop, encode_shutdown(exit_code));
}

TEST(WorkerLoop, AnswersEachRequestAndReturnsTheExitCodeOfTheStopMessage) {
  const mpi::Communicator comm(MPI_COMM_WORLD);
  const Config config;
  const std::uint64_t hash = config_hash(config);
  if (comm.rank() == 0) {
    for (int r = 1; r < comm.size(); ++r) {
      EvalRequest request;
      request.config_hash = hash;
      request.genome_id = 1000 + r;  // no genome bytes: a failed evaluation, still a result
      comm.send(r, mpi::Tag::request, encode_eval_request(request));
    }
    for (int r = 1; r < comm.size(); ++r) {
      const mpi::Message reply = comm.receive(r, mpi::Tag::result);
      const EvalResult result = decode_eval_result(reply.bytes);
      EXPECT_EQ(result.genome_id, 1000 + r);
      EXPECT_EQ(result.worker_rank, r);
      EXPECT_EQ(result.status, EvalStatus::failed);
    }
    for (int r = 1; r < comm.size(); ++r)
      comm.send(r, mpi::Tag::stop, encode_shutdown(70 + r));  // a distinct code per worker
  } else {
    const WorkerOutcome outcome = run_worker_loop(comm, config, hash);
    EXPECT_EQ(outcome.units_evaluated, 1);
    EXPECT_EQ(outcome.exit_code, 70 + comm.rank());
  }
  MPI_Barrier(MPI_COMM_WORLD);
}

TEST(WorkerLoop, RejectsAConfigHashMismatch) {
  const mpi::Communicator comm(MPI_COMM_WORLD);
  const Config config;
  const std::uint64_t hash = config_hash(config);
  if (comm.rank() == 0) {
    EvalRequest request;
    request.config_hash = hash ^ 1;  // a master with another config
    request.genome_id = 42;
    comm.send(1, mpi::Tag::request, encode_eval_request(request));
    const mpi::Message reply = comm.receive(1, mpi::Tag::error);
    const std::string text(reply.bytes.begin(), reply.bytes.end());
    EXPECT_TRUE(contains(text, "config hash")) << text;
    EXPECT_TRUE(contains(text, "rank 1")) << text;
    stop_workers(comm, 1, 0);
  } else {
    const WorkerOutcome outcome = run_worker_loop(comm, config, hash);
    EXPECT_EQ(outcome.units_evaluated, 0);
    EXPECT_EQ(outcome.exit_code, 0);
  }
  MPI_Barrier(MPI_COMM_WORLD);
}

// Rank 0 sends `bytes` with `tag` to rank 1 and stops the others; rank 1's loop must throw an
// error whose text holds every one of `expected`.
template <class ErrorType>
void expect_protocol_error(mpi::Tag tag, const std::vector<std::uint8_t>& bytes,
                           const std::vector<std::string>& expected) {
  const mpi::Communicator comm(MPI_COMM_WORLD);
  const Config config;
  const std::uint64_t hash = config_hash(config);
  if (comm.rank() == 0) {
    comm.send(1, tag, bytes);
    stop_workers(comm, 2, 0);
  } else if (comm.rank() == 1) {
    try {
      run_worker_loop(comm, config, hash);
      ADD_FAILURE() << "the worker accepted a broken message with tag " << mpi::tag_name(tag);
    } catch (const ErrorType& e) {
      for (const std::string& part : expected) EXPECT_TRUE(contains(e.what(), part)) << e.what();
    }
  } else {
    EXPECT_EQ(run_worker_loop(comm, config, hash).exit_code, 0);
  }
  MPI_Barrier(MPI_COMM_WORLD);
}

TEST(WorkerLoop, ATruncatedRequestIsAClearError) {
  EvalRequest request;
  request.genome = {1, 2, 3, 4};
  std::vector<std::uint8_t> bytes = encode_eval_request(request);
  bytes.resize(bytes.size() - 3);
  expect_protocol_error<WireError>(mpi::Tag::request, bytes, {"message header", "truncated"});
}

TEST(WorkerLoop, AStopWithoutAnExitCodeIsAClearError) {
  expect_protocol_error<WireError>(mpi::Tag::stop, {}, {"message header", "magic"});
}

TEST(WorkerLoop, AMessageOnlyWorkersSendIsAClearError) {
  expect_protocol_error<mpi::Error>(mpi::Tag::result, {0}, {"rank 1", "result", "1 bytes"});
}

}  // namespace
}  // namespace softevo::worker
