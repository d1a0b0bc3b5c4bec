// The run archive's small root (docs/archive.md "On disk: while running, once finished"): run
// attributes, /config, /stats, a link per generation and /checkpoint, written whole and renamed
// over RUN.h5; and the space reserved beside it for the root that records a run's stop.
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "common/safe_write.hpp"
#include "io/archive.hpp"
#include "io/archive_internal.hpp"
#include "io/archive_writer_internal.hpp"
#include "io/h5.hpp"

namespace softevo::io::detail {
namespace {

namespace fs = std::filesystem;
using h5::Charset;

// The space kept for the root that records a run's stop (docs/archive.md "What survives which
// fault"): a failed write usually means a full disk, and the new root with state `interrupted`
// then had no room beside the old one until the rename (issue 29: 4 of 31 packed full-disk scan
// sizes left an archive `running`). Every root write first makes sure this file, in RUN.h5.d/,
// holds at least as many allocated bytes as the new root plus kStopRootMarginBytes; a state
// change that ends the run and finds no room writes its root into these bytes (no new block is
// needed to overwrite allocated ones) and renames the file over the root.
constexpr const char* kReservedRootName = "reserved-root";
// What the stop's root may take beyond the root it replaces: the same groups with state, end
// time and a stop reason (attributes of at most ArchiveLimits::string_bytes each, in HDF5's
// global heap collections of at least 4 kB).
constexpr std::uint64_t kStopRootMarginBytes = std::uint64_t{16} << 10;

// Grows the reserved file of `path` to at least `root_bytes` + kStopRootMarginBytes allocated
// bytes (posix_fallocate: allocated, not a sparse hole); never shrinks it.
void reserve_stop_root(const std::string& path, std::uint64_t root_bytes) {
  const std::string reserve = make_segment_directory(path) + "/" + kReservedRootName;
  const std::uint64_t wanted = root_bytes + kStopRootMarginBytes;
  const int fd = ::open(reserve.c_str(), O_RDWR | O_CREAT | O_NOFOLLOW | O_CLOEXEC, 0644);
  if (fd < 0)
    throw ArchiveError(
        reserve + ": cannot open the space reserved for the stop's root: " + std::strerror(errno));
  struct stat st {};
  int error = ::fstat(fd, &st) != 0 ? errno : 0;
  if (error == 0 && static_cast<std::uint64_t>(st.st_size) < wanted)
    error = ::posix_fallocate(fd, 0, static_cast<off_t>(wanted));
  ::close(fd);
  if (error != 0)
    throw ArchiveError(reserve + ": cannot reserve " + std::to_string(wanted) +
                       " bytes for the root that records the run's stop: " + std::strerror(error));
}

// The content of a small root (run attributes, /config, /stats, a link per generation,
// /checkpoint) written into `file`.
void fill_root(h5::File& file, const std::string& path, const RootContent& c,
               const PartSteps& step) {
  step("attributes");
  write_run_info(file, c.info);
  step("/config");
  file.write_string_dataset("config", c.config_text, Charset::utf8);
  step("/stats");
  write_stats(file, c.stats);
  step("/generations");
  const h5::Group generations = file.create_group("generations");
  for (const GenerationStorage& s : c.generations) {
    if (s.file.empty())
      throw ArchiveError(path + ": internal error: generation " + std::to_string(s.generation) +
                         " has no segment");
    generations.create_external_link(generation_group_name(s.generation), {s.file, s.object});
  }
  if (c.checkpoint) {
    step("/checkpoint");
    write_checkpoint(file, *c.checkpoint);
  }
  step("flush");
  file.flush();
}

}  // namespace

RootContent read_root(const std::string& path, bool with_checkpoint) {
  if (!fs::exists(path)) throw ArchiveError(path + ": archive does not exist");
  const Archive archive(path);
  RootContent c;
  c.info = archive.info();
  c.config_text = archive.config_text();
  c.stats = archive.stats();
  c.generations = archive.generation_storage();
  if (with_checkpoint) c.checkpoint = archive.checkpoint();
  return c;
}

void require_generations_done(const std::string& path, const RootContent& c, const RunInfo& info) {
  // A state change must not claim a generation the archive does not hold (a failed append
  // followed by "interrupted" once left an archive no --resume would accept).
  if (c.info.generations_done != info.generations_done)
    throw ArchiveError(
        path + ": refusing to set generations_done = " + std::to_string(info.generations_done) +
        " in a state change (archive has " + std::to_string(c.info.generations_done) + ")");
}

std::string reserved_root_path(const std::string& path) {
  return segment_directory(path) + "/" + kReservedRootName;
}

// The new, small root, written whole to a temporary and renamed over `path` (its size does not
// depend on the data of the generations, only on their count: one link and one /stats row
// each). Before the rename, the reserved space grows to hold a root of its size.
void write_root(const std::string& path, const RootContent& c, const WriteSteps& steps) {
  const PartSteps step(steps, "root");
  AtomicOutput out(path, Overwrite::replace);
  {
    step("create");
    h5::File file = h5::File::create(out.temp_path(), nullptr, path);
    fill_root(file, path, c, step);
    step("close");
    file.close();
  }
  step("reserve");
  reserve_stop_root(path, fs::file_size(out.temp_path()));
  out.commit(step.commit_hook());
}

// The small root written into the reserved space and renamed over `path`: built in memory, its
// bytes overwrite the reserved file's allocated ones (ArchiveError when it does not fit), the
// file is cut to the root's size and renamed. Atomic as write_root; the reservation is used up.
void write_root_into_reserve(const std::string& path, const RootContent& c,
                             const WriteSteps& steps) {
  const PartSteps step(steps, "reserved root");
  const std::string reserve = reserved_root_path(path);
  struct stat st {};
  if (::lstat(reserve.c_str(), &st) != 0 || !S_ISREG(st.st_mode))
    throw ArchiveError(reserve + ": no space reserved for the stop's root");
  std::vector<std::uint8_t> image;
  {
    step("create");
    h5::File file = h5::File::create_in_memory(path);
    fill_root(file, path, c, step);
    image = file.image();
    step("close");
    file.close();
  }
  if (image.size() > static_cast<std::uint64_t>(st.st_size))
    throw ArchiveError(reserve + ": the stop's root takes " + std::to_string(image.size()) +
                       " bytes, " + std::to_string(st.st_size) + " are reserved");
  AtomicOutput out(path, Overwrite::replace, reserve);
  step("write");
  const int fd = ::open(reserve.c_str(), O_WRONLY | O_NOFOLLOW | O_CLOEXEC);
  if (fd < 0) throw ArchiveError(reserve + ": cannot open: " + std::strerror(errno));
  int error = write_fully(
      fd, {reinterpret_cast<const char*>(image.data()), image.size()});  // from offset 0
  if (error == 0 && ::ftruncate(fd, static_cast<off_t>(image.size())) != 0) error = errno;
  ::close(fd);
  if (error != 0)
    throw ArchiveError(reserve + ": cannot write the stop's root: " + std::strerror(error));
  out.commit(step.commit_hook());
}

}  // namespace softevo::io::detail
