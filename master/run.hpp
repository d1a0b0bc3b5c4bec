// The generation loop of a distributed run, MPI-free (docs/model.md §8.1, docs/model.md §8.10):
//   members = population.members()           (generation g, immigrants included)
//   evaluate every work unit                 (UnitExecutor: in-process or over MPI)
//   archive generation g, population.advance(results), checkpoint the NEXT population
//                                            (io/archive.hpp: its segment, then a new root)
//   at the end (or a stop): pack the archive into one file
// The MPI master driver (master/mpi_driver.cpp) only supplies an executor that farms the units
// out to worker ranks; everything else is here and is tested without MPI.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>

#include "common/config.hpp"
#include "common/eval_types.hpp"
#include "evo/population.hpp"
#include "io/archive.hpp"
#include "io/run_lock.hpp"
#include "master/progress.hpp"
#include "master/scheduler.hpp"

namespace softevo::master {

// A problem found before anything was written (bad output path, archive exists, resume of an
// archive with another config, ...). The run has not touched any existing file.
class StartupError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};
// An unrecoverable problem during the run (I/O, rejected request, run.on_failure = "abort").
class RunError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Evaluates all work units of one generation.
class UnitExecutor {
 public:
  virtual ~UnitExecutor() = default;
  virtual int ranks() const = 0;
  // Hands out every unit of `scheduler` (requests built by `make_request`) and stores every
  // result; reports progress. Returns false if a stop-now request (SIGTERM) interrupted it; the
  // partial results are then discarded by the caller.
  virtual bool evaluate(GenerationScheduler& scheduler,
                        const std::function<EvalRequest(const WorkUnit&)>& make_request,
                        ProgressReporter& progress) = 0;
};

// Single-rank executor: the master evaluates by itself (also the test stand-in).
class LocalExecutor : public UnitExecutor {
 public:
  using EvaluateFn = std::function<EvalResult(const EvalRequest&)>;
  explicit LocalExecutor(EvaluateFn evaluate) : evaluate_(std::move(evaluate)) {}
  int ranks() const override { return 1; }
  bool evaluate(GenerationScheduler& scheduler,
                const std::function<EvalRequest(const WorkUnit&)>& make_request,
                ProgressReporter& progress) override;

 private:
  EvaluateFn evaluate_;
};

struct RunOptions {
  std::string out_path;
  bool resume = false;     // continue `out_path` if it exists (a new run otherwise)
  bool overwrite = false;  // replace an existing `out_path` (at the first archive write)
  std::string host;        // "" = gethostname()
  // Fault injection for tests only (io/archive.hpp): passed to every archive write of the run.
  io::WriteStepHook archive_fault;
};

enum class RunOutcome {
  complete,          // every generation evaluated and archived
  interrupted,       // stopped by a signal after a consistent checkpoint (exit kExitRequeue)
  already_complete,  // --resume of a complete archive: nothing to do
};

// State between start-up and the loop (rank 0).
struct PreparedRun {
  Config config;
  std::string config_text;
  std::uint64_t config_hash = 0;
  RunOptions options;
  io::RunInfo info;
  std::optional<evo::Population> population;
  bool already_complete = false;
  bool resumed = false;
  // --resume with another run length than the archive's config (an extended run): the archive's
  // /config and config_hash are replaced by this run's when it starts.
  bool run_length_changed = false;
  // --resume of an archive whose last run did not complete: what happened to it, in the words
  // of master/run_state.hpp, for the start's console header.
  std::optional<std::string> previous_run;
  // Held from start-up to the end of the run (io/run_lock.hpp): no other run writes the archive.
  std::optional<io::RunLock> lock;
};

// Start-up: validates the output path, takes the run lock (a second run on the same archive
// fails here, naming the holder), loads the checkpoint for --resume (the experiment hash and
// the seed must match the archive's: a finished run can be extended with more generations),
// creates the population. Throws StartupError (nothing touched) or
// ConfigError. Writes nothing but the lock file.
PreparedRun prepare_run(const Config& config, const RunOptions& options, int ranks);
// The loop. Creates or updates the archive; throws RunError (the archive then holds the last
// consistent checkpoint; its state is set to "interrupted" when possible).
RunOutcome execute_run(PreparedRun& run, UnitExecutor& executor, ProgressReporter& progress);

// Helpers shared with the tools.
std::string iso8601_now();  // "2026-11-22T05:02:53Z"
std::string host_name();

}  // namespace softevo::master
