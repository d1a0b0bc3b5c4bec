#include "master/thread_executor.hpp"

#include <sched.h>

#include <chrono>
#include <string>

#include "master/signals.hpp"

namespace softevo::master {

int available_cores() {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof set, &set) == 0) {
    const int n = CPU_COUNT(&set);
    if (n > 0) return n;
  }
  const unsigned n = std::thread::hardware_concurrency();
  return n > 0 ? static_cast<int>(n) : 1;
}

ThreadExecutor::ThreadExecutor(int workers, EvaluateFn evaluate, std::function<bool()> stop)
    : evaluate_(std::move(evaluate)), stop_(std::move(stop)) {
  if (workers < 1)
    throw std::invalid_argument("ThreadExecutor: " + std::to_string(workers) +
                                " worker threads (at least 1)");
  threads_.reserve(static_cast<std::size_t>(workers));
  // Worker w is "rank" w + 1 in the archive's worker_rank column, as on softevo-mpi.
  for (int w = 1; w <= workers; ++w) threads_.emplace_back([this, w] { work(w); });
}

ThreadExecutor::~ThreadExecutor() {
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    quit_ = true;
    in_flight_ -= jobs_.size();
    jobs_.clear();
  }
  job_ready_.notify_all();
  for (std::thread& t : threads_) t.join();
}

void ThreadExecutor::work(int worker) {
  for (;;) {
    Job job;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      job_ready_.wait(lock, [this] { return quit_ || !jobs_.empty(); });
      if (quit_) return;
      job = std::move(jobs_.front());
      jobs_.pop_front();
    }
    Done done;
    done.run = job.run;
    done.worker = worker;
    try {
      done.result = evaluate_(job.request);
    } catch (...) {
      done.error = std::current_exception();
    }
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      done_.push_back(std::move(done));
    }
    result_ready_.notify_one();
  }
}

bool ThreadExecutor::stop_now() const {
  if (stop_requested() == StopRequest::now) return true;
  if (stop_ && stop_()) {
    // The evaluations in flight abandon on the same request their options ask for.
    request_stop(StopRequest::now);
    return true;
  }
  return false;
}

void ThreadExecutor::drain() {
  std::unique_lock<std::mutex> lock(mutex_);
  in_flight_ -= jobs_.size();
  jobs_.clear();
  while (in_flight_ > 0) {
    result_ready_.wait(lock, [this] { return !done_.empty(); });
    in_flight_ -= done_.size();
    done_.clear();
  }
}

std::optional<std::size_t> ThreadExecutor::evaluate_any(
    const std::vector<ActiveGeneration>& generations) {
  const auto generation_of = [&](std::size_t run) -> const ActiveGeneration* {
    for (const ActiveGeneration& a : generations)
      if (a.run == run) return &a;
    return nullptr;
  };
  for (;;) {
    if (stop_now()) {
      drain();
      return std::nullopt;
    }
    // A generation may be done without a unit (every result reused) or by the last result.
    for (const ActiveGeneration& a : generations)
      if (a.scheduler->done()) return a.run;
    std::unique_lock<std::mutex> lock(mutex_);
    // Self-scheduling as on softevo-mpi: only an idle worker gets a unit, so the scheduler's
    // order (longest first) is the order the workers start them in.
    for (const ActiveGeneration& a : generations) {
      while (in_flight_ < threads_.size() && a.scheduler->has_next()) {
        const WorkUnit unit = *a.scheduler->next();
        jobs_.push_back(Job{a.run, a.request(unit)});
        ++in_flight_;
        job_ready_.notify_one();
      }
    }
    if (done_.empty()) {
      // Bounded, so a signal or the stop poll is seen within 50 ms.
      result_ready_.wait_for(lock, std::chrono::milliseconds(50));
      continue;
    }
    Done done = std::move(done_.front());
    done_.pop_front();
    --in_flight_;
    lock.unlock();
    // A stop-now during the evaluation may have abandoned it: never archive that result.
    if (stop_now()) {
      drain();
      return std::nullopt;
    }
    if (done.error) {
      try {
        std::rethrow_exception(done.error);
      } catch (const std::exception& e) {
        throw RunError(std::string("worker thread ") + std::to_string(done.worker) + ": " +
                       e.what());
      }
    }
    const ActiveGeneration* a = generation_of(done.run);
    if (a == nullptr)
      throw RunError("a result of run " + std::to_string(done.run) +
                     ", which has no generation in flight");
    done.result.worker_rank = done.worker;
    a->scheduler->complete(done.result);
    a->progress->unit_done(a->scheduler->units_done(), a->scheduler->units_total());
  }
}

}  // namespace softevo::master
