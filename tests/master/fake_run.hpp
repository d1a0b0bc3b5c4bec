// A run of the real loop (master/run.hpp) with a stand-in evaluator: fitness from the genome
// bytes, so a run of a few generations takes milliseconds. Shared by the run-loop tests.
#pragma once

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <functional>
#include <string>

#include "common/fnv1a.hpp"
#include "io/archive.hpp"
#include "master/run.hpp"
#include "tasks/task.hpp"

namespace softevo::master {

inline Config small_config() {
  Config c;
  c.body.lattice = {5, 5, 5};
  c.task.eval_seconds = 0.1;
  c.neat.pop_size = 6;
  c.run.seed = 5;
  c.run.generations = 4;
  return c;
}

// A deterministic stand-in for a physics evaluation: fitness from the genome's bytes.
inline EvalResult fake_evaluation(const EvalRequest& request) {
  Fnv1a64 fnv;
  fnv.bytes(request.genome.data(), request.genome.size());
  const std::uint64_t h = fnv.value();
  EvalResult r;
  r.genome_id = request.genome_id;
  r.unit = request.unit;
  r.fitness = static_cast<double>(h >> 11) / static_cast<double>(1ULL << 53);
  r.voxels = 10;
  UnitFitness u;
  u.fitness = r.fitness;
  u.values.assign(tasks::make_task(small_config())->component_names().size(), r.fitness);
  r.components.push_back(u);
  return r;
}

// One run (or resume) of `config` into `out`; throws StartupError / RunError.
inline RunOutcome run_once(const Config& config, const std::string& out, bool resume,
                           const io::WriteStepHook& fault = {}) {
  RunOptions options;
  options.out_path = out;
  options.resume = resume;
  options.archive_fault = fault;
  PreparedRun run = prepare_run(config, options, 1);
  LocalExecutor executor(fake_evaluation);
  ProgressReporter progress = ProgressReporter::silent();
  return execute_run(run, executor, progress);
}

// Runs `body` in a child process (fork) that exits when it returns or throws; true when the
// child died of SIGKILL instead (the body killed itself at the instant under test).
inline bool killed_in_child(const std::function<void()>& body) {
  const pid_t child = ::fork();
  if (child == 0) {
    try {
      body();
    } catch (...) {
      ::_exit(3);
    }
    ::_exit(0);
  }
  int status = 0;
  ::waitpid(child, &status, 0);
  return WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL;
}

inline std::string fitness_digest_of(const std::string& path) {
  return hash_hex(io::fitness_digest(io::Archive(path)));
}

}  // namespace softevo::master
