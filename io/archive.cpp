// HDF5 implementation of the run archive (schema: docs/archive.md) over the RAII layer of
// io/h5.hpp. Every failure, HDF5 or file system, becomes an ArchiveError naming the file and
// the object.
#include "io/archive.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <utility>

#include "common/config.hpp"
#include "common/config_identity.hpp"  // hash_hex
#include "common/fnv1a.hpp"
#include "common/input_file.hpp"
#include "common/safe_write.hpp"
#include "io/h5.hpp"

namespace softevo::io {
namespace {

namespace fs = std::filesystem;
using h5::Charset;

// Runs `body`; any other error (h5::Error, file system) is rethrown as an ArchiveError with the
// same message, so callers catch one type.
template <typename Body>
auto archive_errors(Body&& body) -> decltype(body()) {
  try {
    return body();
  } catch (const ArchiveError&) {
    throw;
  } catch (const std::runtime_error& e) {
    throw ArchiveError(e.what());
  }
}

constexpr auto kStringBytes = static_cast<std::size_t>(ArchiveLimits::string_bytes);

const char* const kStatsColumnNames =
    "generation,best,mean,sd,species_count,evaluations_per_second";

void write_run_info(const h5::File& file, const RunInfo& info) {
  file.write_string_attribute("format", info.format, Charset::utf8);
  file.write_string_attribute("version", info.version, Charset::utf8);
  file.write_string_attribute("git_commit", info.git_commit, Charset::utf8);
  file.write_attribute<std::int32_t>("physics_revision", info.physics_revision);
  file.write_attribute<std::int64_t>("seed", info.seed);
  file.write_attribute<std::int32_t>("ranks", info.ranks);
  file.write_string_attribute("host", info.host, Charset::utf8);
  file.write_string_attribute("start_time", info.start_time, Charset::utf8);
  file.write_string_attribute("end_time", info.end_time, Charset::utf8);
  file.write_string_attribute("config_hash", info.config_hash, Charset::utf8);
  if (!info.experiment_hash.empty())
    file.write_string_attribute("experiment_hash", info.experiment_hash, Charset::utf8);
  file.write_string_attribute("experiment", info.experiment, Charset::utf8);
  file.write_string_attribute("state", info.state, Charset::utf8);
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

// When a write into `directory` failed, the reason HDF5 reports is often generic ("file write
// failed", "flush failed", "Input/output error"): it does not pass errno on. A full file system
// is by far the most common cause and the one the user must act on, so say so when it is the
// case (less than kLowSpaceBytes left for the writer).
std::string with_space_diagnosis(const std::string& message, const std::string& directory) {
  constexpr std::uint64_t kLowSpaceBytes = 1 << 20;
  if (message.find(std::strerror(ENOSPC)) != std::string::npos) return message;
  struct statvfs vfs {};
  if (::statvfs(directory.c_str(), &vfs) != 0) return message;
  const std::uint64_t free_bytes =
      static_cast<std::uint64_t>(vfs.f_bavail) * static_cast<std::uint64_t>(vfs.f_frsize);
  if (free_bytes >= kLowSpaceBytes && vfs.f_favail != 0) return message;
  return message + " (" + std::strerror(ENOSPC) + ": " + directory + " has " +
         std::to_string(free_bytes) + " bytes free)";
}

// ---- digests: FNV-1a 64 (common/fnv1a.hpp), values little-endian, containers length-first ----
class Fnv {
 public:
  void byte(std::uint8_t b) { h_.byte(b); }
  void u64(std::uint64_t v) { h_.u64_le(v); }
  void i64(std::int64_t v) { u64(static_cast<std::uint64_t>(v)); }
  void f64(double v) { h_.f64_le(v); }
  void bytes(const std::vector<std::uint8_t>& b) {
    u64(b.size());
    h_.bytes(b.data(), b.size());
  }
  void str(const std::string& s) {
    u64(s.size());
    h_.text(s);
  }
  std::uint64_t value() const { return h_.value(); }

 private:
  Fnv1a64 h_;
};

}  // namespace

std::string generation_group_name(std::int64_t generation) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%06lld", static_cast<long long>(generation));
  return buf;
}

const std::vector<std::string>& legacy_component_columns() {
  static const std::vector<std::string> columns = {
      "fitness", "distance", "path_length", "angle_error", "perpendicular_penalty", "status"};
  return columns;
}

namespace {

// The attribute "columns" of a components dataset: the names joined by commas.
constexpr const char* kColumnsAttribute = "columns";

std::string join_columns(const std::vector<std::string>& columns) {
  std::string out;
  for (std::size_t i = 0; i < columns.size(); ++i) out += (i ? "," : "") + columns[i];
  return out;
}

std::vector<std::string> split_columns(const std::string& text) {
  std::vector<std::string> out;
  std::size_t start = 0;
  for (;;) {
    const std::size_t comma = text.find(',', start);
    out.push_back(text.substr(start, comma - start));
    if (comma == std::string::npos) return out;
    start = comma + 1;
  }
}

}  // namespace

void GenerationRecord::check() const {
  const std::size_t n = id.size();
  const std::string at = "generation " + std::to_string(generation) + ": ";
  const auto beyond = [&](const std::string& what, std::int64_t limit) {
    return ArchiveError(at + what + " beyond the limit of " + std::to_string(limit) +
                        " (docs/archive.md \"Limits\")");
  };
  if (generation < 0 || generation >= ArchiveLimits::generations)
    throw beyond("generation number", ArchiveLimits::generations - 1);
  if (n > static_cast<std::size_t>(ArchiveLimits::individuals))
    throw beyond(std::to_string(n) + " rows", ArchiveLimits::individuals);
  if (units > ArchiveLimits::units)
    throw beyond(std::to_string(units) + " work units", ArchiveLimits::units);
  if (component_columns.size() > static_cast<std::size_t>(ArchiveLimits::component_columns))
    throw beyond(std::to_string(component_columns.size()) + " component columns",
                 ArchiveLimits::component_columns);
  for (const std::vector<std::uint8_t>& g : genome)
    if (g.size() > static_cast<std::size_t>(ArchiveLimits::genome_bytes))
      throw beyond("a genome of " + std::to_string(g.size()) + " bytes",
                   ArchiveLimits::genome_bytes);
  const bool same =
      parent1.size() == n && parent2.size() == n && species.size() == n && status.size() == n &&
      fitness.size() == n && voxels.size() == n && chambers.size() == n &&
      wall_seconds.size() == n && worker_rank.size() == n && genome.size() == n && units >= 1 &&
      (reused_from.empty() || reused_from.size() == n) && !component_columns.empty() &&
      components.size() == n * static_cast<std::size_t>(units) * component_columns.size();
  const bool learning_same =
      fitness_before.empty()
          ? learn_evaluations.empty() && learned_genome.empty() && learning_curve.empty()
          : fitness_before.size() == n && learn_evaluations.size() == n &&
                learned_genome.size() == n && learning_points >= 1 &&
                learning_curve.size() == n * static_cast<std::size_t>(learning_points);
  if (!same || !learning_same)
    throw ArchiveError("generation " + std::to_string(generation) +
                       ": record columns have different lengths");
  for (const std::string& c : component_columns)
    if (c.empty() || c.find(',') != std::string::npos)
      throw ArchiveError("generation " + std::to_string(generation) + ": component column '" + c +
                         "' is empty or contains a comma");
  for (std::size_t i = 1; i < n; ++i)
    if (id[i] <= id[i - 1])
      throw ArchiveError("generation " + std::to_string(generation) +
                         ": rows are not sorted by ascending unique id");
}

FitnessStats fitness_stats(const std::vector<double>& fitness) {
  FitnessStats s;
  if (fitness.empty()) return s;
  s.best = fitness[0];
  double sum = 0.0;
  for (double f : fitness) {
    s.best = std::max(s.best, f);
    sum += f;
  }
  s.mean = sum / static_cast<double>(fitness.size());
  double ss = 0.0;
  for (double f : fitness) ss += (f - s.mean) * (f - s.mean);
  s.sd = std::sqrt(ss / static_cast<double>(fitness.size()));
  return s;
}

void check_output_path(const std::string& path) {
  if (path.empty()) throw ArchiveError("output path is empty");
  std::error_code ec;
  if (fs::is_directory(path, ec)) throw ArchiveError(path + ": is a directory, not a file");
  const std::string dir = directory_of(path);
  if (!fs::is_directory(dir, ec))
    throw ArchiveError(path + ": output directory " + dir + " does not exist");
  try {
    // The archive is replaced like any output (common/safe_write.hpp): a symlink or special
    // file is refused now, before a run starts, rather than at its first write.
    const AtomicOutput probe(path, Overwrite::replace);
  } catch (const OutputFileError& e) {
    throw ArchiveError(e.what());
  }
}

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

// The new, small root: run attributes, /config, /stats, a link per generation, /checkpoint.
// Written whole to a temporary and renamed over `path` (its size does not depend on the data
// of the generations, only on their count: one link and one /stats row each).
void write_root(const std::string& path, const RootContent& c, const WriteSteps& steps) {
  const PartSteps step(steps, "root");
  AtomicOutput out(path, Overwrite::replace);
  {
    step("create");
    h5::File file = h5::File::create(out.temp_path(), nullptr, path);
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
    step("close");
    file.close();
  }
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
    for (ssize_t done = 0; done < got;) {
      const ssize_t put =
          ::write(out.fd, buffer.data() + done, static_cast<std::size_t>(got - done));
      if (put < 0 && errno == EINTR) continue;
      if (put < 0) fail("write");
      done += put;
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
  if (fs::exists(path)) {
    try {
      for (const GenerationStorage& s : Archive(path).generation_storage())
        referenced.push_back(s.file);
    } catch (const std::exception&) {
      return 0;  // a damaged root: its segments may be all that is left of the run
    }
  }
  int removed = remove_stale_temporaries_in(dir);
  std::error_code ec;
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

// A new root with new attributes (and /config, when given): the state changes of a run.
void update_root(const std::string& path, const RunInfo& info,
                 const std::optional<std::string>& config_text, const WriteStepHook& hook) {
  const WriteSteps steps(hook);
  archive_update(path, [&] {
    RootContent c = read_root(path, true);
    require_generations_done(path, c, info);
    keep_generation_data_apart(path, c, steps);
    c.info = info;
    if (config_text) c.config_text = *config_text;
    write_root(path, c, steps);
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
  update_root(path, info, std::nullopt, hook);
}

void update_run_config(const std::string& path, const RunInfo& info, const std::string& config_text,
                       const WriteStepHook& hook) {
  update_root(path, info, config_text, hook);
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
void require_room_to_pack(const std::string& path, const Archive& source) {
  // HDF5's own overhead (headers, free-space tracking, the checkpoint) on top of the groups.
  constexpr std::uint64_t kMarginBytes = std::uint64_t{64} << 10;
  const std::uint64_t needed = bytes_to_pack(path, source);
  const std::uint64_t wanted = needed + needed / 8 + kMarginBytes;
  const std::string dir = directory_of(path);
  struct statvfs vfs {};
  if (::statvfs(dir.c_str(), &vfs) != 0) return;  // unknown: the pack's own errors will say
  const std::uint64_t free_bytes =
      static_cast<std::uint64_t>(vfs.f_bavail) * static_cast<std::uint64_t>(vfs.f_frsize);
  if (free_bytes < wanted)
    throw ArchiveError(path + ": not packed into one file: " + std::strerror(ENOSPC) + ": " + dir +
                       " has " + std::to_string(free_bytes) + " bytes free, the pack needs about " +
                       std::to_string(wanted));
}

}  // namespace

void finish_archive(const std::string& path, const RunInfo& info, const WriteStepHook& hook) {
  const WriteSteps steps(hook);
  archive_update(path, [&] {
    const PartSteps step(steps, "pack");
    {
      const Archive source(path);
      require_room_to_pack(path, source);
      RootContent c;
      c.info = source.info();
      require_generations_done(path, c, info);
      AtomicOutput out(path, Overwrite::replace);
      {
        step("create");
        // Persistent free-space tracking: an older build that continues this archive edits it
        // in place, and reuses the space of each replaced /checkpoint.
        h5::PropertyList creation = h5::PropertyList::file_creation();
        creation.persist_free_space();
        h5::File file = h5::File::create(out.temp_path(), &creation, path);
        step("attributes");
        write_run_info(file, info);
        step("/config");
        file.write_string_dataset("config", source.config_text(), Charset::utf8);
        step("/stats");
        write_stats(file, source.stats());
        step("/generations");
        const h5::Group to = file.create_group("generations");
        const h5::Group from = source.file_->open_group("generations");
        // Object copies (links followed): every byte and attribute of a group as written,
        // the digest included, so the integrity checks still see what the run wrote.
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
      out.commit(step.commit_hook());
    }
    // The root is self-contained now: the segments are unreferenced (a kill here leaves them
    // for the next start to remove).
    step("remove segments");
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

// ---- Archive (reader) --------------------------------------------------------------------------
namespace {

// A file of another kind than a run archive: what it is and what takes it ("" if not told).
std::string other_kind_of_file(const std::string& path) {
  switch (file_magic(path)) {
    case FileMagic::json:
      return path +
             ": not a run archive: it is JSON text, a robot file (softevo.robot/1) if softevo "
             "wrote it; `softevo eval`, `render` and `view` take robot files (a run archive is "
             "the .h5 that `softevo evolve` or softevo-mpi writes)";
    case FileMagic::png:
    case FileMagic::zip:
    case FileMagic::gzip:
      return path + ": not a run archive: it is " +
             (file_magic(path) == FileMagic::png ? "a PNG image" : "a compressed file") +
             " (a run archive is the .h5 that `softevo evolve` or softevo-mpi writes)";
    default:
      return "";
  }
}

}  // namespace

Archive::Archive(const std::string& path) : path_(path) {
  if (const std::string other = other_kind_of_file(path); !other.empty()) throw ArchiveError(other);
  archive_errors([&] {
    file_ = std::make_unique<h5::File>(h5::File::open(path));
    if (!file_->has_attribute("format") && file_->has_link("positions"))
      throw ArchiveError(path +
                         ": not a run archive: it is a simulation trace (`softevo eval "
                         "--trace`, `view --save-trace`); `softevo render` and `view` take "
                         "traces");
    if (!file_->has_attribute("format"))
      throw ArchiveError(path + ": not a softevo run archive (no format attribute)");
    const std::string format = file_->read_string_attribute("format", kStringBytes);
    if (format != kArchiveFormat)
      throw ArchiveError(path + ": unsupported archive format \"" + format + "\" (expected " +
                         kArchiveFormat + ")");
  });
}

Archive::~Archive() = default;

RunInfo Archive::info() const {
  return archive_errors([&] {
    const h5::File& f = *file_;
    RunInfo r;
    r.format = f.read_string_attribute("format", kStringBytes);
    r.version = f.read_string_attribute("version", kStringBytes);
    r.git_commit = f.read_string_attribute("git_commit", kStringBytes);
    r.physics_revision = f.has_attribute("physics_revision")
                             ? f.read_attribute<std::int32_t>("physics_revision")
                             : 1;
    r.seed = f.read_attribute<std::int64_t>("seed");
    r.ranks = f.read_attribute<std::int32_t>("ranks");
    r.host = f.read_string_attribute("host", kStringBytes);
    r.start_time = f.read_string_attribute("start_time", kStringBytes);
    r.end_time = f.read_string_attribute("end_time", kStringBytes);
    r.config_hash = f.read_string_attribute("config_hash", kStringBytes);
    if (f.has_attribute("experiment_hash")) {
      r.experiment_hash = f.read_string_attribute("experiment_hash", kStringBytes);
    } else {
      // An older archive: the hash of its stored config, "" when that cannot be read (the
      // integrity checks say why; the other attributes are still worth showing).
      try {
        r.experiment_hash = hash_hex(experiment_hash_of_text(config_text()));
      } catch (const ArchiveError&) {
      }
    }
    // Optional: the analysis scripts take an archive's experiment from its config without it.
    r.experiment =
        f.has_attribute("experiment") ? f.read_string_attribute("experiment", kStringBytes) : "";
    r.state = f.read_string_attribute("state", kStringBytes);
    r.generations_done = f.read_attribute<std::int64_t>("generations_done");
    if (f.has_attribute("stop_reason"))
      r.stop_reason = f.read_string_attribute("stop_reason", kStringBytes);
    if (r.generations_done < 0 || r.generations_done > ArchiveLimits::generations)
      throw ArchiveError(path_ +
                         ": /: attribute generations_done = " + std::to_string(r.generations_done) +
                         " is outside [0, " + std::to_string(ArchiveLimits::generations) + "]");
    return r;
  });
}

std::string Archive::config_text() const {
  return archive_errors([&] {
    return file_->open_dataset("config").read_string(
        static_cast<std::size_t>(ArchiveLimits::config_bytes));
  });
}

std::vector<std::int64_t> Archive::generations() const {
  return archive_errors([&] {
    std::vector<std::int64_t> out;
    for (const std::string& name :
         file_->open_group("generations").link_names(ArchiveLimits::generations)) {
      char* end = nullptr;
      const long long v = std::strtoll(name.c_str(), &end, 10);
      if (end == name.c_str() || *end != '\0' || name.size() != 6)
        throw ArchiveError(path_ + ": unexpected object /generations/" + name);
      out.push_back(v);
    }
    std::sort(out.begin(), out.end());
    return out;
  });
}

GenerationRecord Archive::generation(std::int64_t gen) const {
  return archive_errors([&] {
    const std::string name = "generations/" + generation_group_name(gen);
    if (!file_->has_link(name))
      throw ArchiveError(path_ + ": no generation " + std::to_string(gen) + " (/" + name + ")");
    require_segment(name);
    const h5::Group g = file_->open_group(name);
    GenerationRecord r;
    r.generation = gen;
    // The rows of `id` (at most ArchiveLimits::individuals) fix n; every other column must
    // have exactly n rows before it is read, so no extent is trusted beyond the schema's.
    const h5::Dataset ids = g.open_dataset("id");
    const std::vector<hsize_t> id_dims = ids.dims();
    if (id_dims.size() != 1)
      throw ArchiveError(path_ + ": /" + name + "/id is not one-dimensional");
    r.id = ids.read<std::int64_t>(ArchiveLimits::individuals);
    const hsize_t n = r.id.size();
    const auto column = [&](const std::string& dataset) {
      h5::Dataset ds = g.open_dataset(dataset);
      if (ds.dims() != std::vector<hsize_t>{n})
        throw ArchiveError(path_ + ": /" + name + "/" + dataset + " is not [" + std::to_string(n) +
                           "] like /" + name + "/id");
      return ds;
    };
    r.parent1 = column("parent1").read<std::int64_t>();
    r.parent2 = column("parent2").read<std::int64_t>();
    r.species = column("species").read<std::int64_t>();
    r.status = column("status").read<std::uint8_t>();
    r.fitness = column("fitness").read<double>();
    r.voxels = column("voxels").read<std::int32_t>();
    r.chambers = column("chambers").read<std::int32_t>();
    r.wall_seconds = column("wall_seconds").read<double>();
    r.worker_rank = column("worker_rank").read<std::int32_t>();
    // Archives written before results were reused have no such column: nothing was reused.
    r.reused_from = g.has_link("reused_from") ? column("reused_from").read<std::int64_t>()
                                              : std::vector<std::int64_t>(n, kNotReused);
    r.genome = column("genome").read_byte_rows(n, ArchiveLimits::genome_bytes);
    const h5::Dataset components = g.open_dataset("components");
    r.component_columns =
        components.has_attribute(kColumnsAttribute)
            ? split_columns(components.read_string_attribute(kColumnsAttribute, kStringBytes))
            : legacy_component_columns();
    const std::vector<hsize_t> dims = components.dims();
    if (dims.size() != 3 || dims[0] != n || dims[1] < 1 ||
        dims[1] > static_cast<hsize_t>(ArchiveLimits::units) ||
        dims[2] != r.component_columns.size() ||
        dims[2] > static_cast<hsize_t>(ArchiveLimits::component_columns))
      throw ArchiveError(path_ + ": /" + name + "/components is not [" + std::to_string(n) +
                         ", units <= " + std::to_string(ArchiveLimits::units) + ", " +
                         std::to_string(r.component_columns.size()) + "] (columns " +
                         join_columns(r.component_columns) + ")");
    r.components = components.read<double>();
    r.units = static_cast<int>(dims[1]);
    if (g.has_link("fitness_before")) {  // a run with controller learning
      r.fitness_before = column("fitness_before").read<double>();
      r.learn_evaluations = column("learn_evaluations").read<std::int64_t>();
      r.learned_genome = column("learned_genome").read_byte_rows(n, ArchiveLimits::genome_bytes);
      const h5::Dataset curve = g.open_dataset("learning_curve");
      const std::vector<hsize_t> curve_dims = curve.dims();
      if (curve_dims.size() != 2 || curve_dims[0] != n || curve_dims[1] < 1 ||
          curve_dims[1] > static_cast<hsize_t>(ArchiveLimits::learning_points))
        throw ArchiveError(path_ + ": /" + name + "/learning_curve is not [" + std::to_string(n) +
                           ", 1.." + std::to_string(ArchiveLimits::learning_points) + "]");
      r.learning_curve = curve.read<double>();
      r.learning_points = static_cast<std::int64_t>(curve_dims[1]);
    }
    r.best = g.read_attribute<double>("best");
    r.mean = g.read_attribute<double>("mean");
    r.sd = g.read_attribute<double>("sd");
    r.species_count = g.read_attribute<std::int64_t>("species_count");
    r.evaluations = g.read_attribute<std::int64_t>("evaluations");
    r.eval_wall_seconds = g.read_attribute<double>("eval_wall_seconds");
    try {
      r.check();
    } catch (const ArchiveError& e) {
      throw ArchiveError(path_ + ": " + e.what());
    }
    return r;
  });
}

std::vector<StatsRow> Archive::stats() const {
  return archive_errors([&] {
    const h5::Dataset table = file_->open_dataset("stats");
    const std::vector<hsize_t> dims = table.dims();
    if (dims.size() != 2 || dims[1] != kStatsColumns ||
        dims[0] > static_cast<hsize_t>(ArchiveLimits::generations))
      throw ArchiveError(
          path_ + ": /stats is not [G, 6] with G <= " + std::to_string(ArchiveLimits::generations));
    const std::vector<double> v = table.read<double>();
    std::vector<StatsRow> rows(static_cast<std::size_t>(dims[0]));
    for (std::size_t i = 0; i < rows.size(); ++i) {
      const double* r = &v[i * kStatsColumns];
      rows[i] = StatsRow{r[0], r[1], r[2], r[3], r[4], r[5]};
    }
    return rows;
  });
}

std::optional<Checkpoint> Archive::checkpoint() const {
  return archive_errors([&]() -> std::optional<Checkpoint> {
    if (!file_->has_link("checkpoint")) return std::nullopt;
    const h5::Group g = file_->open_group("checkpoint");
    Checkpoint c;
    c.generation = g.read_attribute<std::int64_t>("generation");
    const h5::Dataset population = g.open_dataset("population");
    if (population.dims().size() != 1)
      throw ArchiveError(path_ + ": /checkpoint/population is not one-dimensional");
    c.population = population.read<std::uint8_t>(ArchiveLimits::checkpoint_bytes);
    return c;
  });
}

std::vector<GenerationStorage> Archive::generation_storage() const {
  return archive_errors([&] {
    std::vector<GenerationStorage> out;
    const h5::Group generations = file_->open_group("generations");
    for (const std::int64_t g : this->generations()) {
      const std::string name = generation_group_name(g);
      GenerationStorage s{g, "", "/generations/" + name};
      if (const auto target = generations.external_link(name)) {
        s.file = target->file;
        s.object = target->object;
      }
      out.push_back(std::move(s));
    }
    return out;
  });
}

bool Archive::self_contained() const {
  const std::vector<GenerationStorage> storage = generation_storage();
  return std::all_of(storage.begin(), storage.end(),
                     [](const GenerationStorage& s) { return s.file.empty(); });
}

void Archive::require_segment(const std::string& name) const {
  const std::size_t slash = name.rfind('/');
  const h5::Group parent = file_->open_group(name.substr(0, slash));
  const auto target = parent.external_link(name.substr(slash + 1));
  if (!target) return;
  const fs::path file = fs::path(target->file).is_absolute()
                            ? fs::path(target->file)
                            : fs::path(directory_of(path_)) / target->file;
  std::error_code ec;
  if (!fs::is_regular_file(file, ec))
    throw ArchiveError(path_ + ": /" + name + " is stored in " + file.string() +
                       ", which is missing (a run's segment directory must stay beside its "
                       "archive until the run is finished)");
}

bool is_run_archive(const std::string& path) {
  try {
    if (!h5::File::is_hdf5(path)) return false;
    const h5::File file = h5::File::open(path);
    return file.has_attribute("format") &&
           file.read_string_attribute("format", kStringBytes) == kArchiveFormat;
  } catch (const h5::DamagedFileError& e) {
    throw ArchiveError(e.what());
  } catch (const h5::Error&) {
    return false;
  }
}

namespace {

// The deterministic part of one generation, in content_digest's order (which must not change:
// equal digests across builds are how runs are compared).
void hash_generation_results(Fnv& h, const GenerationRecord& r) {
  h.i64(r.generation);
  h.u64(r.size());
  h.i64(r.units);
  // Named columns are part of the content; an archive without names (the legacy six) keeps
  // the digest it always had.
  if (r.component_columns != legacy_component_columns())
    for (const std::string& c : r.component_columns) h.str(c);
  for (std::size_t i = 0; i < r.size(); ++i) {
    h.i64(r.id[i]);
    h.i64(r.parent1[i]);
    h.i64(r.parent2[i]);
    h.i64(r.species[i]);
    h.byte(r.status[i]);
    h.f64(r.fitness[i]);
    h.i64(r.voxels[i]);
    h.i64(r.chambers[i]);
    h.bytes(r.genome[i]);
  }
  for (double c : r.components) h.f64(c);
  // Only a run with controller learning hashes its columns: every other digest is unchanged.
  if (r.has_learning()) {
    h.i64(r.learning_points);
    for (std::size_t i = 0; i < r.size(); ++i) {
      h.f64(r.fitness_before[i]);
      h.i64(r.learn_evaluations[i]);
      h.bytes(r.learned_genome[i]);
    }
    for (double c : r.learning_curve) h.f64(c);
  }
  h.f64(r.best);
  h.f64(r.mean);
  h.f64(r.sd);
  h.i64(r.species_count);
  h.i64(r.evaluations);
}

}  // namespace

std::uint64_t generation_digest(const GenerationRecord& r) {
  Fnv h;
  hash_generation_results(h, r);
  for (std::size_t i = 0; i < r.size(); ++i) {
    h.f64(r.wall_seconds[i]);
    h.i64(r.worker_rank[i]);
  }
  h.f64(r.eval_wall_seconds);
  // Only a generation that reused a result hashes the column, so every digest stored before it
  // existed (and of a generation without reuse) is unchanged.
  if (std::any_of(r.reused_from.begin(), r.reused_from.end(),
                  [](std::int64_t from) { return from != kNotReused; }))
    for (std::int64_t from : r.reused_from) h.i64(from);
  return h.value();
}

std::optional<std::uint64_t> Archive::stored_generation_digest(std::int64_t gen) const {
  return archive_errors([&]() -> std::optional<std::uint64_t> {
    const std::string name = "generations/" + generation_group_name(gen);
    require_segment(name);
    const h5::Group g = file_->open_group(name);
    if (!g.has_attribute("digest")) return std::nullopt;
    const std::string text = g.read_string_attribute("digest", kStringBytes);
    char* end = nullptr;
    const unsigned long long v = std::strtoull(text.c_str(), &end, 16);
    if (text.size() != 16 || end != text.c_str() + text.size())
      throw ArchiveError(path_ + ": /" + name + ": attribute digest \"" + text +
                         "\" is not 16 hex digits");
    return v;
  });
}

std::uint64_t fitness_digest(const Archive& archive) {
  Fnv h;
  for (std::int64_t gen : archive.generations()) {
    const GenerationRecord r = archive.generation(gen);
    for (std::size_t i = 0; i < r.size(); ++i) {
      h.i64(gen);
      h.i64(r.id[i]);
      h.byte(r.status[i]);
      h.f64(r.fitness[i]);
    }
  }
  return h.value();
}

std::uint64_t content_digest(const Archive& archive) {
  Fnv h;
  const RunInfo info = archive.info();
  h.str(info.format);
  h.i64(info.seed);
  h.str(info.config_hash);
  h.str(info.experiment);
  h.str(info.state);
  h.i64(info.generations_done);
  h.str(archive.config_text());
  for (std::int64_t gen : archive.generations()) {
    hash_generation_results(h, archive.generation(gen));
  }
  for (const StatsRow& s : archive.stats()) {
    h.f64(s.generation);
    h.f64(s.best);
    h.f64(s.mean);
    h.f64(s.sd);
    h.f64(s.species_count);
  }
  if (const auto c = archive.checkpoint()) {
    h.i64(c->generation);
    h.bytes(c->population);
  }
  return h.value();
}

}  // namespace softevo::io
