// The run archive's reader (docs/archive.md): the root, its generations wherever they are
// stored (in the root, a segment file or a packed file), the statistics and the checkpoint, every
// read bounded by the limits of docs/archive.md "Limits".
#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "common/config_identity.hpp"  // experiment_hash_of_text, hash_hex
#include "common/input_file.hpp"
#include "common/safe_write.hpp"  // directory_of
#include "io/archive.hpp"
#include "io/archive_internal.hpp"
#include "io/h5.hpp"

namespace softevo::io {
namespace {
namespace fs = std::filesystem;
using namespace detail;
}  // namespace

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
    // Archives written before the attribute were softevo-mpi's: the one default, set here.
    r.program = f.has_attribute("program") ? f.read_string_attribute("program", kStringBytes)
                                           : "softevo-mpi";
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
    const std::string state = f.read_string_attribute("state", kStringBytes);
    const std::optional<RunState> known_state = choice_from_string<RunState>(state);
    if (!known_state)
      throw ArchiveError(path_ + ": /: attribute state = '" + state +
                         "' is not one of running, complete, interrupted");
    r.state = *known_state;
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

namespace {

// /generations/G/strategy (docs/archive.md): every extent checked before it is read.
StrategyReport read_strategy_group(const h5::Group& g, hsize_t n, const std::string& where) {
  StrategyReport s;
  s.strategy = g.read_string_attribute("name", kStringBytes);
  const auto version = g.read_attribute<std::int64_t>("schema_version");
  if (version != kStrategySchemaVersion)
    throw ArchiveError(where + ": schema_version " + std::to_string(version) +
                       ", this build reads " + std::to_string(kStrategySchemaVersion));
  const auto table = [&](const std::string& name, std::optional<hsize_t> rows, hsize_t max_rows) {
    StrategyTable t;
    if (!g.has_link(name)) return t;
    const h5::Dataset ds = g.open_dataset(name);
    t.columns = split_columns(ds.read_string_attribute(kColumnsAttribute, kStringBytes));
    const std::vector<hsize_t> dims = ds.dims();
    if (dims.size() != 2 || dims[1] != t.columns.size() ||
        dims[1] > static_cast<hsize_t>(ArchiveLimits::strategy_columns) ||
        (rows && dims[0] != *rows) || dims[0] > max_rows)
      throw ArchiveError(where + "/" + name + " is not [" +
                         (rows ? std::to_string(*rows) : "rows <= " + std::to_string(max_rows)) +
                         ", " + std::to_string(t.columns.size()) + "] (columns " +
                         join_columns(t.columns) + ")");
    t.values = ds.read<double>();
    return t;
  };
  s.rows = table("rows", n, n);
  s.map = table("map", std::nullopt, static_cast<hsize_t>(ArchiveLimits::map_cells));
  const StrategyTable metrics = table("metrics", hsize_t{1}, 1);
  for (std::size_t k = 0; k < metrics.columns.size(); ++k)
    s.metrics.emplace_back(metrics.columns[k], metrics.values[k]);
  return s;
}

// Which generations an archive has, for a message about one it lacks: "the archive has
// generations 0..9", or "the archive has no generation yet".
std::string generations_text(const std::vector<std::int64_t>& gens) {
  return gens.empty() ? std::string("the archive has no generation yet")
                      : "the archive has generations " + std::to_string(gens.front()) + ".." +
                            std::to_string(gens.back());
}

}  // namespace

std::int64_t Archive::generation_of(std::int64_t id, std::optional<std::int64_t> g) const {
  return archive_errors([&] {
    const std::vector<std::int64_t> gens = generations();
    if (gens.empty()) throw ArchiveError(path_ + ": " + generations_text(gens));
    if (g && !std::binary_search(gens.begin(), gens.end(), *g))
      throw ArchiveError(path_ + ": no generation " + std::to_string(*g) + "; " +
                         generations_text(gens));
    const auto ids_of = [&](std::int64_t gen) {
      const std::string name = "generations/" + generation_group_name(gen);
      require_segment(name);
      return file_->open_group(name).open_dataset("id").read<std::int64_t>(
          ArchiveLimits::individuals);
    };
    const auto holds = [&](std::int64_t gen) {
      const std::vector<std::int64_t> ids = ids_of(gen);
      return std::find(ids.begin(), ids.end(), id) != ids.end();
    };
    // The answer reads one id column, or as few as there are generations after the last one
    // that holds `id`; every column is read only for the message when there is no answer.
    if (g && holds(*g)) return *g;
    if (!g)
      for (auto gen = gens.rbegin(); gen != gens.rend(); ++gen)
        if (holds(*gen)) return *gen;
    // Generations holding `id`, ascending, and the span of all ids for the message.
    std::vector<std::int64_t> holding;
    std::int64_t lowest = INT64_MAX, highest = INT64_MIN;
    for (const std::int64_t gen : gens) {
      const std::vector<std::int64_t> ids = ids_of(gen);
      if (std::find(ids.begin(), ids.end(), id) != ids.end()) holding.push_back(gen);
      for (const std::int64_t i : ids) {
        lowest = std::min(lowest, i);
        highest = std::max(highest, i);
      }
    }
    const std::string span = lowest <= highest
                                 ? " (the archive's ids run from " + std::to_string(lowest) +
                                       " to " + std::to_string(highest) + ")"
                                 : std::string();
    if (holding.empty())
      throw ArchiveError(path_ + ": " +
                         (g ? "generation " + std::to_string(*g) + " has no individual with id " +
                                  std::to_string(id) + ", nor has any other generation"
                            : "no generation has an individual with id " + std::to_string(id)) +
                         span);
    // Runs of consecutive generations as "a..b", at most eight of them.
    std::string list;
    int runs = 0;
    for (std::size_t i = 0; i < holding.size(); ++i) {
      std::size_t j = i;
      while (j + 1 < holding.size() && holding[j + 1] == holding[j] + 1) ++j;
      if (++runs > 8) {
        list += ", ...";
        break;
      }
      list += (list.empty() ? "" : ", ") + std::to_string(holding[i]) +
              (j > i ? ".." + std::to_string(holding[j]) : "");
      i = j;
    }
    throw ArchiveError(path_ + ": generation " + std::to_string(*g) +
                       " has no individual with id " + std::to_string(id) +
                       "; it is in generation" + (holding.size() > 1 ? "s " : " ") + list);
  });
}

GenerationRecord Archive::generation(std::int64_t gen) const {
  return archive_errors([&] {
    const std::string name = "generations/" + generation_group_name(gen);
    if (!file_->has_link(name)) {
      // Which ones there are, so that a mistyped --generation can be corrected (issue 39).
      const std::vector<std::int64_t> gens = generations();
      throw ArchiveError(path_ + ": no generation " + std::to_string(gen) + " (/" + name + "); " +
                         generations_text(gens));
    }
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
    if (g.has_link("strategy"))
      r.strategy = read_strategy_group(g.open_group("strategy"), n, "/" + name + "/strategy");
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
    // Absent in every checkpoint but one within a learning generation (and in older builds').
    if (g.has_link("learning")) {
      const h5::Dataset learning = g.open_dataset("learning");
      if (learning.dims().size() != 1)
        throw ArchiveError(path_ + ": /checkpoint/learning is not one-dimensional");
      c.learning = learning.read<std::uint8_t>(ArchiveLimits::checkpoint_bytes);
    }
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

}  // namespace softevo::io
