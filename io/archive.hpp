// Run archive `softevo.run/1` (HDF5): what a distributed run records, written by rank 0 only.
// The schema is documented in docs/archive.md; this header is its single implementation.
//
// Crash safety with a cost per generation that does not grow with the run (docs/archive.md
// "On disk"): while a run writes, RUN.h5 is a small root (run attributes, /config, /stats,
// /checkpoint) whose /generations/<G> are HDF5 external links to one segment file per
// generation in RUN.h5.d/, each written once. Every file is written whole to a temporary and
// renamed into place (common/safe_write.hpp): a new generation is its segment, then a new root
// that names it, so a kill at any instant leaves the previous root or the new one, both
// complete. finish_archive() packs everything into one self-contained RUN.h5 (one copy of the
// data per run) and removes RUN.h5.d/. The reader reads both forms, and archives of older
// builds (always self-contained).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/choice.hpp"
#include "common/strategy_report.hpp"

namespace softevo::io {

namespace h5 {
class File;
}

// Where a run is in its life, the root attribute `state` (docs/archive.md). `running` is also
// what a run that died without closing leaves; the run lock tells the two apart.
enum class RunState : std::uint8_t { running, complete, interrupted };

}  // namespace softevo::io
template <>
struct softevo::ChoiceNames<softevo::io::RunState> {
  static constexpr std::array<const char*, 3> names = {"running", "complete", "interrupted"};
};
namespace softevo::io {

inline constexpr const char* kArchiveFormat = "softevo.run/1";
// The component columns of an archive written before the columns were named (no attribute
// "columns" on /generations/G/components): six per work unit.
const std::vector<std::string>& legacy_component_columns();
// Columns of /stats: generation, best, mean, sd, species_count, evaluations_per_second.
inline constexpr int kStatsColumns = 6;

// What the schema allows (docs/archive.md "Limits"). The reader checks every extent, count and
// length against these before it allocates anything, so a flipped byte costs an error, not
// gigabytes; the writer refuses a generation beyond them (GenerationRecord::check), so it never
// writes an archive the reader would refuse.
struct ArchiveLimits {
  // Generations of a run (run.generations <= 10^7): /generations groups, /stats rows.
  static constexpr std::int64_t generations = 10'000'000;
  // Rows of a generation: twice the largest neat.pop_size (10^6), since spawn rounding and
  // rescue clones may exceed pop_size.
  static constexpr std::int64_t individuals = 2'000'000;
  static constexpr std::int64_t units = 4096;                  // work units per genome (directions)
  static constexpr std::int64_t component_columns = 64;        // last axis of components
  static constexpr std::int64_t genome_bytes = 1LL << 30;      // one genome (the wire's limit)
  static constexpr std::int64_t checkpoint_bytes = 1LL << 32;  // /checkpoint/population
  static constexpr std::int64_t config_bytes = 1LL << 20;      // /config text
  static constexpr std::int64_t string_bytes = 4096;           // any string attribute
  // Points of one learning curve: strategy iterations (<= 10^5, common/config.cpp) + 1.
  static constexpr std::int64_t learning_points = 100'001;
  // A search strategy's tables (/generations/G/strategy): columns of one table, and rows of
  // the MAP-Elites map (map_elites.max_cells <= 10^7, common/config_schema.cpp).
  static constexpr std::int64_t strategy_columns = 64;
  static constexpr std::int64_t map_cells = 10'000'000;
};
// Layout version of /generations/G/strategy (docs/archive.md), its attribute schema_version.
inline constexpr std::int64_t kStrategySchemaVersion = 1;

// A missing, unreadable, foreign or malformed archive, or a failed write; the message names the
// file, the object and the reason.
class ArchiveError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// reused_from of a row whose result was evaluated in its own generation.
inline constexpr std::int64_t kNotReused = -1;

// Root attributes of the archive.
struct RunInfo {
  std::string format = kArchiveFormat;
  std::string version;
  std::string git_commit;
  // physics/revision.hpp; an archive written before the attribute existed reads as 1
  std::int32_t physics_revision = 1;
  std::int64_t seed = 0;
  std::int32_t ranks = 1;  // (not part of the run's identity)
  // What ran it last: "softevo-mpi" (ranks are MPI ranks), "softevo evolve" or "softevo.evolve"
  // (ranks - 1 worker threads); read as "softevo-mpi" from archives written before it.
  // Not part of the run's identity.
  std::string program;
  std::string host;         // (not part of the run's identity)
  std::string start_time;   // ISO 8601 UTC (not part of the run's identity)
  std::string end_time;     // ISO 8601 UTC, "" while running
  std::string config_hash;  // 16 lower-case hex digits (hash_hex(config_hash(config)))
  // 16 hex digits, hash_hex(experiment_hash(config)): the config without run length and seed
  // (common/config.hpp). An archive written before the attribute existed reads it from /config.
  std::string experiment_hash;
  std::string experiment;  // "gait-open" | "gait-closed" | "dir-open" | "dir-closed"
  RunState state = RunState::running;
  std::int64_t generations_done = 0;
  // Why the run stopped on its own before its end (e.g. run.stop_after_failed_generations); ""
  // otherwise, and while running. Written only when set (older archives have none).
  std::string stop_reason;
};

// One evaluated generation: one row per individual, sorted by id.
struct GenerationRecord {
  std::int64_t generation = 0;
  std::vector<std::int64_t> id;
  std::vector<std::int64_t> parent1;  // -1: none
  std::vector<std::int64_t> parent2;  // -1: none
  std::vector<std::int64_t> species;
  std::vector<std::uint8_t> status;  // EvalStatus (common/eval_types.hpp)
  std::vector<double> fitness;
  std::vector<std::int32_t> voxels;
  std::vector<std::int32_t> chambers;
  std::vector<double> wall_seconds;       // [s] summed over the genome's work units
  std::vector<std::int32_t> worker_rank;  // rank that evaluated the first work unit
  // -1: evaluated in this generation; else the id of the row whose evaluation this row reuses
  // (same genome bytes, same config: master/result_reuse.hpp). Its wall_seconds are then 0 and
  // its worker_rank -1. Empty when writing = no row reused; an archive written before the
  // column existed reads as all -1.
  std::vector<std::int64_t> reused_from;
  std::vector<std::vector<std::uint8_t>> genome;  // evo::encode_genome bytes
  int units = 1;  // work units per genome (tasks::Task::units(): directed = directions)
  // Names of the components' last axis, in order (the task's: "fitness", its named components,
  // "status"; legacy_component_columns() for an archive that does not name them).
  std::vector<std::string> component_columns = legacy_component_columns();
  std::vector<double> components;  // row-major [n][units][component_columns.size()]
  // Controller learning (docs/model.md §8.11), all empty in a run without learning. Per row:
  // the fitness of the genome as created (`fitness` is the learned one), the evaluations spent
  // on the body (the born one included; a reused row repeats its origin's), the genome with
  // the learned controller (evo::encode_genome) and the best fitness so far after the born
  // evaluation and after every strategy iteration, row-major [n][learning_points].
  std::vector<double> fitness_before;
  std::vector<std::int64_t> learn_evaluations;
  std::vector<std::vector<std::uint8_t>> learned_genome;
  std::int64_t learning_points = 0;  // curve points per row (iterations + 1)
  std::vector<double> learning_curve;
  bool has_learning() const { return !fitness_before.empty(); }
  // A search strategy other than NEAT (docs/model.md §8.12): its per-row columns (one row per
  // row above), the MAP-Elites map after the generation and the generation's metrics, in the
  // group /generations/G/strategy; empty for NEAT (species are the columns above), and in
  // archives of earlier builds.
  StrategyReport strategy;
  // Group attributes.
  double best = 0.0;
  double mean = 0.0;
  double sd = 0.0;  // population standard deviation (divide by n)
  std::int64_t species_count = 0;
  std::int64_t evaluations = 0;    // work units evaluated (gait: n, directed: n x directions)
  double eval_wall_seconds = 0.0;  // [s] wall time of the evaluation phase

  std::size_t size() const { return id.size(); }
  // Throws ArchiveError if the columns have different lengths, ids are not ascending or a size
  // is beyond ArchiveLimits.
  void check() const;
};

struct StatsRow {
  double generation = 0.0;
  double best = 0.0;
  double mean = 0.0;
  double sd = 0.0;
  double species_count = 0.0;
  double evaluations_per_second = 0.0;  // (timing: not part of the run's identity)
};

// The population that continues the run: Population::serialize() after the last evaluated
// generation, i.e. the NEXT population; `generation` = its generation number = generations_done.
// With controller learning, the checkpoint within that generation after each completed learning
// round adds the learning's state (master/learning_rounds.hpp, docs/model.md §8.11), opaque
// here; empty = none (every checkpoint of a run without learning, and of older builds).
struct Checkpoint {
  std::int64_t generation = 0;
  std::vector<std::uint8_t> population;
  std::vector<std::uint8_t>
      learning{};  // {}: Checkpoint{generation, population} needs no third initializer (-Wextra)
};

// Population statistics of a fitness column (best = max, sd with divisor n; empty -> zeros).
struct FitnessStats {
  double best = 0.0;
  double mean = 0.0;
  double sd = 0.0;
};
FitnessStats fitness_stats(const std::vector<double>& fitness);

// ---- writing (rank 0 only; every call is atomic, see the file comment) -------------------------

// Fault injection, for tests only: called with a step name ("segment: create",
// "segment: /generations/000003", "root: /stats", "root: rename", "pack: /generations", ...)
// before every write step of an archive update. A hook that throws (e.g.
// std::system_error(ENOSPC)) makes that step fail as a full disk would; the update then fails
// like a real one (ArchiveError, temporary removed, archive unchanged). A hook that kills the
// process shows what a kill at that instant leaves. The pack's steps from "pack: create" to
// "pack: close" run in the pack's own child process (finish_archive): there the hook's effects
// stay in the child (a throw or a crash fails the pack). "root: reserve" grows the space kept
// for the stop's root; "reserved root: ..." are the steps of a stop's root written into it
// (update_run_info). Empty = no hook.
using WriteStepHook = std::function<void(const std::string& step)>;

// Throws ArchiveError unless the archive can be written at `path`: its directory exists and is
// writable, and `path` is absent or a regular file (not a directory, symlink, FIFO or device;
// common/safe_write.hpp). Touches nothing that exists.
void check_output_path(const std::string& path);
// New archive (a root) with root attributes, /config, an empty /stats and no generation.
void create_archive(const std::string& path, const RunInfo& info, const std::string& config_text,
                    const WriteStepHook& hook = {});
// Writes generation <G> as a segment, then a root that links it as /generations/<G>, with one
// more /stats row, the new /checkpoint and root attributes. `info.generations_done` should be
// record.generation + 1 (master/run.cpp counts a generation only once this call has
// succeeded). A self-contained archive becomes a root first (its file moves unchanged into
// RUN.h5.d/ as packed-<G>.h5, by a hard link where possible).
void append_generation(const std::string& path, const RunInfo& info, const GenerationRecord& record,
                       const StatsRow& stats, const Checkpoint& checkpoint,
                       const WriteStepHook& hook = {});
// Replaces /checkpoint and the root attributes: a checkpoint within the generation in flight
// (its controller learning's state after a round). `checkpoint.generation` and
// `info.generations_done` must equal the archive's generations_done (ArchiveError otherwise).
void update_checkpoint(const std::string& path, const RunInfo& info, const Checkpoint& checkpoint,
                       const WriteStepHook& hook = {});
// Replaces the root attributes (state changes, end time). `info.generations_done` must equal
// the archive's: a state change never claims generations (ArchiveError otherwise). A state
// other than "running" that cannot be written as a new root (a full disk) is written into the
// space every root write reserves for it (RUN.h5.d/reserved-root, as large as the root and
// 16 kB): the stop of a run is recorded on a disk with no block free (docs/archive.md).
void update_run_info(const std::string& path, const RunInfo& info, const WriteStepHook& hook = {});
// As update_run_info, and /config replaced by `config_text`: a run continued with another run
// length (--resume --generations N) records the config it now runs.
void update_run_config(const std::string& path, const RunInfo& info, const std::string& config_text,
                       const WriteStepHook& hook = {});
// Sets the root attributes (as update_run_info) and packs the archive into one self-contained
// file (every generation group copied as written), replacing the root atomically, then removes
// the segments and the reserved space. A failure leaves the archive as it was (consistent, in
// either form). Refused when the file system has no room for the copy; the copy is written by
// a forked child process (io/child_process.hpp), so a crash of libhdf5 there (another process
// filling the disk during the copy) is an ArchiveError naming the signal, not this process's.
void finish_archive(const std::string& path, const RunInfo& info, const WriteStepHook& hook = {});
// Removes what a writer killed in the middle of an update left behind: temporaries of dead
// processes beside `path` and in RUN.h5.d/, and segments the root does not reference (written
// before a root update that never happened, or left by a finish that was killed). Keeps
// everything when the root exists but cannot be read. Call it only under the run lock (io/
// run_lock.hpp). Returns how many files it removed.
int remove_archive_debris(const std::string& path);
// Removes the archive at `path` and its segments (a temporary archive that is not wanted).
void remove_archive(const std::string& path);

// ---- reading ---------------------------------------------------------------------------------

// Where the data of one generation is: `file` = "" when it is in the archive file itself (a
// finished archive), else the file its external link names (relative to the archive's
// directory, e.g. "run.h5.d/gen-000003.h5"), with `object` the group inside it.
struct GenerationStorage {
  std::int64_t generation = 0;
  std::string file;
  std::string object;
};

class Archive {
 public:
  // Opens read-only and checks the format attribute; throws ArchiveError.
  explicit Archive(const std::string& path);
  ~Archive();
  Archive(const Archive&) = delete;
  Archive& operator=(const Archive&) = delete;

  const std::string& path() const { return path_; }
  RunInfo info() const;
  std::string config_text() const;
  std::vector<std::int64_t> generations() const;  // ascending
  GenerationRecord generation(std::int64_t g) const;
  // The generation to take individual `id` from: `g` when given, else the last generation that
  // holds `id` (a MAP-Elites elite or a NEAT elite stays in later generations under its id).
  // ArchiveError when it is not there, naming the generations that hold it, or the span of the
  // ids when none does. Reads only the id column of each generation.
  std::int64_t generation_of(std::int64_t id, std::optional<std::int64_t> g = std::nullopt) const;
  std::vector<StatsRow> stats() const;
  std::optional<Checkpoint> checkpoint() const;
  // The `digest` attribute of /generations/<G> (generation_digest at write time); nullopt in
  // archives written before the attribute existed. Throws ArchiveError when it is malformed.
  std::optional<std::uint64_t> stored_generation_digest(std::int64_t g) const;
  // Where each generation is stored, ascending.
  std::vector<GenerationStorage> generation_storage() const;
  // Every generation is in the file itself (a finished archive, or one of an older build).
  bool self_contained() const;

 private:
  friend void finish_archive(const std::string&, const RunInfo&, const WriteStepHook&);
  // Throws a clear ArchiveError when generation `name`'s segment file is missing (HDF5 would
  // otherwise look for it relative to the working directory too).
  void require_segment(const std::string& name) const;
  std::string path_;
  std::unique_ptr<h5::File> file_;
};

// `path` is an HDF5 file whose root attribute `format` is kArchiveFormat. Throws only for a file
// that crashes libhdf5 (ArchiveError "damaged HDF5 file", io/open_probe.hpp): that is the answer.
bool is_run_archive(const std::string& path);

// FNV-1a 64 over every archived (generation, id, status, fitness bits), generations ascending,
// rows in id order, each field little-endian (i64, i64, u8, u64 bits). Equal digests = equal
// evolutionary outcomes, whatever the rank count or timing.
std::uint64_t fitness_digest(const Archive& archive);
// FNV-1a 64 over everything deterministic: config text and hash, seed, experiment, state,
// generations_done, every generation's columns except wall_seconds/worker_rank/reused_from
// (parents, species, status, fitness, voxels, chambers, components, genomes), the deterministic
// /stats columns and the checkpoint. Excludes version, git commit, host, ranks, times and timings.
std::uint64_t content_digest(const Archive& archive);

// FNV-1a 64 over every column and group attribute of one generation (timings included): the
// integrity digest stored at write time as the group's attribute `digest` (16 hex digits) and
// recomputed by master/archive_check.hpp. Not an identity: fitness_digest and content_digest
// are unchanged by it.
std::uint64_t generation_digest(const GenerationRecord& record);

// "000042"
std::string generation_group_name(std::int64_t generation);

}  // namespace softevo::io
