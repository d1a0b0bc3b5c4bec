// Progress reporter: observes the generation loop (docs/architecture.md §3: reporters, not
// print statements inside the loop). One line per evaluated generation on `out` (elapsed time,
// fitness with its unit, the count of each status), a warning on `warn` when a whole generation
// is killed or none of its robots moved, and a live line within the generation (carriage
// return, throttled to a few updates/s) where someone watches it (show_live_line).
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <optional>
#include <string>

#include "common/eval_types.hpp"

namespace softevo::master {

// EvalStatus values 0..invalid_body.
inline constexpr std::size_t kStatusKinds = static_cast<std::size_t>(EvalStatus::invalid_body) + 1;
using StatusCounts = std::array<std::int64_t, kStatusKinds>;  // genomes per EvalStatus

struct GenerationSummary {
  std::int64_t generation = 0;
  double best = 0.0;
  double mean = 0.0;
  std::int64_t species = 0;
  // A search strategy other than NEAT: its figures in place of the species (strategy_text of
  // master/generation_record.hpp); "" for NEAT.
  std::string search;
  std::int64_t evaluations = 0;     // work units simulated
  double eval_wall_seconds = 0.0;   // [s] evaluation phase
  double generation_seconds = 0.0;  // [s] whole generation incl. reproduction and archive
  StatusCounts status_counts{};     // the genomes' archived statuses
  double max_abs_ok_fitness = 0.0;  // largest |fitness| of an ok genome: 0 = nothing moved
  std::string fitness_unit;         // the task's ("cm", "rad")
  std::int64_t reused = 0;          // work units whose result was reused (not simulated)
  // Controller learning (docs/model.md §8.11): bodies that learned in this generation, the
  // strategy iterations each ran, and the mean and largest fitness gained by learning.
  std::int64_t learned_bodies = 0;
  std::int64_t learning_iterations = 0;
  double learning_gain_mean = 0.0;
  double learning_gain_best = 0.0;
};

// A learning round of a generation starts (the live line names it).
struct LearningProgress {
  std::int64_t iteration = 0;  // 1-based iteration of this round
  std::int64_t iterations = 0;
  std::size_t bodies = 0;  // bodies learning
  double gain_mean = 0.0;  // mean fitness gained so far
  double gain_best = 0.0;  // largest fitness gained so far
};

// The generation's line: "gen 3/10  best 1.6440 cm  mean ... ok 11 flipped 1 ... elapsed 12s
// ETA 28s". `elapsed_seconds` [s] since the run (or this resume) started.
std::string generation_line(const GenerationSummary& s, std::int64_t total_generations,
                            double elapsed_seconds, double eta_seconds);
// "ok 11, flipped 1, exploded 0, diverged 0, failed 0" (timeout and invalid body when present):
// the status names of `softevo info` and the archive docs.
std::string status_counts_text(const StatusCounts& counts);
// The warning for a generation whose numbers mean nothing ("" when fine): every genome killed
// (best and mean are then 0 by rule), or no ok genome with a fitness other than 0.
std::string generation_warning(const GenerationSummary& s);

// --progress: the live in-generation line.
enum class ProgressMode : std::uint8_t { automatic, always, never };
std::optional<ProgressMode> parse_progress_mode(const std::string& text);  // auto|always|never
// How rank 0's stderr is connected.
enum class StreamKind : std::uint8_t { terminal, pipe, other };
StreamKind stream_kind(int fd);
// For a pipe from an MPI launcher: where the launcher forwards it. The ranks' stderr is a pipe
// to mpirun (or orted), which writes what comes through to its own stderr: a terminal, or the
// log of `nohup mpirun ... > log 2>&1`, where carriage returns and ESC sequences are clutter.
// Follows the same descriptor up the ancestors (/proc/PID/fd) while it is a pipe; `pipe` when
// that cannot be told (another host's launcher, no /proc).
StreamKind forwarded_stream_kind(int fd);
// Whether to show the live line. auto: stderr is a terminal, or it is a pipe to an MPI launcher
// (Open MPI's mpirun: OMPI_COMM_WORLD_SIZE; PMIx: PMIX_RANK; MPICH/Hydra: PMI_RANK; srun:
// SLURM_STEP_ID) that forwards it to the user's terminal, i.e. not inside a batch job
// (Slurm's sbatch sets ENVIRONMENT=BATCH, PBS sets PBS_ENVIRONMENT=PBS_BATCH), whose output goes
// to a log file where carriage returns only clutter. `env` reads an environment variable
// (nullptr when unset).
bool show_live_line(ProgressMode mode, StreamKind stderr_kind,
                    const std::function<const char*(const char*)>& env);

class ProgressReporter {
 public:
  // `out` = nullptr: no generation lines (quiet); `live` = nullptr: no live line; `warn` =
  // nullptr: no warnings. `label` starts every line (several runs in one job name their archive).
  ProgressReporter(std::FILE* out, std::FILE* live, std::FILE* warn, std::int64_t total_generations,
                   std::string label = "");
  // A reporter that prints nothing.
  static ProgressReporter silent() { return ProgressReporter(nullptr, nullptr, nullptr, 0); }
  // A reporter that hands each generation line and warning, as the console would print them
  // (without the newline), to `sink` instead (Python prints them through sys.stdout).
  static ProgressReporter to_sink(std::int64_t total_generations,
                                  std::function<void(const std::string&)> sink);
  // stdout for the lines (none when quiet), stderr for the warnings and, as `mode` decides,
  // the live line. `label` as for the constructor.
  static ProgressReporter console(std::int64_t total_generations, ProgressMode mode, bool quiet,
                                  std::string label = "");

  void generation_started(std::int64_t generation, std::size_t units_total);
  void unit_done(std::size_t units_done, std::size_t units_total);
  // The generation's next learning round: the live line then reads "gen 3 learn 2/10: ...".
  void learning_started(const LearningProgress& round);
  void generation_finished(const GenerationSummary& s);
  void message(const char* text);  // a free-form line (clears the live line first)
  // The program that starts each warning line ("softevo-mpi" unless set).
  void set_program(std::string program) { program_ = std::move(program); }

 private:
  void clear_live();
  std::FILE* out_;
  std::FILE* live_;
  std::FILE* warn_;
  std::string label_;
  std::string program_ = "softevo-mpi";
  std::function<void(const std::string&)> sink_;
  std::int64_t total_generations_;
  std::int64_t generation_ = 0;
  std::int64_t generations_reported_ = 0;
  double seconds_reported_ = 0.0;  // sum of generation_seconds, for the ETA
  bool live_visible_ = false;
  std::optional<LearningProgress> round_;  // the learning round in flight, if any
  std::chrono::steady_clock::time_point round_start_;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point generation_start_;
  std::chrono::steady_clock::time_point last_live_;
};

// "1h02m", "3m05s", "12s"
void format_duration(double seconds, char* buf, std::size_t size);

}  // namespace softevo::master
