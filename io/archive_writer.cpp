// The run archive's writer (docs/archive.md "On disk while running, once finished"): creating,
// appending a generation as a segment file, updating the root, finishing (packing) and removing.
#include <fcntl.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "common/config.hpp"
#include "common/safe_write.hpp"
#include "io/archive.hpp"
#include "io/archive_internal.hpp"
#include "io/child_process.hpp"
#include "io/h5.hpp"

namespace softevo::io {
namespace {

namespace fs = std::filesystem;
using namespace detail;
using h5::Charset;

const char* const kStatsColumnNames =
    "generation,best,mean,sd,species_count,evaluations_per_second";

void write_run_info(const h5::File& file, const RunInfo& info) {
  file.write_string_attribute("format", info.format, Charset::utf8);
  file.write_string_attribute("version", info.version, Charset::utf8);
  file.write_string_attribute("git_commit", info.git_commit, Charset::utf8);
  file.write_attribute<std::int32_t>("physics_revision", info.physics_revision);
  file.write_attribute<std::int64_t>("seed", info.seed);
  file.write_attribute<std::int32_t>("ranks", info.ranks);
  if (!info.program.empty()) file.write_string_attribute("program", info.program, Charset::utf8);
  file.write_string_attribute("host", info.host, Charset::utf8);
  file.write_string_attribute("start_time", info.start_time, Charset::utf8);
  file.write_string_attribute("end_time", info.end_time, Charset::utf8);
  file.write_string_attribute("config_hash", info.config_hash, Charset::utf8);
  if (!info.experiment_hash.empty())
    file.write_string_attribute("experiment_hash", info.experiment_hash, Charset::utf8);
  file.write_string_attribute("experiment", info.experiment, Charset::utf8);
  file.write_string_attribute("state", to_string(info.state), Charset::utf8);
  file.write_attribute<std::int64_t>("generations_done", info.generations_done);
  if (!info.stop_reason.empty() || file.has_attribute("stop_reason"))  // "" clears it (--resume)
    file.write_string_attribute("stop_reason", info.stop_reason, Charset::utf8);
}

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

// The bytes an unprivileged writer may still take in `directory`'s file system; the maximum
// when unknown (statvfs failed: the writes' own errors will say). `no_inode`: set when no
// file can be created there any more.
std::uint64_t free_bytes_in(const std::string& directory, bool* no_inode = nullptr) {
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

}  // namespace

namespace {

// ---- the writer's layout (docs/archive.md "On disk while running, once finished") -----------

constexpr const char* kSegmentFormat = "softevo.segment/1";

std::string segment_directory(const std::string& path) {
  return path + ".d";
}
// The segment directory as external links name it: relative to the root file's directory,
// so the pair can be moved together.
std::string segment_directory_link_name(const std::string& path) {
  return fs::path(path).filename().string() + ".d";
}
std::string segment_file_name(std::int64_t generation) {
  return "gen-" + generation_group_name(generation) + ".h5";
}
// The former self-contained root, kept as it was, that holds generations 0..n-1 of an archive
// being continued (a finished archive, or one from an older build).
std::string packed_file_name(std::int64_t generations) {
  return "packed-" + generation_group_name(generations) + ".h5";
}
bool is_segment_file_name(const std::string& name) {
  const auto numbered = [&](const std::string& prefix) {
    return name.size() == prefix.size() + 9 && name.rfind(prefix, 0) == 0 &&
           name.compare(name.size() - 3, 3, ".h5") == 0 &&
           std::all_of(name.begin() + static_cast<std::ptrdiff_t>(prefix.size()), name.end() - 3,
                       [](char c) { return c >= '0' && c <= '9'; });
  };
  return numbered("gen-") || numbered("packed-");
}

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

void write_stats(const h5::File& file, const std::vector<StatsRow>& rows) {
  // Chunked with unlimited rows, as it always was: an older build continuing this archive
  // extends it in place.
  h5::PropertyList creation = h5::PropertyList::dataset_creation();
  creation.chunk({64, kStatsColumns});
  const hsize_t n = rows.size();
  const h5::Dataset stats = file.create_dataset<double>(
      "stats", h5::Dataspace::simple({n, kStatsColumns}, {H5S_UNLIMITED, kStatsColumns}),
      &creation);
  stats.write_string_attribute("columns", kStatsColumnNames, Charset::utf8);
  if (n == 0) return;
  std::vector<double> values;
  values.reserve(rows.size() * kStatsColumns);
  for (const StatsRow& s : rows)
    values.insert(values.end(),
                  {s.generation, s.best, s.mean, s.sd, s.species_count, s.evaluations_per_second});
  stats.write_block<double>({0, 0}, {n, kStatsColumns}, values);
}

void write_checkpoint(const h5::File& file, const Checkpoint& checkpoint) {
  const h5::Group cg = file.create_group("checkpoint");
  cg.write_dataset<std::uint8_t>("population", {static_cast<hsize_t>(checkpoint.population.size())},
                                 checkpoint.population);
  cg.write_attribute<std::int64_t>("generation", checkpoint.generation);
  if (!checkpoint.learning.empty())
    cg.write_dataset<std::uint8_t>("learning", {static_cast<hsize_t>(checkpoint.learning.size())},
                                   checkpoint.learning);
}

// A strategy table as a 2-D dataset with its column names (nothing for a table without columns).
void write_strategy_table(const h5::Group& g, const std::string& name, const StrategyTable& t) {
  if (t.columns.empty()) return;
  g.write_dataset<double>(name, {static_cast<hsize_t>(t.rows()), t.columns.size()}, t.values)
      .write_string_attribute(kColumnsAttribute, join_columns(t.columns), h5::Charset::ascii);
}

// /generations/G/strategy (docs/archive.md): a strategy other than NEAT.
void write_strategy_group(const h5::Group& parent, const StrategyReport& s) {
  const h5::Group g = parent.create_group("strategy");
  g.write_string_attribute("name", s.strategy, Charset::utf8);
  g.write_attribute<std::int64_t>("schema_version", kStrategySchemaVersion);
  write_strategy_table(g, "rows", s.rows);
  write_strategy_table(g, "map", s.map);
  StrategyTable metrics;
  for (const auto& [key, value] : s.metrics) {
    metrics.columns.push_back(key);
    metrics.values.push_back(value);
  }
  write_strategy_table(g, "metrics", metrics);
}

void write_generation_group(const h5::Group& parent, const std::string& name,
                            const GenerationRecord& record) {
  const h5::Group g = parent.create_group(name);
  const hsize_t n = record.size();
  g.write_dataset<std::int64_t>("id", {n}, record.id);
  g.write_dataset<std::int64_t>("parent1", {n}, record.parent1);
  g.write_dataset<std::int64_t>("parent2", {n}, record.parent2);
  g.write_dataset<std::int64_t>("species", {n}, record.species);
  g.write_dataset<std::uint8_t>("status", {n}, record.status);
  g.write_dataset<double>("fitness", {n}, record.fitness);
  g.write_dataset<std::int32_t>("voxels", {n}, record.voxels);
  g.write_dataset<std::int32_t>("chambers", {n}, record.chambers);
  g.write_dataset<double>("wall_seconds", {n}, record.wall_seconds);
  g.write_dataset<std::int32_t>("worker_rank", {n}, record.worker_rank);
  g.write_dataset<std::int64_t>("reused_from", {n},
                                record.reused_from.empty()
                                    ? std::vector<std::int64_t>(record.size(), kNotReused)
                                    : record.reused_from);
  g.write_byte_rows("genome", record.genome);
  g.write_dataset<double>("components",
                          {n, static_cast<hsize_t>(record.units),
                           static_cast<hsize_t>(record.component_columns.size())},
                          record.components)
      .write_string_attribute(kColumnsAttribute, join_columns(record.component_columns),
                              h5::Charset::ascii);
  if (record.has_learning()) {
    g.write_dataset<double>("fitness_before", {n}, record.fitness_before);
    g.write_dataset<std::int64_t>("learn_evaluations", {n}, record.learn_evaluations);
    g.write_byte_rows("learned_genome", record.learned_genome);
    g.write_dataset<double>("learning_curve", {n, static_cast<hsize_t>(record.learning_points)},
                            record.learning_curve);
  }
  if (!record.strategy.empty()) write_strategy_group(g, record.strategy);
  g.write_attribute<double>("best", record.best);
  g.write_attribute<double>("mean", record.mean);
  g.write_attribute<double>("sd", record.sd);
  g.write_attribute<std::int64_t>("species_count", record.species_count);
  g.write_attribute<std::int64_t>("evaluations", record.evaluations);
  g.write_attribute<double>("eval_wall_seconds", record.eval_wall_seconds);
  g.write_string_attribute("digest", hash_hex(generation_digest(record)), Charset::utf8);
}

// The segment directory of `path`, created if needed; a symlink or non-directory there is
// refused (the archive never writes through a link).
std::string make_segment_directory(const std::string& path) {
  const std::string dir = segment_directory(path);
  if (::mkdir(dir.c_str(), 0777) != 0 && errno != EEXIST)
    throw ArchiveError(dir + ": cannot create the segment directory: " + std::strerror(errno));
  struct stat st {};
  if (::lstat(dir.c_str(), &st) != 0 || !S_ISDIR(st.st_mode))
    throw ArchiveError(dir + ": exists and is not a directory (the archive's segments go there)");
  return dir;
}

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

std::string reserved_root_path(const std::string& path) {
  return segment_directory(path) + "/" + kReservedRootName;
}

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

// Writes the segment of one generation (written once, never edited) and returns its link.
GenerationStorage write_segment(const std::string& path, const GenerationRecord& record,
                                const WriteSteps& steps) {
  const PartSteps step(steps, "segment");
  const std::string name = segment_file_name(record.generation);
  const std::string segment = make_segment_directory(path) + "/" + name;
  AtomicOutput out(segment, Overwrite::replace);
  {
    step("create");
    h5::File file = h5::File::create(out.temp_path(), nullptr, segment);
    file.write_string_attribute("format", kSegmentFormat, Charset::utf8);
    const std::string group = "generations/" + generation_group_name(record.generation);
    step("/" + group);
    write_generation_group(file.create_group("generations"),
                           generation_group_name(record.generation), record);
    step("flush");
    file.flush();
    step("close");
    file.close();
  }
  out.commit(step.commit_hook());
  return GenerationStorage{record.generation, segment_directory_link_name(path) + "/" + name,
                           "/generations/" + generation_group_name(record.generation)};
}

// Copies the bytes of `from` into the existing, empty file `to`; a full disk says "No space
// left on device" (std::filesystem::copy_file reports a short sendfile as EIO).
void copy_file_contents(const std::string& from, const std::string& to) {
  const auto fail = [&](const std::string& what) {
    throw ArchiveError(to + ": cannot copy " + from + ": " + what + ": " + std::strerror(errno));
  };
  struct Fd {
    int fd = -1;
    ~Fd() {
      if (fd >= 0) ::close(fd);
    }
  };
  const Fd in{::open(from.c_str(), O_RDONLY | O_CLOEXEC)};
  if (in.fd < 0) fail("open for reading");
  Fd out{::open(to.c_str(), O_WRONLY | O_TRUNC | O_NOFOLLOW | O_CLOEXEC)};
  if (out.fd < 0) fail("open the copy");
  std::vector<char> buffer(std::size_t{1} << 20);
  for (;;) {
    const ssize_t got = ::read(in.fd, buffer.data(), buffer.size());
    if (got < 0 && errno == EINTR) continue;
    if (got < 0) fail("read");
    if (got == 0) break;
    if (const int error = write_fully(out.fd, {buffer.data(), static_cast<std::size_t>(got)})) {
      errno = error;
      fail("write");
    }
  }
  if (::close(std::exchange(out.fd, -1)) != 0) fail("close");
}

// A root that still holds generation data (a finished archive being continued, or one written
// by an older build) becomes a small root first: the file as it is moves, unchanged, into the
// segment directory as packed-<n>.h5 (a hard link: no byte is copied; a copy where the file
// system has no hard links), and its generations become links into it.
void keep_generation_data_apart(const std::string& path, RootContent& c, const WriteSteps& steps) {
  if (!c.holds_generation_data()) return;
  const PartSteps step(steps, "packed");
  std::int64_t held = 0;
  for (const GenerationStorage& s : c.generations)
    if (s.file.empty()) held = std::max(held, s.generation + 1);
  const std::string name = packed_file_name(held);
  const std::string packed = make_segment_directory(path) + "/" + name;
  AtomicOutput out(packed, Overwrite::replace);
  step("link");
  ::unlink(out.temp_path().c_str());
  if (::link(path.c_str(), out.temp_path().c_str()) != 0) {
    const int fd = ::open(out.temp_path().c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    if (fd < 0) throw ArchiveError(out.temp_path() + ": cannot create: " + std::strerror(errno));
    ::close(fd);
    step("copy");
    copy_file_contents(path, out.temp_path());
  }
  out.commit(step.commit_hook());
  for (GenerationStorage& s : c.generations)
    if (s.file.empty()) s.file = segment_directory_link_name(path) + "/" + name;
}

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

void require_generations_done(const std::string& path, const RootContent& c, const RunInfo& info) {
  // A state change must not claim a generation the archive does not hold (a failed append
  // followed by "interrupted" once left an archive no --resume would accept).
  if (c.info.generations_done != info.generations_done)
    throw ArchiveError(
        path + ": refusing to set generations_done = " + std::to_string(info.generations_done) +
        " in a state change (archive has " + std::to_string(c.info.generations_done) + ")");
}

// Removes the segment directory's files that the root at `path` does not reference (all of
// them when `path` references none, e.g. a finished archive), stale temporaries included, and
// the directory once empty. Nothing is removed when the root exists but cannot be read.
int remove_unreferenced_segments(const std::string& path) {
  const std::string dir = segment_directory(path);
  struct stat st {};
  if (::lstat(dir.c_str(), &st) != 0 || !S_ISDIR(st.st_mode)) return 0;
  std::vector<std::string> referenced;
  bool packed = false;
  const bool root_exists = fs::exists(path);
  if (root_exists) {
    try {
      const Archive root(path);
      for (const GenerationStorage& s : root.generation_storage()) {
        referenced.push_back(s.file);
        packed = packed || s.file.empty();
      }
    } catch (const std::exception&) {
      return 0;  // a damaged root: its segments may be all that is left of the run
    }
  }
  int removed = remove_stale_temporaries_in(dir);
  std::error_code ec;
  // The reserved space belongs to a root in its running form (or a new one, without
  // generations yet); without a root, or beside a packed archive, it is debris.
  if (!root_exists || packed)
    if (fs::remove(reserved_root_path(path), ec)) ++removed;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    const std::string as_linked = segment_directory_link_name(path) + "/" + name;
    if (!is_segment_file_name(name) ||
        std::find(referenced.begin(), referenced.end(), as_linked) != referenced.end())
      continue;
    std::error_code rm;
    if (fs::remove(entry.path(), rm)) ++removed;
  }
  if (fs::is_empty(dir, ec)) fs::remove(dir, ec);
  return removed;
}

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

namespace {

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

int remove_archive_debris(const std::string& path) {
  return remove_stale_temporaries(path) + remove_unreferenced_segments(path);
}

void remove_archive(const std::string& path) {
  std::error_code ec;
  fs::remove(path, ec);
  remove_unreferenced_segments(path);
}

}  // namespace softevo::io
