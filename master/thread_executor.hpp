// The executor of `softevo evolve` and `softevo.evolve` (Python): the work units of a run
// evaluated by worker threads of this process instead of MPI ranks (docs/archive.md, "One
// process: softevo evolve"). It hands out units like softevo-mpi's master hands them to worker
// ranks (master/mpi_driver.cpp): an idle worker gets the scheduler's next unit, each result frees
// its worker, units of several runs' generations may be in flight at once. Results are stored by
// genome id and unit, so the archive, its content and fitness digests are those of softevo-mpi at
// any rank count: a run with W worker threads writes the archive softevo-mpi -np W+1 writes
// (ranks() = W + 1, worker_rank 1..W).
//
// No MPI here: it lives in master/ and works in a build without MPI. The evaluation reaches it
// as a function (called concurrently from the worker threads; worker::evaluate is a pure
// function of its arguments).
//
// A stop-now (SIGTERM/SIGINT via master/signals.hpp, or the `stop` poll, e.g. Python's Ctrl-C)
// hands out nothing more and waits only for the units in flight, which the evaluation function
// is expected to abandon at its next control frame (worker::EvaluateOptions::abandon); their
// results are dropped with the generation, as softevo-mpi drops them.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <exception>
#include <functional>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include "common/eval_types.hpp"
#include "master/run.hpp"

namespace softevo::master {

// The worker threads for `softevo evolve` when none are asked for: the cores this process may
// run on (its CPU affinity, which Slurm and taskset restrict), at least 1.
int available_cores();
// The most worker threads one process starts (`softevo evolve --workers`, `softevo.evolve`):
// far above any node's cores, and below the count whose thread stacks alone exhaust a machine's
// memory (100,000 threads aborted the Python interpreter, issue 39).
inline constexpr int kMaxWorkerThreads = 4096;

class ThreadExecutor : public UnitExecutor {
 public:
  using EvaluateFn = std::function<EvalResult(const EvalRequest&)>;
  // `workers` >= 1 threads calling `evaluate`. `stop` (optional) is polled by the calling
  // thread while it waits (every <= 50 ms): true = stop now, as a SIGTERM would.
  ThreadExecutor(int workers, EvaluateFn evaluate, std::function<bool()> stop = {});
  ~ThreadExecutor() override;  // waits for the units in flight, joins the threads
  ThreadExecutor(const ThreadExecutor&) = delete;
  ThreadExecutor& operator=(const ThreadExecutor&) = delete;

  int ranks() const override { return static_cast<int>(threads_.size()) + 1; }
  int workers() const { return static_cast<int>(threads_.size()); }
  std::optional<std::size_t> evaluate_any(
      const std::vector<ActiveGeneration>& generations) override;

 private:
  struct Job {
    std::size_t run = 0;
    EvalRequest request;
  };
  struct Done {
    std::size_t run = 0;
    int worker = 0;
    EvalResult result;
    std::exception_ptr error;  // the evaluation threw (a config mismatch): the run fails
  };
  void work(int worker);
  bool stop_now() const;
  // Waits until no unit is in flight, dropping their results (after a stop-now).
  void drain();

  EvaluateFn evaluate_;
  std::function<bool()> stop_;
  std::mutex mutex_;
  std::condition_variable job_ready_;
  std::condition_variable result_ready_;
  std::deque<Job> jobs_;
  std::deque<Done> done_;
  std::size_t in_flight_ = 0;  // units handed out whose result has not been taken
  bool quit_ = false;
  std::vector<std::thread> threads_;
};

}  // namespace softevo::master
