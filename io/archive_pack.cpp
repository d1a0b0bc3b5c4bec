// Finishing a run archive (docs/archive.md "On disk: while running, once finished"): the root
// and its segments packed into one self-contained RUN.h5, in a child process, only when the
// disk has room for the copy; the segments are removed afterwards.
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "common/safe_write.hpp"
#include "io/archive.hpp"
#include "io/archive_internal.hpp"
#include "io/archive_writer_internal.hpp"
#include "io/child_process.hpp"
#include "io/h5.hpp"

namespace softevo::io {
namespace {

namespace fs = std::filesystem;
using namespace detail;
using h5::Charset;

// The bytes a pack of `source` (at `path`) may write: the root and every file it links. The
// packed file holds the same groups, so it is no larger than that, give or take HDF5's headers.
std::uint64_t bytes_to_pack(const std::string& path, const Archive& source) {
  std::error_code ec;
  std::uint64_t total = fs::file_size(path, ec);
  std::vector<std::string> counted;
  for (const GenerationStorage& s : source.generation_storage()) {
    if (s.file.empty() || std::find(counted.begin(), counted.end(), s.file) != counted.end())
      continue;
    counted.push_back(s.file);
    const std::uintmax_t size = fs::file_size(fs::path(directory_of(path)) / s.file, ec);
    if (!ec) total += size;
  }
  return total;
}

// Refuses to pack when the file system of `path` cannot take the packed copy. libhdf5 1.10
// crashed (SIGSEGV in H5Ocopy) when the disk filled during the copy (issue 29); a write that is
// never started cannot fail there, and the archive stays readable as a root with segments.
// Returns the bytes the pack wants free.
std::uint64_t require_room_to_pack(const std::string& path, const Archive& source) {
  // HDF5's own overhead (headers, free-space tracking, the checkpoint) on top of the groups.
  constexpr std::uint64_t kMarginBytes = std::uint64_t{64} << 10;
  const std::uint64_t needed = bytes_to_pack(path, source);
  const std::uint64_t wanted = needed + needed / 8 + kMarginBytes;
  const std::string dir = directory_of(path);
  const std::uint64_t free_bytes = free_bytes_in(dir);
  if (free_bytes < wanted)
    throw ArchiveError(path + ": not packed into one file: " + std::strerror(ENOSPC) + ": " + dir +
                       " has " + std::to_string(free_bytes) + " bytes free, the pack needs about " +
                       std::to_string(wanted));
  return wanted;
}

// The packed archive written to `temp`: every group of `source` copied as written.
// `from` = the source's /generations.
void write_packed(const std::string& temp, const std::string& path, const Archive& source,
                  const h5::Group& from, const RunInfo& info, const PartSteps& step) {
  step("create");
  // Persistent free-space tracking: an older build that continues this archive edits it in
  // place, and reuses the space of each replaced /checkpoint.
  h5::PropertyList creation = h5::PropertyList::file_creation();
  creation.persist_free_space();
  h5::File file = h5::File::create(temp, &creation, path);
  step("attributes");
  write_run_info(file, info);
  step("/config");
  file.write_string_dataset("config", source.config_text(), Charset::utf8);
  step("/stats");
  write_stats(file, source.stats());
  step("/generations");
  const h5::Group to = file.create_group("generations");
  // Object copies (links followed): every byte and attribute of a group as written, the digest
  // included, so the integrity checks still see what the run wrote.
  for (const std::int64_t g : source.generations())
    from.copy_object(generation_group_name(g), to, generation_group_name(g));
  if (const std::optional<Checkpoint> cp = source.checkpoint()) {
    step("/checkpoint");
    write_checkpoint(file, *cp);
  }
  step("flush");
  file.flush();
  step("close");
  file.close();
}

}  // namespace

void finish_archive(const std::string& path, const RunInfo& info, const WriteStepHook& hook) {
  const WriteSteps steps(hook);
  archive_update(path, [&] {
    const PartSteps step(steps, "pack");
    {
      const Archive source(path);
      const std::uint64_t wanted = require_room_to_pack(path, source);
      RootContent c;
      c.info = source.info();
      require_generations_done(path, c, info);
      AtomicOutput out(path, Overwrite::replace);
      // In a child process: libhdf5 1.10 crashed (SIGSEGV in H5Ocopy) when another process
      // filled the disk during the copy (issue 29). A crash there costs the pack, not the run:
      // the half-written temporary is removed, the archive stays as it was (root and segments).
      const h5::Group from = source.file_->open_group("generations");
      const std::string failure = run_in_child(
          "the pack", [&] { write_packed(out.temp_path(), path, source, from, info, step); });
      if (!failure.empty()) {
        const std::string dir = directory_of(path);
        const std::uint64_t free_bytes = free_bytes_in(dir);
        throw ArchiveError(
            path + ": not packed into one file: " + failure +
            (free_bytes < wanted
                 ? "; the disk filled during the pack (" + std::string(std::strerror(ENOSPC)) +
                       ": " + dir + " has " + std::to_string(free_bytes) +
                       " bytes free, the pack needs about " + std::to_string(wanted) + ")"
                 : std::string()) +
            "; the archive is kept as it was, readable as a root with its segments");
      }
      out.commit(step.commit_hook());
    }
    // The root is self-contained now: the segments are unreferenced (a kill here leaves them
    // for the next start to remove).
    step("remove segments");
    std::error_code ec;
    fs::remove(reserved_root_path(path), ec);  // a packed archive records no stop any more
    remove_unreferenced_segments(path);
  });
}

}  // namespace softevo::io
