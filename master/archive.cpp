// HDF5 implementation of the run archive (schema: docs/archive.md). Uses the HDF5 C API with
// small RAII handles; HDF5's own error printing is switched off and every failure becomes an
// ArchiveError naming the file and the object.
#include "master/archive.hpp"

#include <fcntl.h>
#include <hdf5.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <utility>

namespace softevo::master {
namespace {

namespace fs = std::filesystem;

// ---- RAII for hid_t ----------------------------------------------------------------------------
class Handle {
 public:
  Handle() = default;
  Handle(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  Handle(Handle&& o) noexcept : id_(std::exchange(o.id_, -1)), close_(o.close_) {}
  Handle& operator=(Handle&& o) noexcept {
    reset();
    id_ = std::exchange(o.id_, -1);
    close_ = o.close_;
    return *this;
  }
  ~Handle() { reset(); }
  void reset() {
    if (id_ >= 0 && close_ != nullptr) close_(id_);
    id_ = -1;
  }
  hid_t get() const { return id_; }
  operator hid_t() const { return id_; }  // NOLINT: handles are passed straight to the C API

 private:
  hid_t id_ = -1;
  herr_t (*close_)(hid_t) = nullptr;
};

void quiet_hdf5() {
  // HDF5 prints an error stack on every failed call; we report our own messages instead.
  static const bool done = [] {
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    return true;
  }();
  (void)done;
}

[[noreturn]] void fail(const std::string& file, const std::string& what) {
  throw ArchiveError(file + ": " + what);
}

hid_t check_id(hid_t id, const std::string& file, const std::string& what) {
  if (id < 0) fail(file, what);
  return id;
}
void check_status(herr_t st, const std::string& file, const std::string& what) {
  if (st < 0) fail(file, what);
}

Handle vlen_string_type() {
  Handle t(H5Tcopy(H5T_C_S1), H5Tclose);
  H5Tset_size(t, H5T_VARIABLE);
  H5Tset_cset(t, H5T_CSET_UTF8);
  return t;
}

// ---- attributes --------------------------------------------------------------------------------
void delete_attr_if_exists(hid_t obj, const char* name) {
  if (H5Aexists(obj, name) > 0) H5Adelete(obj, name);
}

void write_attr_string(hid_t obj, const char* name, const std::string& value,
                       const std::string& file) {
  delete_attr_if_exists(obj, name);
  Handle type = vlen_string_type();
  Handle space(H5Screate(H5S_SCALAR), H5Sclose);
  Handle attr(check_id(H5Acreate2(obj, name, type, space, H5P_DEFAULT, H5P_DEFAULT), file,
                       std::string("cannot create attribute ") + name),
              H5Aclose);
  const char* p = value.c_str();
  check_status(H5Awrite(attr, type, &p), file, std::string("cannot write attribute ") + name);
}

template <typename T>
hid_t native_type();
template <>
hid_t native_type<std::int64_t>() {
  return H5T_NATIVE_INT64;
}
template <>
hid_t native_type<std::int32_t>() {
  return H5T_NATIVE_INT32;
}
template <>
hid_t native_type<std::uint8_t>() {
  return H5T_NATIVE_UINT8;
}
template <>
hid_t native_type<double>() {
  return H5T_NATIVE_DOUBLE;
}
// File (on-disk) types are fixed little-endian so archives are identical on every host.
template <typename T>
hid_t file_type();
template <>
hid_t file_type<std::int64_t>() {
  return H5T_STD_I64LE;
}
template <>
hid_t file_type<std::int32_t>() {
  return H5T_STD_I32LE;
}
template <>
hid_t file_type<std::uint8_t>() {
  return H5T_STD_U8LE;
}
template <>
hid_t file_type<double>() {
  return H5T_IEEE_F64LE;
}

template <typename T>
void write_attr(hid_t obj, const char* name, T value, const std::string& file) {
  delete_attr_if_exists(obj, name);
  Handle space(H5Screate(H5S_SCALAR), H5Sclose);
  Handle attr(check_id(H5Acreate2(obj, name, file_type<T>(), space, H5P_DEFAULT, H5P_DEFAULT), file,
                       std::string("cannot create attribute ") + name),
              H5Aclose);
  check_status(H5Awrite(attr, native_type<T>(), &value), file,
               std::string("cannot write attribute ") + name);
}

std::string read_attr_string(hid_t obj, const char* name, const std::string& file) {
  if (H5Aexists(obj, name) <= 0) fail(file, std::string("missing attribute ") + name);
  Handle attr(
      check_id(H5Aopen(obj, name, H5P_DEFAULT), file, std::string("cannot open attribute ") + name),
      H5Aclose);
  Handle ftype(H5Aget_type(attr), H5Tclose);
  if (H5Tget_class(ftype) != H5T_STRING || H5Tis_variable_str(ftype) <= 0)
    fail(file, std::string("attribute ") + name + " is not a variable-length string");
  Handle type = vlen_string_type();
  char* p = nullptr;
  check_status(H5Aread(attr, type, &p), file, std::string("cannot read attribute ") + name);
  std::string s = p != nullptr ? p : "";
  H5free_memory(p);
  return s;
}

template <typename T>
T read_attr(hid_t obj, const char* name, const std::string& file) {
  if (H5Aexists(obj, name) <= 0) fail(file, std::string("missing attribute ") + name);
  Handle attr(
      check_id(H5Aopen(obj, name, H5P_DEFAULT), file, std::string("cannot open attribute ") + name),
      H5Aclose);
  T v{};
  check_status(H5Aread(attr, native_type<T>(), &v), file,
               std::string("cannot read attribute ") + name);
  return v;
}

// ---- datasets ----------------------------------------------------------------------------------
template <typename T>
void write_dataset(hid_t loc, const char* name, const std::vector<T>& data,
                   const std::vector<hsize_t>& dims, const std::string& file) {
  Handle space(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr), H5Sclose);
  Handle ds(
      check_id(H5Dcreate2(loc, name, file_type<T>(), space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
               file, std::string("cannot create dataset ") + name),
      H5Dclose);
  if (!data.empty())
    check_status(H5Dwrite(ds, native_type<T>(), H5S_ALL, H5S_ALL, H5P_DEFAULT, data.data()), file,
                 std::string("cannot write dataset ") + name);
}

template <typename T>
std::vector<T> read_dataset(hid_t loc, const char* name, const std::string& file,
                            std::vector<hsize_t>* dims_out = nullptr) {
  Handle ds(
      check_id(H5Dopen2(loc, name, H5P_DEFAULT), file, std::string("missing dataset ") + name),
      H5Dclose);
  Handle space(H5Dget_space(ds), H5Sclose);
  const int rank = H5Sget_simple_extent_ndims(space);
  if (rank < 1) fail(file, std::string("dataset ") + name + " has no extent");
  std::vector<hsize_t> dims(static_cast<std::size_t>(rank));
  H5Sget_simple_extent_dims(space, dims.data(), nullptr);
  std::size_t n = 1;
  for (hsize_t d : dims) n *= static_cast<std::size_t>(d);
  std::vector<T> out(n);
  if (n > 0)
    check_status(H5Dread(ds, native_type<T>(), H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()), file,
                 std::string("cannot read dataset ") + name);
  if (dims_out != nullptr) *dims_out = dims;
  return out;
}

void write_string_dataset(hid_t loc, const char* name, const std::string& text,
                          const std::string& file) {
  Handle type = vlen_string_type();
  Handle space(H5Screate(H5S_SCALAR), H5Sclose);
  Handle ds(check_id(H5Dcreate2(loc, name, type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
                     file, std::string("cannot create dataset ") + name),
            H5Dclose);
  const char* p = text.c_str();
  check_status(H5Dwrite(ds, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, &p), file,
               std::string("cannot write dataset ") + name);
}

std::string read_string_dataset(hid_t loc, const char* name, const std::string& file) {
  Handle ds(
      check_id(H5Dopen2(loc, name, H5P_DEFAULT), file, std::string("missing dataset ") + name),
      H5Dclose);
  Handle type = vlen_string_type();
  char* p = nullptr;
  check_status(H5Dread(ds, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, &p), file,
               std::string("cannot read dataset ") + name);
  std::string s = p != nullptr ? p : "";
  H5free_memory(p);
  return s;
}

void write_genomes(hid_t loc, const std::vector<std::vector<std::uint8_t>>& genomes,
                   const std::string& file) {
  Handle type(H5Tvlen_create(H5T_STD_U8LE), H5Tclose);
  Handle mem_type(H5Tvlen_create(H5T_NATIVE_UINT8), H5Tclose);
  const hsize_t n = genomes.size();
  Handle space(H5Screate_simple(1, &n, nullptr), H5Sclose);
  Handle ds(check_id(H5Dcreate2(loc, "genome", type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
                     file, "cannot create dataset genome"),
            H5Dclose);
  std::vector<hvl_t> buf(genomes.size());
  for (std::size_t i = 0; i < genomes.size(); ++i) {
    buf[i].len = genomes[i].size();
    buf[i].p = const_cast<std::uint8_t*>(genomes[i].data());  // HDF5 only reads it
  }
  if (!buf.empty())
    check_status(H5Dwrite(ds, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf.data()), file,
                 "cannot write dataset genome");
}

std::vector<std::vector<std::uint8_t>> read_genomes(hid_t loc, const std::string& file) {
  Handle ds(check_id(H5Dopen2(loc, "genome", H5P_DEFAULT), file, "missing dataset genome"),
            H5Dclose);
  Handle space(H5Dget_space(ds), H5Sclose);
  hsize_t n = 0;
  if (H5Sget_simple_extent_ndims(space) != 1) fail(file, "dataset genome is not 1-D");
  H5Sget_simple_extent_dims(space, &n, nullptr);
  Handle mem_type(H5Tvlen_create(H5T_NATIVE_UINT8), H5Tclose);
  std::vector<hvl_t> buf(static_cast<std::size_t>(n));
  std::vector<std::vector<std::uint8_t>> out(static_cast<std::size_t>(n));
  if (n == 0) return out;
  check_status(H5Dread(ds, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf.data()), file,
               "cannot read dataset genome");
  for (std::size_t i = 0; i < buf.size(); ++i) {
    const auto* p = static_cast<const std::uint8_t*>(buf[i].p);
    out[i].assign(p, p + buf[i].len);
  }
  H5Dvlen_reclaim(mem_type, space, H5P_DEFAULT, buf.data());
  return out;
}

// ---- the atomic update discipline --------------------------------------------------------------
void fsync_path(const std::string& path, bool directory) {
  const int fd = ::open(path.c_str(), directory ? (O_RDONLY | O_DIRECTORY) : O_RDONLY);
  if (fd < 0) fail(path, std::string("cannot open for fsync: ") + std::strerror(errno));
  const int rc = ::fsync(fd);
  const int err = errno;
  ::close(fd);
  if (rc != 0) fail(path, std::string("fsync failed: ") + std::strerror(err));
}

std::string temp_path_for(const std::string& path) {
  const fs::path p(path);
  const fs::path dir = p.has_parent_path() ? p.parent_path() : fs::path(".");
  return (dir / ("." + p.filename().string() + ".tmp." + std::to_string(::getpid()))).string();
}

std::string directory_of(const std::string& path) {
  const fs::path p(path);
  return p.has_parent_path() ? p.parent_path().string() : std::string(".");
}

Handle create_file(const std::string& path) {
  quiet_hdf5();
  // Persistent free-space tracking: space freed by replacing /checkpoint is reused on the next
  // generation instead of growing the file forever (HDF5 >= 1.10.1).
  Handle fcpl(H5Pcreate(H5P_FILE_CREATE), H5Pclose);
  H5Pset_file_space_strategy(fcpl, H5F_FSPACE_STRATEGY_FSM_AGGR, 1, 1);
  return Handle(check_id(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, fcpl, H5P_DEFAULT), path,
                         "cannot create HDF5 file"),
                H5Fclose);
}

// Runs `edit` on a copy of `path` (or on a new file if `fresh`), then swaps the copy in.
template <typename Edit>
void atomic_edit(const std::string& path, bool fresh, Edit&& edit) {
  quiet_hdf5();
  const std::string tmp = temp_path_for(path);
  try {
    std::error_code ec;
    fs::remove(tmp, ec);
    Handle file;
    if (fresh) {
      file = create_file(tmp);
    } else {
      if (!fs::exists(path)) fail(path, "archive does not exist");
      fs::copy_file(path, tmp, fs::copy_options::overwrite_existing);
      file = Handle(check_id(H5Fopen(tmp.c_str(), H5F_ACC_RDWR, H5P_DEFAULT), tmp,
                             "cannot open copy of the archive for writing"),
                    H5Fclose);
    }
    edit(file.get(), path);
    check_status(H5Fflush(file, H5F_SCOPE_GLOBAL), tmp, "flush failed");
    file.reset();
    fsync_path(tmp, false);
    if (std::rename(tmp.c_str(), path.c_str()) != 0)
      fail(path, std::string("cannot rename ") + tmp + ": " + std::strerror(errno));
    fsync_path(directory_of(path), true);
  } catch (const fs::filesystem_error& e) {
    std::error_code ec;
    fs::remove(tmp, ec);
    fail(path, e.what());
  } catch (...) {
    std::error_code ec;
    fs::remove(tmp, ec);
    throw;
  }
}

void write_run_info(hid_t file, const RunInfo& info, const std::string& path) {
  write_attr_string(file, "format", info.format, path);
  write_attr_string(file, "version", info.version, path);
  write_attr_string(file, "git_commit", info.git_commit, path);
  write_attr<std::int32_t>(file, "physics_revision", info.physics_revision, path);
  write_attr<std::int64_t>(file, "seed", info.seed, path);
  write_attr<std::int32_t>(file, "ranks", info.ranks, path);
  write_attr_string(file, "host", info.host, path);
  write_attr_string(file, "start_time", info.start_time, path);
  write_attr_string(file, "end_time", info.end_time, path);
  write_attr_string(file, "config_hash", info.config_hash, path);
  write_attr_string(file, "experiment", info.experiment, path);
  write_attr_string(file, "state", info.state, path);
  write_attr<std::int64_t>(file, "generations_done", info.generations_done, path);
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

void GenerationRecord::check() const {
  const std::size_t n = id.size();
  const bool same = parent1.size() == n && parent2.size() == n && species.size() == n &&
                    status.size() == n && fitness.size() == n && voxels.size() == n &&
                    chambers.size() == n && wall_seconds.size() == n && worker_rank.size() == n &&
                    genome.size() == n && n_directions >= 1 &&
                    components.size() == n * static_cast<std::size_t>(n_directions) *
                                             static_cast<std::size_t>(kComponentCount);
  if (!same)
    throw ArchiveError("generation " + std::to_string(generation) +
                       ": record columns have different lengths");
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

int remove_stale_temp_files(const std::string& path) {
  const fs::path p(path);
  const std::string prefix = "." + p.filename().string() + ".tmp.";
  int removed = 0;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(directory_of(path), ec)) {
    const std::string name = e.path().filename().string();
    if (name.rfind(prefix, 0) != 0) continue;
    const std::string rest = name.substr(prefix.size());
    char* end = nullptr;
    const long pid = std::strtol(rest.c_str(), &end, 10);
    if (end == rest.c_str() || pid <= 0) continue;
    // ".probe" files and copies of live processes are left alone.
    if (*end != '\0' || (::kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH)) continue;
    std::error_code rm;
    if (fs::remove(e.path(), rm)) ++removed;
  }
  return removed;
}

void create_archive(const std::string& path, const RunInfo& info, const std::string& config_text) {
  atomic_edit(path, true, [&](hid_t file, const std::string& p) {
    write_run_info(file, info, p);
    write_string_dataset(file, "config", config_text, p);
    // /stats: chunked, unlimited rows, extended by one row per generation.
    const hsize_t dims[2] = {0, kStatsColumns};
    const hsize_t maxdims[2] = {H5S_UNLIMITED, kStatsColumns};
    const hsize_t chunk[2] = {64, kStatsColumns};
    Handle space(H5Screate_simple(2, dims, maxdims), H5Sclose);
    Handle dcpl(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
    H5Pset_chunk(dcpl, 2, chunk);
    Handle ds(
        check_id(H5Dcreate2(file, "stats", H5T_IEEE_F64LE, space, H5P_DEFAULT, dcpl, H5P_DEFAULT),
                 p, "cannot create dataset stats"),
        H5Dclose);
    write_attr_string(ds, "columns", "generation,best,mean,sd,species_count,evaluations_per_second",
                      p);
    Handle g(check_id(H5Gcreate2(file, "generations", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), p,
                      "cannot create group generations"),
             H5Gclose);
  });
}

void append_generation(const std::string& path, const RunInfo& info, const GenerationRecord& record,
                       const StatsRow& stats, const Checkpoint& checkpoint) {
  record.check();
  atomic_edit(path, false, [&](hid_t file, const std::string& p) {
    const std::string gname = "generations/" + generation_group_name(record.generation);
    if (H5Lexists(file, gname.c_str(), H5P_DEFAULT) > 0) fail(p, "/" + gname + " already exists");
    Handle g(check_id(H5Gcreate2(file, gname.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), p,
                      "cannot create group /" + gname),
             H5Gclose);
    const hsize_t n = record.size();
    write_dataset(g, "id", record.id, {n}, p);
    write_dataset(g, "parent1", record.parent1, {n}, p);
    write_dataset(g, "parent2", record.parent2, {n}, p);
    write_dataset(g, "species", record.species, {n}, p);
    write_dataset(g, "status", record.status, {n}, p);
    write_dataset(g, "fitness", record.fitness, {n}, p);
    write_dataset(g, "voxels", record.voxels, {n}, p);
    write_dataset(g, "chambers", record.chambers, {n}, p);
    write_dataset(g, "wall_seconds", record.wall_seconds, {n}, p);
    write_dataset(g, "worker_rank", record.worker_rank, {n}, p);
    write_genomes(g, record.genome, p);
    write_dataset(g, "components", record.components,
                  {n, static_cast<hsize_t>(record.n_directions), kComponentCount}, p);
    write_attr<double>(g, "best", record.best, p);
    write_attr<double>(g, "mean", record.mean, p);
    write_attr<double>(g, "sd", record.sd, p);
    write_attr<std::int64_t>(g, "species_count", record.species_count, p);
    write_attr<std::int64_t>(g, "evaluations", record.evaluations, p);
    write_attr<double>(g, "eval_wall_seconds", record.eval_wall_seconds, p);

    // /stats: one more row.
    Handle ds(check_id(H5Dopen2(file, "stats", H5P_DEFAULT), p, "missing dataset stats"), H5Dclose);
    Handle space(H5Dget_space(ds), H5Sclose);
    hsize_t dims[2] = {0, 0};
    H5Sget_simple_extent_dims(space, dims, nullptr);
    const hsize_t new_dims[2] = {dims[0] + 1, kStatsColumns};
    check_status(H5Dset_extent(ds, new_dims), p, "cannot extend dataset stats");
    Handle fspace(H5Dget_space(ds), H5Sclose);
    const hsize_t start[2] = {dims[0], 0};
    const hsize_t count[2] = {1, kStatsColumns};
    H5Sselect_hyperslab(fspace, H5S_SELECT_SET, start, nullptr, count, nullptr);
    Handle mspace(H5Screate_simple(2, count, nullptr), H5Sclose);
    const double row[kStatsColumns] = {stats.generation,    stats.best,
                                       stats.mean,          stats.sd,
                                       stats.species_count, stats.evaluations_per_second};
    check_status(H5Dwrite(ds, H5T_NATIVE_DOUBLE, mspace, fspace, H5P_DEFAULT, row), p,
                 "cannot write dataset stats");

    // /checkpoint: replaced as a whole.
    if (H5Lexists(file, "checkpoint", H5P_DEFAULT) > 0)
      check_status(H5Ldelete(file, "checkpoint", H5P_DEFAULT), p, "cannot replace /checkpoint");
    Handle cg(check_id(H5Gcreate2(file, "checkpoint", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), p,
                       "cannot create group /checkpoint"),
              H5Gclose);
    write_dataset(cg, "population", checkpoint.population,
                  {static_cast<hsize_t>(checkpoint.population.size())}, p);
    write_attr<std::int64_t>(cg, "generation", checkpoint.generation, p);

    write_run_info(file, info, p);
  });
}

void update_run_info(const std::string& path, const RunInfo& info) {
  atomic_edit(path, false,
              [&](hid_t file, const std::string& p) { write_run_info(file, info, p); });
}

// ---- Archive (reader) --------------------------------------------------------------------------
Archive::Archive(const std::string& path) : path_(path) {
  quiet_hdf5();
  std::error_code ec;
  if (!fs::exists(path, ec)) fail(path, "no such file");
  if (H5Fis_hdf5(path.c_str()) <= 0) fail(path, "not an HDF5 file (or unreadable)");
  file_ = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (file_ < 0) fail(path, "cannot open HDF5 file");
  std::string format;
  try {
    format = read_attr_string(file_, "format", path);
  } catch (const ArchiveError&) {
    H5Fclose(file_);
    file_ = -1;
    fail(path, std::string("not a softevo run archive (no format attribute)"));
  }
  if (format != kArchiveFormat) {
    H5Fclose(file_);
    file_ = -1;
    fail(path, "unsupported archive format \"" + format + "\" (expected " + kArchiveFormat + ")");
  }
}

Archive::~Archive() {
  if (file_ >= 0) H5Fclose(file_);
}

RunInfo Archive::info() const {
  RunInfo r;
  r.format = read_attr_string(file_, "format", path_);
  r.version = read_attr_string(file_, "version", path_);
  r.git_commit = read_attr_string(file_, "git_commit", path_);
  r.physics_revision = H5Aexists(file_, "physics_revision") > 0
                           ? read_attr<std::int32_t>(file_, "physics_revision", path_)
                           : 1;
  r.seed = read_attr<std::int64_t>(file_, "seed", path_);
  r.ranks = read_attr<std::int32_t>(file_, "ranks", path_);
  r.host = read_attr_string(file_, "host", path_);
  r.start_time = read_attr_string(file_, "start_time", path_);
  r.end_time = read_attr_string(file_, "end_time", path_);
  r.config_hash = read_attr_string(file_, "config_hash", path_);
  r.experiment = read_attr_string(file_, "experiment", path_);
  r.state = read_attr_string(file_, "state", path_);
  r.generations_done = read_attr<std::int64_t>(file_, "generations_done", path_);
  return r;
}

std::string Archive::config_text() const {
  return read_string_dataset(file_, "config", path_);
}

std::vector<std::int64_t> Archive::generations() const {
  std::vector<std::int64_t> out;
  Handle g(
      check_id(H5Gopen2(file_, "generations", H5P_DEFAULT), path_, "missing group /generations"),
      H5Gclose);
  H5G_info_t ginfo;
  check_status(H5Gget_info(g, &ginfo), path_, "cannot list /generations");
  for (hsize_t i = 0; i < ginfo.nlinks; ++i) {
    char name[64] = {0};
    H5Lget_name_by_idx(g, ".", H5_INDEX_NAME, H5_ITER_INC, i, name, sizeof name, H5P_DEFAULT);
    char* end = nullptr;
    const long long v = std::strtoll(name, &end, 10);
    if (end == name || *end != '\0' || std::strlen(name) != 6)
      fail(path_, std::string("unexpected object /generations/") + name);
    out.push_back(v);
  }
  std::sort(out.begin(), out.end());
  return out;
}

GenerationRecord Archive::generation(std::int64_t gen) const {
  const std::string gname = "generations/" + generation_group_name(gen);
  if (H5Lexists(file_, "generations", H5P_DEFAULT) <= 0 ||
      H5Lexists(file_, gname.c_str(), H5P_DEFAULT) <= 0)
    fail(path_, "no generation " + std::to_string(gen) + " (/" + gname + ")");
  Handle g(check_id(H5Gopen2(file_, gname.c_str(), H5P_DEFAULT), path_, "cannot open /" + gname),
           H5Gclose);
  const std::string where = path_ + ": /" + gname;
  GenerationRecord r;
  r.generation = gen;
  r.id = read_dataset<std::int64_t>(g, "id", where);
  r.parent1 = read_dataset<std::int64_t>(g, "parent1", where);
  r.parent2 = read_dataset<std::int64_t>(g, "parent2", where);
  r.species = read_dataset<std::int64_t>(g, "species", where);
  r.status = read_dataset<std::uint8_t>(g, "status", where);
  r.fitness = read_dataset<double>(g, "fitness", where);
  r.voxels = read_dataset<std::int32_t>(g, "voxels", where);
  r.chambers = read_dataset<std::int32_t>(g, "chambers", where);
  r.wall_seconds = read_dataset<double>(g, "wall_seconds", where);
  r.worker_rank = read_dataset<std::int32_t>(g, "worker_rank", where);
  r.genome = read_genomes(g, where);
  std::vector<hsize_t> dims;
  r.components = read_dataset<double>(g, "components", where, &dims);
  if (dims.size() != 3 || dims[2] != kComponentCount)
    fail(where, "components is not [n, n_directions, 6]");
  r.n_directions = static_cast<int>(dims[1]);
  r.best = read_attr<double>(g, "best", where);
  r.mean = read_attr<double>(g, "mean", where);
  r.sd = read_attr<double>(g, "sd", where);
  r.species_count = read_attr<std::int64_t>(g, "species_count", where);
  r.evaluations = read_attr<std::int64_t>(g, "evaluations", where);
  r.eval_wall_seconds = read_attr<double>(g, "eval_wall_seconds", where);
  try {
    r.check();
  } catch (const ArchiveError& e) {
    fail(path_, e.what());
  }
  return r;
}

std::vector<StatsRow> Archive::stats() const {
  std::vector<hsize_t> dims;
  const std::vector<double> v = read_dataset<double>(file_, "stats", path_, &dims);
  if (dims.size() != 2 || dims[1] != kStatsColumns) fail(path_, "stats is not [G, 6]");
  std::vector<StatsRow> rows(static_cast<std::size_t>(dims[0]));
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const double* r = &v[i * kStatsColumns];
    rows[i] = StatsRow{r[0], r[1], r[2], r[3], r[4], r[5]};
  }
  return rows;
}

std::optional<Checkpoint> Archive::checkpoint() const {
  if (H5Lexists(file_, "checkpoint", H5P_DEFAULT) <= 0) return std::nullopt;
  Handle g(check_id(H5Gopen2(file_, "checkpoint", H5P_DEFAULT), path_, "cannot open /checkpoint"),
           H5Gclose);
  Checkpoint c;
  c.generation = read_attr<std::int64_t>(g, "generation", path_ + ": /checkpoint");
  c.population = read_dataset<std::uint8_t>(g, "population", path_ + ": /checkpoint");
  return c;
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
    const GenerationRecord r = archive.generation(gen);
    h.i64(gen);
    h.u64(r.size());
    h.i64(r.n_directions);
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

}  // namespace softevo::master
