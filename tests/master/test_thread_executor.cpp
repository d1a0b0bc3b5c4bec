// The worker-thread executor of `softevo evolve` (master/thread_executor.hpp) on the real run
// loop with the stand-in evaluator: any number of threads writes the archive one process
// evaluating alone writes (both digests), several runs in one pool too; a stop-now drops the
// generation in flight and --resume completes to the same archive; an evaluation that throws
// fails the run with the worker named; worker_rank names the threads 1..W.
#include "master/thread_executor.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <set>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "io/archive.hpp"
#include "master/signals.hpp"
#include "tests/io/tmp_dir.hpp"
#include "tests/master/fake_run.hpp"

namespace softevo::master {
namespace {

struct Digests {
  std::string fitness, content;
};
Digests digests_of(const std::string& path) {
  const io::Archive a(path);
  return {hash_hex(io::fitness_digest(a)), hash_hex(io::content_digest(a))};
}

// A stand-in evaluation that takes a little wall time, so that several units are in flight
// at once and finish out of order.
EvalResult slow_fake(const EvalRequest& request) {
  std::this_thread::sleep_for(std::chrono::microseconds(200 * (request.genome_id % 5)));
  return fake_evaluation(request);
}

RunOutcome run_threads(const Config& config, const std::string& out, int workers, bool resume,
                       const std::function<bool()>& stop = {}) {
  RunOptions options;
  options.out_path = out;
  options.resume = resume;
  PreparedRun run = prepare_run(config, options, workers + 1);
  ThreadExecutor executor(workers, slow_fake, stop);
  ProgressReporter progress = ProgressReporter::silent();
  return execute_run(run, executor, progress);
}

TEST(ThreadExecutor, AnyThreadCountWritesTheArchiveOfOneProcessAlone) {
  test::TmpDir dir(true);  // in memory: the archive writes cost no fsync
  Config config = small_config();
  config.run.generations = 5;
  config.neat.pop_size = 9;
  ASSERT_EQ(run_once(config, dir.file("alone.h5"), false), RunOutcome::complete);
  const Digests alone = digests_of(dir.file("alone.h5"));
  for (int workers : {1, 2, 3, 7}) {
    const std::string out = dir.file("threads" + std::to_string(workers) + ".h5");
    ASSERT_EQ(run_threads(config, out, workers, false), RunOutcome::complete);
    const Digests d = digests_of(out);
    EXPECT_EQ(d.fitness, alone.fitness) << workers << " threads";
    EXPECT_EQ(d.content, alone.content) << workers << " threads";
    const io::Archive a(out);
    EXPECT_EQ(a.info().ranks, workers + 1);
    std::set<std::int64_t> ranks;
    for (std::int64_t g : a.generations())
      for (std::int64_t r : a.generation(g).worker_rank) ranks.insert(r);
    for (std::int64_t r : ranks) {
      EXPECT_GE(r, -1);  // -1: a reused result
      EXPECT_NE(r, 0);   // the calling thread only schedules
      EXPECT_LE(r, workers);
    }
  }
}

TEST(ThreadExecutor, SeveralRunsInOnePoolWriteTheArchivesOfTheRunsAlone) {
  test::TmpDir dir(true);  // in memory: the archive writes cost no fsync
  std::vector<Config> configs;
  std::vector<PreparedRun> runs;
  for (int seed : {3, 4, 5}) {
    Config c = small_config();
    c.run.seed = seed;
    c.run.generations = 3 + seed % 2;
    ASSERT_EQ(run_once(c, dir.file("alone" + std::to_string(seed) + ".h5"), false),
              RunOutcome::complete);
    RunOptions options;
    options.out_path = dir.file("pool" + std::to_string(seed) + ".h5");
    runs.push_back(prepare_run(c, options, 4));
  }
  ThreadExecutor executor(3, slow_fake);
  std::vector<ProgressReporter> reporters(3, ProgressReporter::silent());
  std::vector<PreparedRun*> pointers;
  std::vector<ProgressReporter*> progress;
  for (std::size_t i = 0; i < runs.size(); ++i) {
    pointers.push_back(&runs[i]);
    progress.push_back(&reporters[i]);
  }
  const std::vector<RunOutcome> outcomes = execute_runs(pointers, executor, progress);
  for (RunOutcome o : outcomes) EXPECT_EQ(o, RunOutcome::complete);
  for (int seed : {3, 4, 5}) {
    const Digests a = digests_of(dir.file("alone" + std::to_string(seed) + ".h5"));
    const Digests p = digests_of(dir.file("pool" + std::to_string(seed) + ".h5"));
    EXPECT_EQ(p.fitness, a.fitness) << "seed " << seed;
    EXPECT_EQ(p.content, a.content) << "seed " << seed;
  }
}

TEST(ThreadExecutor, AStopNowDropsTheGenerationInFlightAndResumeCompletesIt) {
  test::TmpDir dir(true);  // in memory: the archive writes cost no fsync
  const Config config = small_config();
  ASSERT_EQ(run_once(config, dir.file("ref.h5"), false), RunOutcome::complete);
  // The stop poll answers true once generation 1 has started (a few units evaluated later).
  std::atomic<int> polls{0};
  const std::string out = dir.file("stopped.h5");
  const auto stop = [&] {
    std::error_code ec;
    if (!std::filesystem::exists(out, ec)) return false;
    return io::Archive(out).info().generations_done >= 2 && ++polls > 1;
  };
  EXPECT_EQ(run_threads(config, out, 3, false, stop), RunOutcome::interrupted);
  EXPECT_EQ(stop_requested(), StopRequest::now);  // the poll became a stop-now request
  clear_stop_request();
  const io::Archive stopped(out);
  EXPECT_EQ(stopped.info().state, io::RunState::interrupted);
  EXPECT_EQ(stopped.info().generations_done, 2);
  ASSERT_EQ(run_threads(config, out, 2, true), RunOutcome::complete);
  const Digests a = digests_of(dir.file("ref.h5")), b = digests_of(out);
  EXPECT_EQ(b.fitness, a.fitness);
  EXPECT_EQ(b.content, a.content);
}

TEST(ThreadExecutor, AnEvaluationThatThrowsFailsTheRunNamingItsWorker) {
  test::TmpDir dir(true);  // in memory: the archive writes cost no fsync
  RunOptions options;
  options.out_path = dir.file("run.h5");
  PreparedRun run = prepare_run(small_config(), options, 3);
  ThreadExecutor executor(2, [](const EvalRequest& r) -> EvalResult {
    if (r.genome_id % 3 == 2) throw std::runtime_error("config mismatch");
    return fake_evaluation(r);
  });
  ProgressReporter progress = ProgressReporter::silent();
  try {
    execute_run(run, executor, progress);
    ADD_FAILURE() << "no RunError";
  } catch (const RunError& e) {
    EXPECT_NE(std::string(e.what()).find("worker thread"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("config mismatch"), std::string::npos) << e.what();
  }
  EXPECT_EQ(io::Archive(dir.file("run.h5")).info().state, io::RunState::interrupted);
}

TEST(ThreadExecutor, RefusesNoWorkersAndFindsTheCores) {
  EXPECT_THROW(ThreadExecutor(0, fake_evaluation), std::invalid_argument);
  EXPECT_GE(available_cores(), 1);
  EXPECT_EQ(ThreadExecutor(4, fake_evaluation).ranks(), 5);
}

}  // namespace
}  // namespace softevo::master
