// The run archive's writer (docs/archive.md "On disk: while running, once finished"): the
// public writes (create, append a generation as a segment file, update the root, remove) and
// the full-disk diagnosis of a failed one. Its parts: io/archive_writer_internal.hpp.
#include <sys/stat.h>
#include <sys/statvfs.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <optional>
#include <string>

#include "common/safe_write.hpp"
#include "io/archive.hpp"
#include "io/archive_internal.hpp"
#include "io/archive_writer_internal.hpp"

namespace softevo::io {

namespace detail {

// The bytes an unprivileged writer may still take in `directory`'s file system; the maximum
// when unknown (statvfs failed: the writes' own errors will say). `no_inode`: set when no
// file can be created there any more.
std::uint64_t free_bytes_in(const std::string& directory, bool* no_inode) {
  struct statvfs vfs {};
  if (::statvfs(directory.c_str(), &vfs) != 0) return UINT64_MAX;
  if (no_inode != nullptr) *no_inode = vfs.f_favail == 0;
  return static_cast<std::uint64_t>(vfs.f_bavail) * static_cast<std::uint64_t>(vfs.f_frsize);
}

// When a write into `directory` failed, the reason HDF5 reports is often generic ("file write
// failed", "flush failed", "Input/output error"): it does not pass errno on. A full file system
// is by far the most common cause and the one the user must act on, so say so when it is the
// case (less than kLowSpaceBytes left for the writer).
std::string with_space_diagnosis(const std::string& message, const std::string& directory) {
  constexpr std::uint64_t kLowSpaceBytes = 1 << 20;
  if (message.find(std::strerror(ENOSPC)) != std::string::npos) return message;
  bool no_inode = false;
  const std::uint64_t free_bytes = free_bytes_in(directory, &no_inode);
  if (free_bytes >= kLowSpaceBytes && !no_inode) return message;
  return message + " (" + std::strerror(ENOSPC) + ": " + directory + " has " +
         std::to_string(free_bytes) + " bytes free)";
}

}  // namespace detail

namespace {

namespace fs = std::filesystem;
using namespace detail;

// A new root with new attributes (and /config or /checkpoint, when given): the state changes
// of a run, and its checkpoints within a generation. A state that ends the run (not
// `running`), when its root cannot be written as a new file (a full disk), goes into the space
// reserved for it.
void update_root(const std::string& path, const RunInfo& info,
                 const std::optional<std::string>& config_text, const Checkpoint* checkpoint,
                 const WriteStepHook& hook) {
  const WriteSteps steps(hook);
  archive_update(path, [&] {
    RootContent c = read_root(path, checkpoint == nullptr);
    require_generations_done(path, c, info);
    keep_generation_data_apart(path, c, steps);
    c.info = info;
    if (config_text) c.config_text = *config_text;
    if (checkpoint) c.checkpoint = *checkpoint;
    const bool ends_the_run =
        info.state != RunState::running && !config_text && checkpoint == nullptr;
    try {
      write_root(path, c, steps);
    } catch (const std::exception& e) {
      struct stat st {};
      if (!ends_the_run || ::lstat(reserved_root_path(path).c_str(), &st) != 0) throw;
      try {
        write_root_into_reserve(path, c, steps);
      } catch (const std::exception& reserved) {
        throw ArchiveError(std::string(e.what()) +
                           "; nor into the space reserved for it: " + reserved.what());
      }
    }
  });
}

}  // namespace

void create_archive(const std::string& path, const RunInfo& info, const std::string& config_text,
                    const WriteStepHook& hook) {
  const WriteSteps steps(hook);
  archive_update(path, [&] {
    RootContent c;
    c.info = info;
    c.config_text = config_text;
    write_root(path, c, steps);
  });
}

void append_generation(const std::string& path, const RunInfo& info, const GenerationRecord& record,
                       const StatsRow& stats, const Checkpoint& checkpoint,
                       const WriteStepHook& hook) {
  record.check();
  const WriteSteps steps(hook);
  archive_update(path, [&] {
    RootContent c = read_root(path, false);
    const std::string name = "/generations/" + generation_group_name(record.generation);
    for (const GenerationStorage& s : c.generations)
      if (s.generation == record.generation)
        throw ArchiveError(path + ": " + name + " already exists");
    keep_generation_data_apart(path, c, steps);
    // The segment first: until the root names it, it is an unreferenced file that a kill leaves
    // behind and the next start removes.
    c.generations.push_back(write_segment(path, record, steps));
    c.stats.push_back(stats);
    c.checkpoint = checkpoint;
    c.info = info;
    write_root(path, c, steps);
  });
}

void update_run_info(const std::string& path, const RunInfo& info, const WriteStepHook& hook) {
  update_root(path, info, std::nullopt, nullptr, hook);
}

void update_run_config(const std::string& path, const RunInfo& info, const std::string& config_text,
                       const WriteStepHook& hook) {
  update_root(path, info, config_text, nullptr, hook);
}

void update_checkpoint(const std::string& path, const RunInfo& info, const Checkpoint& checkpoint,
                       const WriteStepHook& hook) {
  if (checkpoint.generation != info.generations_done)
    throw ArchiveError(path + ": a checkpoint for generation " +
                       std::to_string(checkpoint.generation) +
                       " with generations_done = " + std::to_string(info.generations_done));
  update_root(path, info, std::nullopt, &checkpoint, hook);
}

int remove_archive_debris(const std::string& path) {
  return remove_stale_temporaries(path) + remove_unreferenced_segments(path);
}

void remove_archive(const std::string& path) {
  std::error_code ec;
  fs::remove(path, ec);
  remove_unreferenced_segments(path);
}

}  // namespace softevo::io
