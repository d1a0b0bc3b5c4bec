#include "io/h5.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>

#include "common/input_file.hpp"
#include "io/h5_heap.hpp"

namespace softevo::io::h5 {
namespace {

// H5E_walk2_t: keeps the first (with an upward walk: the most specific) entry of the stack.
herr_t keep_innermost(unsigned n, const H5E_error2_t* entry, void* data) {
  if (n != 0) return 0;
  auto* out = static_cast<std::string*>(data);
  *out = entry->desc != nullptr ? entry->desc : "";
  char minor[160] = {0};
  if (H5Eget_msg(entry->min_num, nullptr, minor, sizeof minor) > 0 &&
      out->find(minor) == std::string::npos) {
    *out += out->empty() ? minor : std::string(" (") + minor + ")";
  }
  return 0;
}

Id string_type(Charset charset, std::size_t size) {
  Id type(H5Tcopy(H5T_C_S1), H5Tclose);
  H5Tset_size(type.get(), size);
  H5Tset_cset(type.get(), charset == Charset::utf8 ? H5T_CSET_UTF8 : H5T_CSET_ASCII);
  return type;
}

Id variable_string_type(Charset charset) {
  return string_type(charset, H5T_VARIABLE);
}

// Reads one string of file type `file_type` through `read(memory_type, buffer)`.
template <typename Read>
std::string read_one_string(const Where& where, const std::string& what, hid_t file_type,
                            hsize_t points, std::size_t max_bytes, Read&& read) {
  if (H5Tget_class(file_type) != H5T_STRING) where.fail("read " + what, "is not a string");
  if (points != 1) where.fail("read " + what, "is not a single string");
  // HDF5 refuses to convert between character sets, so read in the file's own.
  const Charset charset = H5Tget_cset(file_type) == H5T_CSET_UTF8 ? Charset::utf8 : Charset::ascii;
  if (H5Tis_variable_str(file_type) > 0) {
    const Id type = variable_string_type(charset);
    char* buffer = nullptr;
    where.check_status(read(type.get(), &buffer), "read " + what);
    std::string value = buffer != nullptr ? buffer : "";
    H5free_memory(buffer);
    if (value.size() > max_bytes) where.fail("read " + what, too_long(value.size(), max_bytes));
    return value;
  }
  const std::size_t size = H5Tget_size(file_type);
  if (size > max_bytes) where.fail("read " + what, too_long(size, max_bytes));
  const Id type = string_type(charset, size);
  std::string value(size, '\0');
  where.check_status(read(type.get(), value.data()), "read " + what);
  const std::size_t end = value.find('\0');
  if (end != std::string::npos) value.resize(end);
  return value;
}

hsize_t points_of(hid_t space) {
  const hssize_t n = H5Sget_simple_extent_npoints(space);
  return n < 0 ? 0 : static_cast<hsize_t>(n);
}

void check_numeric_class(const Where& where, const std::string& what, H5T_class_t cls,
                         bool integer) {
  if (integer && cls != H5T_INTEGER) where.fail("read " + what, "is not an integer");
  if (cls != H5T_INTEGER && cls != H5T_FLOAT) where.fail("read " + what, "is not a number");
}

}  // namespace

// ---- errors ------------------------------------------------------------------------------------

Error::Error(std::string file, std::string object, std::string action, std::string reason)
    : std::runtime_error(file + ": " + object + ": " + action + ": " + reason),
      file_(std::move(file)),
      object_(std::move(object)),
      action_(std::move(action)),
      reason_(std::move(reason)) {}

namespace {

// libhdf5 (1.10) keeps the id of a file whose close failed (on a full disk the close flushes and
// fails again) after freeing most of its object; its clean-up at exit then closes that file a
// second time and crashes (issue 39: `softevo evolve` exited 139 after the right error, Python's
// interpreter crashed at exit). Every file this process opens is closed by its owner, so that
// clean-up has nothing to do: it is never registered. H5dont_atexit takes effect only before the
// library starts, hence a static initializer of this module, which runs before main and before
// a Python module's first call (unless h5py started the library in that process before).
const bool kNoCleanupAtExit = [] {
  H5dont_atexit();
  return true;
}();

}  // namespace

void silence_error_printing() {
  (void)kNoCleanupAtExit;
  static const bool silenced = [] {
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    return true;
  }();
  (void)silenced;
}

std::string take_error_message() {
  // H5Eget_current_stack copies the stack and clears it, so the next failure starts afresh.
  const hid_t stack = H5Eget_current_stack();
  if (stack < 0) return "";
  std::string message;
  H5Ewalk2(stack, H5E_WALK_UPWARD, keep_innermost, &message);
  H5Eclose_stack(stack);
  return message;
}

Where Where::child(const std::string& name) const {
  return Where{file, object == "/" ? "/" + name : object + "/" + name};
}

void Where::fail(const std::string& action, std::string reason) const {
  if (reason.empty()) reason = take_error_message();
  if (reason.empty()) reason = "HDF5 call failed";
  throw Error(file, object, action, reason);
}

hid_t Where::check(hid_t id, const std::string& action) const {
  if (id < 0) fail(action);
  return id;
}

void Where::check_status(herr_t status, const std::string& action) const {
  if (status < 0) fail(action);
}

// ---- dataspaces and property lists -------------------------------------------------------------

Dataspace Dataspace::scalar() {
  silence_error_printing();
  const Where where{"(memory)", "(dataspace)"};
  return Dataspace(Id(where.check(H5Screate(H5S_SCALAR), "create scalar dataspace"), H5Sclose),
                   where);
}

Dataspace Dataspace::simple(const std::vector<hsize_t>& dims,
                            const std::vector<hsize_t>& max_dims) {
  silence_error_printing();
  const Where where{"(memory)", "(dataspace)"};
  if (!max_dims.empty() && max_dims.size() != dims.size())
    where.fail("create dataspace", "dims and max_dims differ in rank");
  const hid_t id = H5Screate_simple(static_cast<int>(dims.size()), dims.data(),
                                    max_dims.empty() ? nullptr : max_dims.data());
  return Dataspace(Id(where.check(id, "create dataspace"), H5Sclose), where);
}

std::vector<hsize_t> Dataspace::dims() const {
  const int rank = H5Sget_simple_extent_ndims(id());
  if (rank < 0) where_.fail("get the shape");
  std::vector<hsize_t> dims(static_cast<std::size_t>(rank));
  if (rank > 0 && H5Sget_simple_extent_dims(id(), dims.data(), nullptr) < 0)
    where_.fail("get the shape");
  return dims;
}

hsize_t Dataspace::points() const {
  return points_of(id());
}

void Dataspace::select_block(const std::vector<hsize_t>& start, const std::vector<hsize_t>& count) {
  where_.check_status(
      H5Sselect_hyperslab(id(), H5S_SELECT_SET, start.data(), nullptr, count.data(), nullptr),
      "select a block");
}

PropertyList PropertyList::file_creation() {
  silence_error_printing();
  return PropertyList(Id(Where{"(memory)", "(property list)"}.check(
                             H5Pcreate(H5P_FILE_CREATE), "create file creation properties"),
                         H5Pclose));
}

PropertyList PropertyList::dataset_creation() {
  silence_error_printing();
  return PropertyList(Id(Where{"(memory)", "(property list)"}.check(
                             H5Pcreate(H5P_DATASET_CREATE), "create dataset creation properties"),
                         H5Pclose));
}

PropertyList& PropertyList::persist_free_space() {
  Where{"(memory)", "(property list)"}.check_status(
      H5Pset_file_space_strategy(id(), H5F_FSPACE_STRATEGY_FSM_AGGR, 1, 1),
      "set the file space strategy");
  return *this;
}

PropertyList& PropertyList::chunk(const std::vector<hsize_t>& chunk_dims) {
  Where{"(memory)", "(property list)"}.check_status(
      H5Pset_chunk(id(), static_cast<int>(chunk_dims.size()), chunk_dims.data()), "set chunking");
  return *this;
}

// ---- attributes --------------------------------------------------------------------------------

bool Object::has_attribute(const std::string& name) const {
  const htri_t exists = H5Aexists(id(), name.c_str());
  if (exists < 0) where_.fail("look up attribute '" + name + "'");
  return exists > 0;
}

void Object::write_attribute_raw(const std::string& name, hid_t file_type, hid_t memory_type,
                                 const void* value) const {
  const std::string what = "attribute '" + name + "'";
  if (has_attribute(name)) where_.check_status(H5Adelete(id(), name.c_str()), "replace " + what);
  const Dataspace space = Dataspace::scalar();
  const Id attr(
      where_.check(H5Acreate2(id(), name.c_str(), file_type, space.id(), H5P_DEFAULT, H5P_DEFAULT),
                   "create " + what),
      H5Aclose);
  where_.check_status(H5Awrite(attr.get(), memory_type, value), "write " + what);
}

void Object::write_string_attribute(const std::string& name, const std::string& value,
                                    Charset charset) const {
  const Id type = variable_string_type(charset);
  const char* text = value.c_str();
  write_attribute_raw(name, type.get(), type.get(), &text);
}

void Object::read_attribute_raw(const std::string& name, hid_t memory_type, bool integer,
                                void* value) const {
  const std::string what = "attribute '" + name + "'";
  if (!has_attribute(name)) where_.fail("read " + what, "missing");
  const Id attr(where_.check(H5Aopen(id(), name.c_str(), H5P_DEFAULT), "open " + what), H5Aclose);
  const Id type(where_.check(H5Aget_type(attr.get()), "read " + what), H5Tclose);
  check_numeric_class(where_, what, H5Tget_class(type.get()), integer);
  const Id space(where_.check(H5Aget_space(attr.get()), "read " + what), H5Sclose);
  if (points_of(space.get()) != 1) where_.fail("read " + what, "is not a single number");
  where_.check_status(H5Aread(attr.get(), memory_type, value), "read " + what);
}

std::string Object::read_string_attribute(const std::string& name, std::size_t max_bytes) const {
  const std::string what = "attribute '" + name + "'";
  if (!has_attribute(name)) where_.fail("read " + what, "missing");
  const Id attr(where_.check(H5Aopen(id(), name.c_str(), H5P_DEFAULT), "open " + what), H5Aclose);
  const Id type(where_.check(H5Aget_type(attr.get()), "read " + what), H5Tclose);
  const Id space(where_.check(H5Aget_space(attr.get()), "read " + what), H5Sclose);
  if (H5Tget_class(type.get()) == H5T_STRING && H5Tis_variable_str(type.get()) > 0 &&
      points_of(space.get()) == 1)
    check_heaps_before_library_read(id(), where_, "read " + what);
  return read_one_string(where_, what, type.get(), points_of(space.get()), max_bytes,
                         [&attr](hid_t memory_type, void* buffer) {
                           return H5Aread(attr.get(), memory_type, buffer);
                         });
}

// ---- datasets ----------------------------------------------------------------------------------

Dataspace Dataset::space() const {
  return Dataspace(Id(where_.check(H5Dget_space(id()), "get the dataspace"), H5Sclose), where_);
}

H5T_class_t Dataset::type_class() const {
  const Id type(where_.check(H5Dget_type(id()), "get the datatype"), H5Tclose);
  return H5Tget_class(type.get());
}

hsize_t Dataset::checked_points(hsize_t max_points) const {
  const std::vector<hsize_t> extent = dims();
  hsize_t points = 1;
  for (const hsize_t d : extent) {
    if (d != 0 && points > kUnbounded / d) where_.fail("read dataset", "its extent overflows");
    points *= d;
  }
  if (points > max_points)
    where_.fail("read dataset", "has " + std::to_string(points) +
                                    " values, more than the limit of " +
                                    std::to_string(max_points));
  if (points == 0) return 0;
  const Id type(where_.check(H5Dget_type(id()), "get the datatype"), H5Tclose);
  const std::size_t value_bytes = std::max<std::size_t>(1, H5Tget_size(type.get()));
  const Id file(where_.check(H5Iget_file_id(id()), "find the file"), H5Fclose);
  hsize_t file_bytes = 0;
  where_.check_status(H5Fget_filesize(file.get(), &file_bytes), "get the file size");
  if (points > file_bytes / value_bytes)
    where_.fail("read dataset", "has " + std::to_string(points) + " values of " +
                                    std::to_string(value_bytes) + " bytes, more than its file (" +
                                    std::to_string(file_bytes) + " bytes) can hold");
  return points;
}

void Dataset::read_raw(hid_t memory_type, bool integer, void* out, std::size_t count) const {
  check_numeric_class(where_, "dataset", type_class(), integer);
  if (count == 0) return;
  where_.check_status(H5Dread(id(), memory_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, out),
                      "read dataset");
}

void Dataset::write_raw(hid_t memory_type, const void* values, std::size_t count) const {
  const hsize_t points = space().points();
  if (count != points)
    where_.fail("write dataset",
                std::to_string(count) + " values for " + std::to_string(points) + " points");
  if (count == 0) return;
  where_.check_status(H5Dwrite(id(), memory_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, values),
                      "write dataset");
}

void Dataset::set_extent(const std::vector<hsize_t>& dims) const {
  where_.check_status(H5Dset_extent(id(), dims.data()), "change the extent");
}

void Dataset::write_block_raw(const std::vector<hsize_t>& start, const std::vector<hsize_t>& count,
                              hid_t memory_type, const void* values,
                              std::size_t value_count) const {
  Dataspace file_space = space();
  if (start.size() != file_space.dims().size() || count.size() != start.size())
    where_.fail("write a block", "block rank differs from the dataset's");
  file_space.select_block(start, count);
  const Dataspace memory_space = Dataspace::simple(count);
  if (memory_space.points() != value_count)
    where_.fail("write a block", std::to_string(value_count) + " values for a block of " +
                                     std::to_string(memory_space.points()));
  where_.check_status(
      H5Dwrite(id(), memory_type, memory_space.id(), file_space.id(), H5P_DEFAULT, values),
      "write a block");
}

std::string Dataset::read_string(std::size_t max_bytes) const {
  const Id type(where_.check(H5Dget_type(id()), "get the datatype"), H5Tclose);
  const hsize_t points = space().points();
  if (H5Tget_class(type.get()) == H5T_STRING && H5Tis_variable_str(type.get()) > 0 && points == 1) {
    const std::vector<std::vector<std::uint8_t>> rows = read_vlen_rows(id(), where_, 1, max_bytes);
    return std::string(rows[0].begin(), rows[0].end());
  }
  return read_one_string(where_, "dataset", type.get(), points, max_bytes,
                         [this](hid_t memory_type, void* buffer) {
                           return H5Dread(id(), memory_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, buffer);
                         });
}

std::vector<std::vector<std::uint8_t>> Dataset::read_byte_rows(hsize_t max_rows,
                                                               hsize_t max_row_bytes) const {
  const Id type(where_.check(H5Dget_type(id()), "get the datatype"), H5Tclose);
  if (H5Tget_class(type.get()) != H5T_VLEN)
    where_.fail("read dataset", "is not a variable-length byte column");
  const Id base(where_.check(H5Tget_super(type.get()), "get the datatype"), H5Tclose);
  if (H5Tget_class(base.get()) != H5T_INTEGER || H5Tget_size(base.get()) != 1)
    where_.fail("read dataset", "is not a variable-length byte column");
  const std::vector<hsize_t> extent = dims();
  if (extent.size() != 1) where_.fail("read dataset", "is not 1-D");
  if (extent[0] > max_rows)
    where_.fail("read dataset", "has " + std::to_string(extent[0]) +
                                    " rows, more than the limit of " + std::to_string(max_rows));
  return read_vlen_rows(id(), where_, extent[0], max_row_bytes);
}

// ---- groups ------------------------------------------------------------------------------------

bool Group::has_link(const std::string& path) const {
  std::string prefix;
  std::size_t start = 0;
  while (start <= path.size()) {
    const std::size_t slash = path.find('/', start);
    const std::string part =
        path.substr(start, slash == std::string::npos ? std::string::npos : slash - start);
    if (!part.empty()) {
      prefix += (prefix.empty() ? "" : "/") + part;
      const htri_t exists = H5Lexists(id(), prefix.c_str(), H5P_DEFAULT);
      if (exists < 0) where_.child(prefix).fail("look up the link");
      if (exists == 0) return false;
    }
    if (slash == std::string::npos) break;
    start = slash + 1;
  }
  return true;
}

void Group::delete_link(const std::string& name) const {
  where_.child(name).check_status(H5Ldelete(id(), name.c_str(), H5P_DEFAULT), "delete");
}

std::vector<std::string> Group::link_names(hsize_t max_links) const {
  H5G_info_t info;
  where_.check_status(H5Gget_info(id(), &info), "list the group");
  if (info.nlinks > max_links)
    where_.fail("list the group", "has " + std::to_string(info.nlinks) +
                                      " links, more than the limit of " +
                                      std::to_string(max_links));
  // Names of links are short; a longer one is damage, not a name.
  constexpr ssize_t kMaxNameBytes = 4096;
  std::vector<std::string> names;
  for (hsize_t i = 0; i < info.nlinks; ++i) {
    const ssize_t size =
        H5Lget_name_by_idx(id(), ".", H5_INDEX_NAME, H5_ITER_INC, i, nullptr, 0, H5P_DEFAULT);
    if (size < 0) where_.fail("list the group");
    if (size > kMaxNameBytes)
      where_.fail("list the group", "link " + std::to_string(i) + " has a name of " +
                                        std::to_string(size) + " bytes");
    std::string name(static_cast<std::size_t>(size) + 1, '\0');
    if (H5Lget_name_by_idx(id(), ".", H5_INDEX_NAME, H5_ITER_INC, i, name.data(), name.size(),
                           H5P_DEFAULT) < 0)
      where_.fail("list the group");
    name.resize(static_cast<std::size_t>(size));
    names.push_back(std::move(name));
  }
  return names;
}

std::optional<Group::ExternalTarget> Group::external_link(const std::string& name) const {
  const Where w = where_.child(name);
  H5L_info_t info{};
  w.check_status(H5Lget_info(id(), name.c_str(), &info, H5P_DEFAULT), "look up the link");
  if (info.type != H5L_TYPE_EXTERNAL) return std::nullopt;
  // Two path names: a link of more than this comes from a damaged or hostile file.
  constexpr std::size_t kMaxExternalLinkBytes = 1 << 16;
  if (info.u.val_size > kMaxExternalLinkBytes)
    w.fail("read the external link", "its value has " + std::to_string(info.u.val_size) +
                                         " bytes (at most " +
                                         std::to_string(kMaxExternalLinkBytes) + " expected)");
  std::vector<char> value(info.u.val_size);
  w.check_status(H5Lget_val(id(), name.c_str(), value.data(), value.size(), H5P_DEFAULT),
                 "read the external link");
  unsigned flags = 0;
  const char* file = nullptr;
  const char* object = nullptr;
  w.check_status(H5Lunpack_elink_val(value.data(), value.size(), &flags, &file, &object),
                 "decode the external link");
  return ExternalTarget{file, object};
}

void Group::create_external_link(const std::string& name, const ExternalTarget& target) const {
  where_.child(name).check_status(
      H5Lcreate_external(target.file.c_str(), target.object.c_str(), id(), name.c_str(),
                         H5P_DEFAULT, H5P_DEFAULT),
      "create an external link to " + target.file + ":" + target.object);
}

void Group::copy_object(const std::string& name, const Group& destination,
                        const std::string& destination_name) const {
  where_.child(name).check_status(H5Ocopy(id(), name.c_str(), destination.id(),
                                          destination_name.c_str(), H5P_DEFAULT, H5P_DEFAULT),
                                  "copy to " + destination.where().file + ":" +
                                      destination.where().child(destination_name).object);
}

Group Group::create_group(const std::string& name) const {
  const Where w = where_.child(name);
  return Group(Id(w.check(H5Gcreate2(id(), name.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
                          "create group"),
                  H5Gclose),
               w);
}

Group Group::open_group(const std::string& name) const {
  const Where w = where_.child(name);
  if (!has_link(name)) w.fail("open group", "no such group");
  return Group(Id(w.check(H5Gopen2(id(), name.c_str(), H5P_DEFAULT), "open group"), H5Gclose), w);
}

Dataset Group::create_dataset_raw(const std::string& name, hid_t file_type, const Dataspace& space,
                                  const PropertyList* creation) const {
  const Where w = where_.child(name);
  const hid_t dcpl = creation != nullptr ? creation->id() : H5P_DEFAULT;
  return Dataset(Id(w.check(H5Dcreate2(id(), name.c_str(), file_type, space.id(), H5P_DEFAULT, dcpl,
                                       H5P_DEFAULT),
                            "create dataset"),
                    H5Dclose),
                 w);
}

Dataset Group::write_string_dataset(const std::string& name, const std::string& text,
                                    Charset charset) const {
  const Id type = variable_string_type(charset);
  Dataset ds = create_dataset_raw(name, type.get(), Dataspace::scalar(), nullptr);
  const char* p = text.c_str();
  ds.where().check_status(H5Dwrite(ds.id(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, &p),
                          "write dataset");
  return ds;
}

Dataset Group::write_byte_rows(const std::string& name,
                               const std::vector<std::vector<std::uint8_t>>& rows) const {
  const Where w = where_.child(name);
  const Id memory_type(w.check(H5Tvlen_create(H5T_NATIVE_UINT8), "create a vlen type"), H5Tclose);
  const Id file_type(w.check(H5Tvlen_create(H5T_STD_U8LE), "create a vlen type"), H5Tclose);
  Dataset ds = create_dataset_raw(name, file_type.get(),
                                  Dataspace::simple({static_cast<hsize_t>(rows.size())}), nullptr);
  std::vector<hvl_t> raw(rows.size());
  for (std::size_t i = 0; i < rows.size(); ++i) {
    raw[i].len = rows[i].size();
    raw[i].p = const_cast<std::uint8_t*>(rows[i].data());  // HDF5 only reads it
  }
  if (!raw.empty())
    w.check_status(H5Dwrite(ds.id(), memory_type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, raw.data()),
                   "write dataset");
  return ds;
}

Dataset Group::open_dataset(const std::string& name) const {
  const Where w = where_.child(name);
  if (!has_link(name)) w.fail("open dataset", "no such dataset");
  return Dataset(Id(w.check(H5Dopen2(id(), name.c_str(), H5P_DEFAULT), "open dataset"), H5Dclose),
                 w);
}

// ---- files -------------------------------------------------------------------------------------

namespace {

// File access properties that make new objects use the HDF5 1.8+ formats, whose metadata
// (object headers, link and attribute storage, chunk indexes) carries checksums that libhdf5
// verifies on every read. The default (oldest) formats have none, and libhdf5 1.10 decodes a
// damaged old-style object header or symbol table without bounds checks (a flipped byte in the
// root group's header crashed `softevo info`); with checksums such damage is refused. Data and
// global heap collections have no checksum either way: the readers check them.
//
// Off for now: with these formats, libhdf5 1.10.8 (Debian 12) crashed (SIGSEGV in H5Ocopy,
// iterating a group's dense link storage) when the disk filled up while an archive was being
// packed (SoftevoMpi.FullDiskLosesAtMostTheGenerationInFlight). Losing a run on a full disk is
// worse than decoding old-style headers, whose damage the readers' bounds still catch in most
// cases (docs/archive.md, Limits).
constexpr bool kChecksummedFormats = false;

Id checksummed_format_access(const Where& where) {
  Id access(where.check(H5Pcreate(H5P_FILE_ACCESS), "create file access properties"), H5Pclose);
  where.check_status(H5Pset_libver_bounds(access.get(), H5F_LIBVER_V18, H5F_LIBVER_V110),
                     "set the file format versions");
  return access;
}

}  // namespace

File File::create(const std::string& path, const PropertyList* creation, const std::string& label) {
  silence_error_printing();
  const Where w{label.empty() ? path : label, "/"};
  const hid_t fcpl = creation != nullptr ? creation->id() : H5P_DEFAULT;
  const Id access = kChecksummedFormats ? checksummed_format_access(w) : Id(H5P_DEFAULT, nullptr);
  return File(Id(w.check(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, fcpl, access.get()), "create file"),
                 H5Fclose),
              w);
}

File File::create_in_memory(const std::string& label) {
  silence_error_printing();
  const Where w{label, "/"};
  const Id access =
      kChecksummedFormats
          ? checksummed_format_access(w)
          : Id(w.check(H5Pcreate(H5P_FILE_ACCESS), "create file access properties"), H5Pclose);
  // Grown in steps of 64 kB; nothing is written to any file.
  w.check_status(H5Pset_fapl_core(access.get(), std::size_t{64} << 10, false),
                 "select the in-memory driver");
  // The name only tells open files apart: never a file on disk.
  const std::string name = label + " (in memory)";
  return File(
      Id(w.check(H5Fcreate(name.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, access.get()), "create file"),
         H5Fclose),
      w);
}

File File::open(const std::string& path, Access access, const std::string& label) {
  silence_error_printing();
  const Where w{label.empty() ? path : label, "/"};
  // Checked by name before libhdf5 opens it: a FIFO would block the open forever (issue 39).
  const std::string irregular = not_a_regular_file(path);
  if (irregular == "does not exist") w.fail("open file", "no such file");
  if (!irregular.empty()) w.fail("open file", irregular + ", not an HDF5 file");
  if (H5Fis_hdf5(path.c_str()) <= 0) {
    take_error_message();
    w.fail("open file", "not an HDF5 file (or unreadable)");
  }
  probe_before_open(path, w);  // a file that crashes libhdf5 must not crash this process
  const unsigned flags = access == Access::read_write ? H5F_ACC_RDWR : H5F_ACC_RDONLY;
  // Objects added to a file opened for writing take the access properties' format.
  const Id properties = access == Access::read_write && kChecksummedFormats
                            ? checksummed_format_access(w)
                            : Id(H5P_DEFAULT, nullptr);
  return File(Id(w.check(H5Fopen(path.c_str(), flags, properties.get()), "open file"), H5Fclose),
              w);
}

bool File::is_hdf5(const std::string& path) {
  silence_error_printing();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return false;
  const htri_t is = H5Fis_hdf5(path.c_str());
  if (is < 0) take_error_message();
  return is > 0;
}

void File::flush() const {
  where_.check_status(H5Fflush(id(), H5F_SCOPE_GLOBAL), "flush file");
}

std::vector<std::uint8_t> File::image() const {
  const ssize_t size = H5Fget_file_image(id(), nullptr, 0);
  where_.check(size, "get the file image size");
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(size));
  where_.check(H5Fget_file_image(id(), bytes.data(), bytes.size()), "get the file image");
  return bytes;
}

void File::close() {
  if (!id_.valid()) return;
  where_.check_status(H5Fclose(id_.release()), "close file");
}

}  // namespace softevo::io::h5
