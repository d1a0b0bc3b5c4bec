// HDF5 implementation of the run archive (schema: docs/archive.md) over the RAII layer of
// io/h5.hpp. Every failure, HDF5 or file system, becomes an ArchiveError naming the file and
// the object.
#include "io/archive.hpp"

#include <fcntl.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <utility>

#include "common/config.hpp"  // hash_hex
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
  file.write_string_attribute("experiment", info.experiment, Charset::utf8);
  file.write_string_attribute("state", info.state, Charset::utf8);
  file.write_attribute<std::int64_t>("generations_done", info.generations_done);
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

// Runs `edit` on a copy of `path` (or on a new file if `fresh`), then swaps the copy in
// (io/atomic_file.hpp). Messages name `path`, not the copy.
template <typename Edit>
void atomic_edit(const std::string& path, bool fresh, const WriteStepHook& hook, Edit&& edit) {
  const WriteSteps step(hook);
  try {
    archive_errors([&] {
      if (!fresh && !fs::exists(path)) throw ArchiveError(path + ": archive does not exist");
      replace_atomically(
          path,
          [&](const std::string& temp) {
            h5::File file = [&] {
              if (fresh) {
                // Persistent free-space tracking: space freed by replacing /checkpoint is reused
                // on the next generation instead of growing the file forever.
                h5::PropertyList creation = h5::PropertyList::file_creation();
                creation.persist_free_space();
                step("create");
                return h5::File::create(temp, &creation, path);
              }
              step("copy");
              copy_file_contents(path, temp);
              return h5::File::open(temp, h5::File::Access::read_write, path);
            }();
            edit(file, step);
            step("flush");
            file.flush();
            step("close");
            file.close();
          },
          step);
    });
  } catch (const ArchiveError& e) {
    throw ArchiveError(with_space_diagnosis(e.what(), directory_of(path)));
  }
}

// ---- FNV-1a 64 ---------------------------------------------------------------------------------
class Fnv {
 public:
  void byte(std::uint8_t b) {
    h_ ^= b;
    h_ *= 0x100000001b3ULL;
  }
  void u64(std::uint64_t v) {
    for (int i = 0; i < 8; ++i) byte(static_cast<std::uint8_t>(v >> (8 * i)));
  }
  void i64(std::int64_t v) { u64(static_cast<std::uint64_t>(v)); }
  void f64(double v) {
    std::uint64_t bits = 0;
    std::memcpy(&bits, &v, sizeof bits);
    u64(bits);
  }
  void bytes(const std::vector<std::uint8_t>& b) {
    u64(b.size());
    for (std::uint8_t x : b) byte(x);
  }
  void str(const std::string& s) {
    u64(s.size());
    for (char c : s) byte(static_cast<std::uint8_t>(c));
  }
  std::uint64_t value() const { return h_; }

 private:
  std::uint64_t h_ = 0xcbf29ce484222325ULL;
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
      !component_columns.empty() &&
      components.size() == n * static_cast<std::size_t>(units) * component_columns.size();
  if (!same)
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
  const std::string probe = temp_path_for(path) + ".probe";
  const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_EXCL, 0644);
  if (fd < 0)
    throw ArchiveError(path + ": cannot create files in " + dir + ": " + std::strerror(errno));
  ::close(fd);
  ::unlink(probe.c_str());
}

void create_archive(const std::string& path, const RunInfo& info, const std::string& config_text,
                    const WriteStepHook& hook) {
  atomic_edit(path, true, hook, [&](const h5::File& file, const WriteSteps& step) {
    step("attributes");
    write_run_info(file, info);
    step("/config");
    file.write_string_dataset("config", config_text, Charset::utf8);
    step("/stats");
    // /stats: chunked, unlimited rows, extended by one row per generation.
    h5::PropertyList creation = h5::PropertyList::dataset_creation();
    creation.chunk({64, kStatsColumns});
    const h5::Dataset stats = file.create_dataset<double>(
        "stats", h5::Dataspace::simple({0, kStatsColumns}, {H5S_UNLIMITED, kStatsColumns}),
        &creation);
    stats.write_string_attribute("columns", kStatsColumnNames, Charset::utf8);
    file.create_group("generations");
  });
}

void append_generation(const std::string& path, const RunInfo& info, const GenerationRecord& record,
                       const StatsRow& stats, const Checkpoint& checkpoint,
                       const WriteStepHook& hook) {
  record.check();
  atomic_edit(path, false, hook, [&](const h5::File& file, const WriteSteps& step) {
    const std::string name = "generations/" + generation_group_name(record.generation);
    if (file.has_link(name)) throw ArchiveError(path + ": /" + name + " already exists");
    step("/" + name);
    const h5::Group g = file.create_group(name);
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
    g.write_byte_rows("genome", record.genome);
    g.write_dataset<double>("components",
                            {n, static_cast<hsize_t>(record.units),
                             static_cast<hsize_t>(record.component_columns.size())},
                            record.components)
        .write_string_attribute(kColumnsAttribute, join_columns(record.component_columns),
                                h5::Charset::ascii);
    g.write_attribute<double>("best", record.best);
    g.write_attribute<double>("mean", record.mean);
    g.write_attribute<double>("sd", record.sd);
    g.write_attribute<std::int64_t>("species_count", record.species_count);
    g.write_attribute<std::int64_t>("evaluations", record.evaluations);
    g.write_attribute<double>("eval_wall_seconds", record.eval_wall_seconds);
    g.write_string_attribute("digest", hash_hex(generation_digest(record)), Charset::utf8);

    // /stats: one more row.
    step("/stats");
    const h5::Dataset table = file.open_dataset("stats");
    const hsize_t rows = table.dims().at(0);
    table.set_extent({rows + 1, kStatsColumns});
    table.write_block<double>({rows, 0}, {1, kStatsColumns},
                              {stats.generation, stats.best, stats.mean, stats.sd,
                               stats.species_count, stats.evaluations_per_second});

    // /checkpoint: replaced as a whole.
    step("/checkpoint");
    if (file.has_link("checkpoint")) file.delete_link("checkpoint");
    const h5::Group cg = file.create_group("checkpoint");
    cg.write_dataset<std::uint8_t>(
        "population", {static_cast<hsize_t>(checkpoint.population.size())}, checkpoint.population);
    cg.write_attribute<std::int64_t>("generation", checkpoint.generation);

    step("attributes");
    write_run_info(file, info);
  });
}

void update_run_info(const std::string& path, const RunInfo& info, const WriteStepHook& hook) {
  atomic_edit(path, false, hook, [&](const h5::File& file, const WriteSteps& step) {
    // A state change must not claim a generation the archive does not hold (a failed append
    // followed by "interrupted" once left an archive no --resume would accept).
    const std::int64_t stored = file.read_attribute<std::int64_t>("generations_done");
    if (stored != info.generations_done)
      throw ArchiveError(
          path + ": refusing to set generations_done = " + std::to_string(info.generations_done) +
          " in a state change (archive has " + std::to_string(stored) + ")");
    step("attributes");
    write_run_info(file, info);
  });
}

// ---- Archive (reader) --------------------------------------------------------------------------
Archive::Archive(const std::string& path) : path_(path) {
  archive_errors([&] {
    file_ = std::make_unique<h5::File>(h5::File::open(path));
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
    r.experiment = f.read_string_attribute("experiment", kStringBytes);
    r.state = f.read_string_attribute("state", kStringBytes);
    r.generations_done = f.read_attribute<std::int64_t>("generations_done");
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

bool is_run_archive(const std::string& path) {
  try {
    if (!h5::File::is_hdf5(path)) return false;
    const h5::File file = h5::File::open(path);
    return file.has_attribute("format") &&
           file.read_string_attribute("format", kStringBytes) == kArchiveFormat;
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
  return h.value();
}

std::optional<std::uint64_t> Archive::stored_generation_digest(std::int64_t gen) const {
  return archive_errors([&]() -> std::optional<std::uint64_t> {
    const std::string name = "generations/" + generation_group_name(gen);
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
