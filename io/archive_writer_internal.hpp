// The run archive writer's internals (docs/archive.md "On disk while running, once finished"),
// shared by its files, one concept each:
//   archive_writer.cpp    the public writes: create, append a generation, state changes,
//                         removal; the full-disk diagnosis of every failed write;
//   archive_groups.cpp    what the run attributes, /stats, /checkpoint and a generation hold;
//   archive_root.cpp      the small root file and the space reserved for the stop's root;
//   archive_segments.cpp  the segment directory: one file per generation, a continued packed
//                         archive kept apart, unreferenced files removed;
//   archive_pack.cpp      finishing: everything packed into one self-contained file.
// Not for use outside io/.
#pragma once

#include <algorithm>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "common/safe_write.hpp"
#include "io/archive.hpp"
#include "io/archive_internal.hpp"
#include "io/h5.hpp"

namespace softevo::io::detail {

// ---- write steps (the fault-injection hook of archive.hpp) ----------------------------------

// Calls the fault-injection hook (archive.hpp) before a write step.
class WriteSteps {
 public:
  explicit WriteSteps(const WriteStepHook& hook) : hook_(hook) {}
  void operator()(const std::string& step) const {
    if (hook_) hook_(step);
  }

 private:
  const WriteStepHook& hook_;
};

// Steps of one file's write, named "<part>: <step>" for the fault-injection hook.
class PartSteps {
 public:
  PartSteps(const WriteSteps& steps, std::string part) : steps_(steps), part_(std::move(part)) {}
  void operator()(const std::string& step) const { steps_(part_ + ": " + step); }
  CommitStepHook commit_hook() const {
    return [this](const std::string& step) { (*this)(step); };
  }

 private:
  const WriteSteps& steps_;
  std::string part_;
};

// ---- the full-disk diagnosis (archive_writer.cpp) -------------------------------------------

// The bytes an unprivileged writer may still take in `directory`'s file system; the maximum
// when unknown (statvfs failed: the writes' own errors will say). `no_inode`: set when no
// file can be created there any more.
std::uint64_t free_bytes_in(const std::string& directory, bool* no_inode = nullptr);

// When a write into `directory` failed, the reason HDF5 reports is often generic ("file write
// failed", "flush failed", "Input/output error"): it does not pass errno on. A full file system
// is by far the most common cause and the one the user must act on, so say so when it is the
// case (less than kLowSpaceBytes left for the writer).
std::string with_space_diagnosis(const std::string& message, const std::string& directory);

// Runs `body` with every failure as an ArchiveError naming `path`, and the full-disk diagnosis.
template <typename Body>
void archive_update(const std::string& path, Body&& body) {
  try {
    archive_errors([&] {
      try {
        body();
      } catch (const OutputFileError& e) {
        throw ArchiveError(e.what());
      }
    });
  } catch (const ArchiveError& e) {
    throw ArchiveError(with_space_diagnosis(e.what(), directory_of(path)));
  }
}

// ---- the root (archive_root.cpp) ------------------------------------------------------------

// What the root file holds besides the generations' data.
struct RootContent {
  RunInfo info;
  std::string config_text;
  std::vector<StatsRow> stats;
  std::vector<GenerationStorage> generations;  // ascending
  std::optional<Checkpoint> checkpoint;
  bool holds_generation_data() const {
    return std::any_of(generations.begin(), generations.end(),
                       [](const GenerationStorage& s) { return s.file.empty(); });
  }
};

// The root at `path` as it is (ArchiveError when it does not exist), its checkpoint when asked.
RootContent read_root(const std::string& path, bool with_checkpoint);

// A state change may not change generations_done (ArchiveError naming both counts).
void require_generations_done(const std::string& path, const RootContent& c, const RunInfo& info);

// The new, small root, written whole to a temporary and renamed over `path` (its size does not
// depend on the data of the generations, only on their count: one link and one /stats row
// each). Before the rename, the reserved space grows to hold a root of its size.
void write_root(const std::string& path, const RootContent& c, const WriteSteps& steps);

// The small root written into the reserved space and renamed over `path`: built in memory, its
// bytes overwrite the reserved file's allocated ones (ArchiveError when it does not fit), the
// file is cut to the root's size and renamed. Atomic as write_root; the reservation is used up.
void write_root_into_reserve(const std::string& path, const RootContent& c,
                             const WriteSteps& steps);

// The file in RUN.h5.d/ that holds the space reserved for the stop's root.
std::string reserved_root_path(const std::string& path);

// ---- the segment directory (archive_segments.cpp) -------------------------------------------

// RUN.h5.d beside RUN.h5.
std::string segment_directory(const std::string& path);
// The segment directory of `path`, created if needed; a symlink or non-directory there is
// refused (the archive never writes through a link).
std::string make_segment_directory(const std::string& path);

// Writes the segment of one generation (written once, never edited) and returns its link.
GenerationStorage write_segment(const std::string& path, const GenerationRecord& record,
                                const WriteSteps& steps);

// A root that still holds generation data (a finished archive being continued, or one written
// by an older build) becomes a small root first: the file as it is moves, unchanged, into the
// segment directory as packed-<n>.h5 (a hard link: no byte is copied; a copy where the file
// system has no hard links), and its generations become links into it.
void keep_generation_data_apart(const std::string& path, RootContent& c, const WriteSteps& steps);

// Removes the segment directory's files that the root at `path` does not reference (all of
// them when `path` references none, e.g. a finished archive), stale temporaries included, and
// the directory once empty. Nothing is removed when the root exists but cannot be read.
int remove_unreferenced_segments(const std::string& path);

// ---- the groups (archive_groups.cpp) --------------------------------------------------------

// The root attributes (docs/archive.md "Root attributes").
void write_run_info(const h5::File& file, const RunInfo& info);
// /stats: one row per generation.
void write_stats(const h5::File& file, const std::vector<StatsRow>& rows);
// /checkpoint: the population (and learning) state to continue from.
void write_checkpoint(const h5::File& file, const Checkpoint& checkpoint);
// /generations/G: one row per individual, the strategy group, and the generation's digest.
void write_generation_group(const h5::Group& parent, const std::string& name,
                            const GenerationRecord& record);

}  // namespace softevo::io::detail
