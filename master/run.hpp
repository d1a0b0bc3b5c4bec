// The generation loop of a distributed run, MPI-free (docs/model.md §8.1, §8.10, §8.12):
//   members = strategy.ask()                 (generation g, immigrants included)
//   evaluate every work unit                 (UnitExecutor: in-process or over MPI)
//   strategy.tell(results), archive generation g with the strategy's report, checkpoint the
//   strategy's NEXT state
//                                            (io/archive.hpp: its segment, then a new root)
//   at the end (or a stop): pack the archive into one file
// The MPI master driver (master/mpi_driver.cpp) only supplies an executor that farms the units
// out to worker ranks; everything else is here and is tested without MPI.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/available_memory.hpp"
#include "common/config.hpp"
#include "common/eval_types.hpp"
#include "evo/search_strategy.hpp"
#include "io/archive.hpp"
#include "io/run_lock.hpp"
#include "master/learning_rounds.hpp"
#include "master/progress.hpp"
#include "master/result_reuse.hpp"
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

// One generation in flight: the run it belongs to (its index in execute_runs), its units and
// how a unit becomes a request.
struct ActiveGeneration {
  std::size_t run = 0;
  GenerationScheduler* scheduler = nullptr;
  std::function<EvalRequest(const WorkUnit&)> request;
  ProgressReporter* progress = nullptr;  // the run's reporter (unit_done)
};

// Evaluates work units of the generations in flight.
class UnitExecutor {
 public:
  virtual ~UnitExecutor() = default;
  virtual int ranks() const = 0;
  // Hands out units of `generations` (oldest first: the earlier ones before the later ones) and
  // stores every result in its scheduler, until one generation is done; returns its run. Units
  // of other generations may stay in flight across calls (the caller then passes those
  // generations again, the finished one replaced by its run's next one at the end). Returns
  // nothing if a stop-now request (SIGTERM) interrupted it; the partial results are then
  // discarded by the caller. Reports progress.
  virtual std::optional<std::size_t> evaluate_any(
      const std::vector<ActiveGeneration>& generations) = 0;
};

// Single-rank executor: the master evaluates by itself (also the test stand-in).
class LocalExecutor : public UnitExecutor {
 public:
  using EvaluateFn = std::function<EvalResult(const EvalRequest&)>;
  explicit LocalExecutor(EvaluateFn evaluate) : evaluate_(std::move(evaluate)) {}
  int ranks() const override { return 1; }
  std::optional<std::size_t> evaluate_any(
      const std::vector<ActiveGeneration>& generations) override;

 private:
  EvaluateFn evaluate_;
};

// How the messages of a start name the caller's options: the command line's by default; Python
// (softevo.evolve) names its keyword arguments instead (issue 39: it said "pass --resume").
struct OptionNames {
  std::string resume = "--resume", overwrite = "--overwrite", out = "--out",
              generations = "--generations", config = "--config", overrides = "the overrides";
  static OptionNames python() {
    return {
        "resume=True", "overwrite=True", "out=", "generations=", "changes to config", "overrides="};
  }
};

// The search strategy a run archive's config text names ("neat" for a text without one).
std::string archived_strategy(const std::string& config_text);
// Throws StartupError: `out`, evolved by strategy `archived`, was asked to continue with
// `wanted`; a run keeps its strategy (the message names the options to leave out).
[[noreturn]] void refuse_other_strategy(const std::string& out, const std::string& archived,
                                        const std::string& wanted, const OptionNames& names);

struct RunOptions {
  std::string out_path;
  OptionNames names;                    // for the messages
  std::string program = "softevo-mpi";  // io::RunInfo::program
  bool resume = false;                  // continue `out_path` if it exists (a new run otherwise)
  bool overwrite = false;  // replace an existing `out_path` (at the first archive write)
  std::string host;        // "" = gethostname()
  // Throughput (docs/scaling.md); neither changes a result bit. Off = the schedule of earlier
  // builds, for measuring against it.
  bool reuse_results = true;  // a genome evaluated before takes that result (result_reuse.hpp)
  bool longest_first = true;  // hand out the units predicted to take longest first
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
  // The search strategy (evo/search_strategy.hpp, search.strategy): NEAT's population, the
  // MAP-Elites map or the AFPO population, with the members of the next generation.
  std::unique_ptr<evo::SearchStrategy> population;
  bool already_complete = false;
  // --resume of a complete, packed archive on storage this process may not write: nothing is
  // written, no lock is taken.
  bool read_only = false;
  bool resumed = false;
  // --resume with another run length than the archive's config (an extended run): the archive's
  // /config and config_hash are replaced by this run's when it starts.
  bool run_length_changed = false;
  // --resume of an archive whose last run did not complete: what happened to it, in the words
  // of master/run_state.hpp, for the start's console header.
  std::optional<std::string> previous_run;
  // Held from start-up to the end of the run (io/run_lock.hpp): no other run writes the archive.
  std::optional<io::RunLock> lock;
  // The results of the latest archived generation (rebuilt from the archive on --resume).
  ResultMemory memory;
  // --resume of an archive checkpointed within a learning generation: that generation's
  // controller learning after its last completed round, which the run continues.
  std::optional<GenerationLearning> learning;
  // The archived statuses of the generations this start evaluated, counted by EvalStatus: a run
  // none of whose robots was ever ok ends with an error (run_driver.hpp), as one whose
  // generations all failed does.
  StatusCounts statuses_this_start{};
};

// Resource checks (master/run_limits.cpp).
// Descriptors a job needs beside one run lock per run: this process's configs, the archive
// files open while one is written, HDF5's probe pipes, stdio (MPI's are counted as open).
inline constexpr std::size_t kDescriptorsBesideRunLocks = 64;
// The open file descriptors a job of `runs` runs needs (each holds its run lock throughout).
std::size_t descriptors_for_runs(std::size_t runs);
// Makes RLIMIT_NOFILE hold a job of `runs` runs, raising the soft limit up to the hard one if
// that suffices; throws StartupError naming the limit and the number needed otherwise. Call
// before any run is prepared: a job that cannot hold its locks must not take any.
void reserve_descriptors(std::size_t runs);

// Memory of a run's master before and during its generations (rank 0 holds the population,
// its genomes, the work units of a generation and their results): measured at about 9.3 kB
// per member with the quickstart config (lattices 6^3 and 10^3 alike: bodies are built by the
// workers, one at a time), rounded up; a learning generation holds `learning.population`
// candidate controllers per member besides (each a genome and its work unit): measured, peak
// RSS of `softevo evolve -j 1` with 100 members, one generation, one learning iteration
// (task.eval_seconds = 0.01), at 4, 16 and 64 candidates: gait-open-learn 28.8, 36.7 and
// 66.2 MB (a fit of 6.2 KiB per candidate per member), gait-closed-learn 30.0 and 39.2 MB at 4
// and 16 (7.7 KiB: its controllers have more genes); rounded up to 8 KiB (it was 2 KiB,
// unmeasured; issue 29). An estimate, not a bound.
inline constexpr std::uint64_t kRunBaseBytes = std::uint64_t{32} << 20;
inline constexpr std::uint64_t kBytesPerMember = 10 * 1024;
inline constexpr std::uint64_t kBytesPerLearningCandidate = 8 * 1024;
std::uint64_t estimate_run_memory(const Config& config);
// Refuses (StartupError naming the keys to lower) a job of `configs` whose estimated memory
// exceeds `available`, and returns a warning text when it takes more than 3/4 of it ("" else).
std::string check_run_memory(const std::vector<const Config*>& configs,
                             const std::optional<AvailableMemory>& available);

// Start-up (master/run_start.cpp): validates the output path, takes the run lock (a second run on
// the same archive fails here, naming the holder), loads the checkpoint for --resume (the
// experiment hash and the seed must match the archive's: a finished run can be extended with more
// generations), creates the population. Throws StartupError (nothing touched) or ConfigError.
// Writes nothing but the lock file, which a failure removes again if it created it.
PreparedRun prepare_run(const Config& config, const RunOptions& options, int ranks);
// The end of a prepared run whose every generation is archived but whose end was not recorded
// (killed before it, or a full disk then): state complete, packed. RunError on failure.
void finish_complete_run(PreparedRun& run);
// The loop. Creates or updates the archive; throws RunError (the archive then holds the last
// consistent checkpoint; its state is set to "interrupted" when possible).
RunOutcome execute_run(PreparedRun& run, UnitExecutor& executor, ProgressReporter& progress);
// Several runs in one worker pool (softevo-mpi --seeds): each run's generation loop as in
// execute_run, their generations in flight at once, so the pool stays busy across each run's
// barrier. Each archive is the one execute_run writes for that run alone (results are stored
// by id, and nothing of a run depends on another). A stop-now drops every generation in
// flight; one run's error marks every archive interrupted and is thrown. One outcome per run;
// `progress`: one reporter per run.
std::vector<RunOutcome> execute_runs(const std::vector<PreparedRun*>& runs, UnitExecutor& executor,
                                     const std::vector<ProgressReporter*>& progress);

// One run's generation loop in steps (execute_runs drives several). Every step that fails marks
// the archive interrupted (best effort) and throws RunError.
class RunLoop {
 public:
  RunLoop(PreparedRun& run, int ranks, ProgressReporter& progress);
  ~RunLoop();
  RunLoop(const RunLoop&) = delete;
  RunLoop& operator=(const RunLoop&) = delete;

  // Creates the archive (a new run) or marks it running again (--resume).
  void open();
  bool finished() const;  // every generation of run.generations evaluated
  // The next generation's units (members whose result is reused are not among them), handed
  // out longest first unless RunOptions::longest_first is off. Requires !finished().
  GenerationScheduler& begin_generation();
  EvalRequest request(const WorkUnit& unit) const;
  ProgressReporter& progress() const { return progress_; }
  // After every unit of the scheduler has its result: with controller learning on, the next
  // learning round of the generation (master/learning_rounds.hpp) in the same scheduler, or
  // nullptr when the generation is complete (always nullptr without learning).
  GenerationScheduler* continue_generation();
  // After every unit of the generation has its result: archives it, reproduces, checkpoints.
  void end_generation();
  // Records the final state (complete or interrupted) and packs the archive.
  RunOutcome close(RunOutcome outcome);
  // Marks the archive interrupted, best effort (after an error elsewhere).
  void mark_interrupted() noexcept;

 private:
  template <class Step>
  void guarded(const Step& step);
  // The generation's learning after a completed round into the archive's checkpoint (a kill
  // from here on loses no round before it), then its next round in a new scheduler.
  void checkpoint_learning();
  void start_learning_round();
  // RunError naming the first failed unit of `scheduler` under run.on_failure = "abort".
  void check_failures(const GenerationScheduler& scheduler) const;
  // Learning's inheritance, then the population's next generation from the rows' fitness;
  // RunError when reproduction fails.
  void reproduce(const io::GenerationRecord& rec);
  // RunError (recorded as the archive's stop_reason) after run.stop_after_failed_generations
  // generations in a row in which no evaluation succeeded; `evaluated` gives the first cause.
  void check_failed_generations(const io::GenerationRecord& rec,
                                const std::vector<GenomeOutcome>& evaluated);

  using Clock = std::chrono::steady_clock;
  PreparedRun& run_;
  ProgressReporter& progress_;
  std::unique_ptr<tasks::Task> task_;
  std::vector<std::vector<std::uint8_t>> encoded_;  // members' genomes, member order
  ReusePlan plan_;
  std::vector<double> costs_;  // predicted cost per evaluated member (empty: member order)
  std::optional<GenerationScheduler> scheduler_;
  // Controller learning of the generation in flight (learning.method != none).
  std::optional<GenerationLearning> learning_;
  std::size_t units_before_ = 0;  // units simulated in the generation's finished rounds
  Clock::time_point t_generation_;
  Clock::time_point t_eval_;
  bool archive_written_ = false;
  bool state_recorded_ = false;
  std::int64_t failed_generations_ = 0;  // generations in a row without one successful evaluation
};

// Helpers shared with the tools.
std::string iso8601_now();  // "2026-11-22T05:02:53Z"
std::string host_name();

}  // namespace softevo::master
